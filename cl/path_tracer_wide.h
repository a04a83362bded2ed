/* The path tracer PT_LANES samples at a time: cl/path_tracer.h's walk with every lane a sample
 * of its own (cl/lanes.h), so the shading, light sampling, MIS and sample draws run as SIMD
 * code; only the ray queries (intersect, occluded) and the table lookups (a hit's triangle and
 * material, a light's triangle) run lane by lane.
 *
 * Lane k of work item g is launch item g * PT_LANES + k, with its pixel, sample and draws as
 * there, and the same operations per lane as the one-sample walk; its output is that item's
 * camera_out entry. Lanes whose paths ended sit idle (masked) until every lane's has.
 *
 * Built for the scenes whose features it has (host/render/features.cpp, pt_lanes_supported):
 * area lights, the four materials, shading normals, the Sobol sampler; the one-sample walk
 * serves the rest. */
#ifndef CLBDPT_PATH_TRACER_WIDE_H
#define CLBDPT_PATH_TRACER_WIDE_H

#include "lanes.h"
#include "walk.h"

/* ---- cl/bsdf.h per lane ----------------------------------------------------------------- */

typedef struct {
    Framew frame;
    float3w ng;
    float3w kd, ks;
    floatw ior, alpha;
    intw kind;
} Bsdfw;

inline intw bsdf_is_specular_w(const Bsdfw* b) { return b->kind == MATERIAL_MIRROR || b->kind == MATERIAL_GLASS; }

#ifdef HAS_GLOSSY
inline floatw ggx_d_w(float3w wh, floatw alpha) {
    floatw cos2 = wh.z * wh.z;
    floatw a2 = alpha * alpha;
    floatw tan2 = (1.0f - cos2) / cos2;
    floatw e = 1.0f + tan2 / a2;
    return select(1.0f / (PI_F * a2 * cos2 * cos2 * e * e), (floatw)(0.0f), cos2 == 0.0f);
}

inline floatw ggx_lambda_w(float3w w, floatw alpha) {
    floatw cos2 = w.z * w.z;
    floatw tan2 = fmax(0.0f, 1.0f - cos2) / cos2;
    return select(0.5f * (-1.0f + sqrt(1.0f + alpha * alpha * tan2)), (floatw)(0.0f), cos2 == 0.0f);
}

inline float3w ggx_sample_wh_w(floatw ux, floatw uy, floatw alpha) {
    floatw tan2 = alpha * alpha * ux / (1.0f - ux);
    floatw cos_theta = 1.0f / sqrt(1.0f + tan2);
    floatw sin_theta = sqrt(fmax(0.0f, 1.0f - cos_theta * cos_theta));
    floatw c, s;
    unit_circle_turns_w(uy, &c, &s);
    return f3w(sin_theta * c, sin_theta * s, cos_theta);
}

inline float3w glossy_f_local_w(const Bsdfw* b, float3w wo, float3w wi) {
    floatw cos_o = fabs(wo.z), cos_i = fabs(wi.z);
    float3w wh = add3w(wi, wo);
    intw zero = cos_o == 0.0f || cos_i == 0.0f || is_black3w(wh);
    wh = normalize3w(wh);
    floatw g = 1.0f / (1.0f + ggx_lambda_w(wo, b->alpha) + ggx_lambda_w(wi, b->alpha));
    floatw k = select(ggx_d_w(wh, b->alpha) * g / (4.0f * cos_o * cos_i), (floatw)(0.0f), zero);
    return scale3w(b->ks, k);
}

inline floatw glossy_pdf_local_w(const Bsdfw* b, float3w wo, float3w wi) {
    float3w wh = add3w(wi, wo);
    intw zero = wo.z * wi.z <= 0.0f || is_black3w(wh);
    wh = normalize3w(wh);
    return select(ggx_d_w(wh, b->alpha) * fabs(wh.z) / (4.0f * fabs(dot3w(wo, wh))), (floatw)(0.0f), zero);
}

inline floatw luminance_w(float3w c) { return 0.2126f * c.x + 0.7152f * c.y + 0.0722f * c.z; }

inline floatw glossy_diffuse_probability_w(const Bsdfw* b) {
    floatw d = luminance_w(b->kd), s = luminance_w(b->ks);
    return select((floatw)(1.0f), d / (d + s), d + s > 0.0f);
}
#endif

inline float3w bsdf_f_w(const Bsdfw* b, float3w wo_world, float3w wi_world) {
    float3w wo = to_local_w(&b->frame, wo_world), wi = to_local_w(&b->frame, wi_world);
    intw zero = bsdf_is_specular_w(b) || wo.z * wi.z <= 0.0f ||
                dot3w(wi_world, b->ng) * dot3w(wo_world, b->ng) <= 0.0f;
    float3w f = scale3w(b->kd, (floatw)(INV_PI_F));
#ifdef HAS_GLOSSY
    f = select3w(f, add3w(f, glossy_f_local_w(b, wo, wi)), b->kind == MATERIAL_GLOSSY);
#endif
    return select3w(f, splat3w((float3)(0.0f)), zero);
}

inline floatw bsdf_pdf_w(const Bsdfw* b, float3w wo_world, float3w wi_world) {
    float3w wo = to_local_w(&b->frame, wo_world), wi = to_local_w(&b->frame, wi_world);
    intw zero = bsdf_is_specular_w(b) || wo.z == 0.0f || wo.z * wi.z <= 0.0f;
    floatw pdf = fabs(wi.z) * INV_PI_F;
#ifdef HAS_GLOSSY
    floatw pd = glossy_diffuse_probability_w(b);
    pdf = select(pdf, pd * pdf + (1.0f - pd) * glossy_pdf_local_w(b, wo, wi), b->kind == MATERIAL_GLOSSY);
#endif
    return select(pdf, (floatw)(0.0f), zero);
}

#ifdef HAS_GLASS
inline floatw fresnel_dielectric_w(floatw cos_i, floatw eta_inside) {
    cos_i = clamp(cos_i, -1.0f, 1.0f);
    intw inside = cos_i < 0.0f;
    floatw eta_i = select((floatw)(1.0f), eta_inside, inside), eta_t = select(eta_inside, (floatw)(1.0f), inside);
    cos_i = fabs(cos_i);
    floatw sin_i = sqrt(fmax(0.0f, 1.0f - cos_i * cos_i));
    floatw sin_t = eta_i / eta_t * sin_i;
    floatw cos_t = sqrt(fmax(0.0f, 1.0f - sin_t * sin_t));
    floatw r_parl = ((eta_t * cos_i) - (eta_i * cos_t)) / ((eta_t * cos_i) + (eta_i * cos_t));
    floatw r_perp = ((eta_i * cos_i) - (eta_t * cos_t)) / ((eta_i * cos_i) + (eta_t * cos_t));
    return select(0.5f * (r_parl * r_parl + r_perp * r_perp), (floatw)(1.0f), sin_t >= 1.0f);
}
#endif

/* bsdf_sample in radiance mode per lane; returns the lanes that sampled a direction. */
inline intw bsdf_sample_w(const Bsdfw* b, float3w wo_world, floatw u_lobe, floatw ux, floatw uy, float3w* wi_world,
                          float3w* f, floatw* pdf, intw* specular) {
    float3w wo = to_local_w(&b->frame, wo_world);
    /* Diffuse, or diffuse + glossy. */
    float3w wi = sample_cosine_hemisphere_w(ux, uy);
    wi.z = select(wi.z, -wi.z, wo.z < 0.0f);
#ifdef HAS_GLOSSY
    float3w wh = ggx_sample_wh_w(ux, uy, b->alpha);
    wh = select3w(wh, neg3w(wh), wo.z < 0.0f);
    float3w wi_glossy = sub3w(scale3w(wh, 2.0f * dot3w(wo, wh)), wo);
    wi = select3w(wi, wi_glossy, b->kind == MATERIAL_GLOSSY && u_lobe >= glossy_diffuse_probability_w(b));
#endif
    intw ok = wo.z * wi.z > 0.0f;
    *wi_world = from_local_w(&b->frame, wi);
    *pdf = bsdf_pdf_w(b, wo_world, *wi_world);
    *f = bsdf_f_w(b, wo_world, *wi_world);
    ok = ok && *pdf > 0.0f;
    *specular = (intw)(0);
#if defined(HAS_MIRROR) || defined(HAS_GLASS)
    float3w reflected = f3w(-wo.x, -wo.y, wo.z);
#endif
#ifdef HAS_MIRROR
    intw mirror = b->kind == MATERIAL_MIRROR;
    *wi_world = select3w(*wi_world, from_local_w(&b->frame, reflected), mirror);
    *f = select3w(*f, scale3w(b->ks, 1.0f / fabs(reflected.z)), mirror);
    *pdf = select(*pdf, (floatw)(1.0f), mirror);
    ok = select(ok, (intw)(-1), mirror);
    *specular = mirror;
#endif
#ifdef HAS_GLASS
    intw glass = b->kind == MATERIAL_GLASS;
    floatw F = fresnel_dielectric_w(wo.z, b->ior);
    intw reflect = u_lobe < F;
    intw entering = wo.z > 0.0f;
    floatw eta_i = select(b->ior, (floatw)(1.0f), entering), eta_t = select((floatw)(1.0f), b->ior, entering);
    floatw eta = eta_i / eta_t;
    floatw nz = select((floatw)(-1.0f), (floatw)(1.0f), entering);
    floatw cos_i = nz * wo.z; /* dot((0, 0, nz), wo) */
    floatw sin2_i = fmax(0.0f, 1.0f - cos_i * cos_i);
    floatw sin2_t = eta * eta * sin2_i;
    floatw cos_t = sqrt(1.0f - sin2_t);
    float3w refracted = add3w(scale3w(wo, -eta), f3w((floatw)(0.0f), (floatw)(0.0f), (eta * cos_i - cos_t) * nz));
    float3w wi_glass = select3w(refracted, reflected, reflect);
    floatw ft = select((1.0f - F) * (eta * eta), F, reflect);
    *wi_world = select3w(*wi_world, from_local_w(&b->frame, wi_glass), glass);
    float3w f_glass = splat3w((float3)(1.0f));
    f_glass = scale3w(f_glass, ft / fabs(wi_glass.z));
    *f = select3w(*f, f_glass, glass);
    *pdf = select(*pdf, select(1.0f - F, F, reflect), glass);
    ok = select(ok, reflect || sin2_t < 1.0f, glass);
    *specular = *specular || glass;
#endif
    return ok && wo.z != 0.0f;
}

/* ---- The walk ---------------------------------------------------------------------------- */

/* A surface vertex per lane: what path_tracer_sample keeps of a PathVertex. */
typedef struct {
    float3w p, ng, ns, wo;
    floatw p_error;
    Bsdfw bsdf; /* frame from ns */
    intw light; /* the area light of the hit triangle, or -1 */
    float3w le; /* its emitted radiance (0 where light < 0) */
    floatw light_pdf_origin; /* select_pdf / area of that light */
    intw connectible;
} SurfaceLanes;

/* Gathers lane k's hit (its triangle, normals, material and light) into the arrays of `g`,
 * GATHER_FIELDS floats per lane. */
#define GATHER_FIELDS 33
inline void gather_hit(const SceneData* scene, const Hit* hit, int k, float g[GATHER_FIELDS][PT_LANES], int* light,
                       int* kind) {
    __global const Triangle* tri = &scene->triangles[hit->triangle];
    TriangleInfo info = scene->infos[hit->triangle];
    float4 p0 = tri->p0, p1 = tri->p1, p2 = tri->p2;
    g[0][k] = p0.x, g[1][k] = p0.y, g[2][k] = p0.z;
    g[3][k] = p1.x, g[4][k] = p1.y, g[5][k] = p1.z;
    g[6][k] = p2.x, g[7][k] = p2.y, g[8][k] = p2.z;
    g[9][k] = hit->b1, g[10][k] = hit->b2;
    __global const Material* m = &scene->materials[info.material];
    float4 kd = m->kd, ks = m->ks;
    g[11][k] = kd.x, g[12][k] = kd.y, g[13][k] = kd.z;
    g[14][k] = ks.x, g[15][k] = ks.y, g[16][k] = ks.z;
    g[17][k] = m->ior, g[18][k] = m->alpha;
    *kind = m->kind;
    *light = info.light;
    float4 le = (float4)(0.0f);
    float light_pdf = 0.0f;
    if (info.light >= 0) {
        __global const Light* l = &scene->lights[info.light];
        le = l->emission;
        light_pdf = (1.0f / l->area) * l->select_pdf;
    }
    g[19][k] = le.x, g[20][k] = le.y, g[21][k] = le.z, g[22][k] = light_pdf;
#ifdef HAS_SHADING_NORMALS
    /* No per-vertex normals: 0, and the lane keeps ng. */
    float4 n0 = (float4)(0.0f), n1 = n0, n2 = n0;
    if (info.normals >= 0) {
        __global const TriangleNormals* tn = &scene->normals[info.normals];
        n0 = tn->n0;
        n1 = tn->n1;
        n2 = tn->n2;
    }
    g[23][k] = n0.x, g[24][k] = n0.y, g[25][k] = n0.z;
    g[26][k] = n1.x, g[27][k] = n1.y, g[28][k] = n1.z;
    g[29][k] = n2.x, g[30][k] = n2.y, g[31][k] = n2.z;
#endif
}

inline float3w load3w(float g[GATHER_FIELDS][PT_LANES], int first) {
    return f3w(VLOADW(0, g[first]), VLOADW(0, g[first + 1]), VLOADW(0, g[first + 2]));
}

/* surface_vertex_from_hit per lane, from the gathered fields; prev_p: the previous vertex. */
inline void surface_lanes_from_gather(float g[GATHER_FIELDS][PT_LANES], const int* light, const int* kind,
                                      float3w prev_p, SurfaceLanes* v) {
    float3w p0 = load3w(g, 0), e1 = sub3w(load3w(g, 3), p0), e2 = sub3w(load3w(g, 6), p0);
    floatw b1 = VLOADW(0, g[9]), b2 = VLOADW(0, g[10]);
    float3w e1b = scale3w(e1, b1), e2b = scale3w(e2, b2);
    v->p = add3w(add3w(p0, e1b), e2b);
    v->ng = normalize3w(cross3w(e1, e2));
    float3w magnitude = add3w(add3w(fabs3w(p0), fabs3w(e1b)), fabs3w(e2b));
    v->p_error = FLOAT_GAMMA(4) * dot3w(fabs3w(v->ng), magnitude);
    v->ns = v->ng;
#ifdef HAS_SHADING_NORMALS
    floatw b0 = 1.0f - b1 - b2;
    float3w n = add3w(add3w(scale3w(load3w(g, 23), b0), scale3w(load3w(g, 26), b1)), scale3w(load3w(g, 29), b2));
    floatw n2 = dot3w(n, n);
    float3w nu = scale3w(n, rsqrt(n2));
    nu = select3w(nu, neg3w(nu), dot3w(nu, v->ng) < 0.0f); /* face_forward(n, ng) */
    v->ns = select3w(v->ns, nu, n2 > 0.0f);
#endif
    v->wo = normalize3w(sub3w(prev_p, v->p));
    int light_lanes[PT_LANES], kind_lanes[PT_LANES];
    for (int k = 0; k < PT_LANES; ++k) {
        light_lanes[k] = light[k];
        kind_lanes[k] = kind[k];
    }
    v->light = VLOADW(0, light_lanes);
    v->bsdf.kind = VLOADW(0, kind_lanes);
    v->le = load3w(g, 19);
    v->light_pdf_origin = VLOADW(0, g[22]);
    v->bsdf.frame = frame_from_normal_w(v->ns);
    v->bsdf.ng = v->ng;
    v->bsdf.kd = load3w(g, 11);
    v->bsdf.ks = load3w(g, 14);
    v->bsdf.ior = VLOADW(0, g[17]);
    v->bsdf.alpha = VLOADW(0, g[18]);
    v->connectible = !bsdf_is_specular_w(&v->bsdf);
}

/* Adds contribution c of strategy (s, t) in the lanes of `mask`, noting the first that is not
 * finite (path_tracer_add per lane). */
inline void lanes_add(float3w* L, intw* bad_strategy, float3w c, intw mask, int s, int t) {
    c = select3w(splat3w((float3)(0.0f)), c, mask);
    floatw probe = c.x + c.y + c.z;
    *bad_strategy = select(*bad_strategy, (intw)(s * STRATEGY_STRIDE + t), probe - probe != 0.0f && *bad_strategy < 0);
    *L = add3w(*L, c);
}

/* Whether nothing blocks the segment from a to b (vertices_visible), lane by lane in `mask`. */
inline intw lanes_visible(const SceneData* scene, float3w a, float3w a_ng, floatw a_error, float3w b, float3w b_ng,
                          floatw b_error, intw mask, intw* rays) {
    float3w o = offset_ray_origin_w(a, a_ng, a_error, sub3w(b, a));
    float3w target = offset_ray_origin_w(b, b_ng, b_error, sub3w(o, b));
    float3w d = sub3w(target, o);
    mask = mask && !is_black3w(d);
    *rays += select((intw)(0), (intw)(1), mask);
    int m[PT_LANES], visible[PT_LANES];
    VSTOREW(mask, 0, m);
    float rays_l[6][PT_LANES];
    store3w(o, rays_l, 0);
    store3w(d, rays_l, 3);
    for (int k = 0; k < PT_LANES; ++k)
        visible[k] = m[k] && !occluded(scene->nodes, scene->triangles, &scene->cutouts, lane_of(rays_l, 0, k),
                                       lane_of(rays_l, 3, k), 1.0f)
                         ? -1
                         : 0;
    return VLOADW(0, visible);
}

/* s = 1 at vertex v (reached from prev_p) in the lanes of `mask`: path_tracer_light_samples with
 * one light sample of an area light, picked by power. */
inline float3w lanes_light_sample(const SceneData* scene, const SurfaceLanes* v, float3w prev_p, float3w beta,
                                  floatw u_light, floatw ux, floatw uy, intw mask, intw* rays) {
    float g[12][PT_LANES];
    float u[PT_LANES], area_lanes[PT_LANES];
    VSTOREW(u_light, 0, u);
    int n = scene->info->light_count;
    for (int k = 0; k < PT_LANES; ++k) {
        int i = find_interval(scene->light_cdf, n, u[k]);
        __global const Light* l = &scene->lights[i];
        /* Only area lights in these scenes. */
        __global const Triangle* tri = &scene->triangles[l->triangle];
        float4 p0 = tri->p0, p1 = tri->p1, p2 = tri->p2, le = l->emission;
        g[0][k] = p0.x, g[1][k] = p0.y, g[2][k] = p0.z;
        g[3][k] = p1.x, g[4][k] = p1.y, g[5][k] = p1.z;
        g[6][k] = p2.x, g[7][k] = p2.y, g[8][k] = p2.z;
        g[9][k] = le.x, g[10][k] = le.y, g[11][k] = le.z;
        u[k] = l->select_pdf;
        area_lanes[k] = l->area;
    }
    floatw select_pdf = VLOADW(0, u), area = VLOADW(0, area_lanes);
    float3w p0 = f3w(VLOADW(0, g[0]), VLOADW(0, g[1]), VLOADW(0, g[2]));
    float3w e1 = sub3w(f3w(VLOADW(0, g[3]), VLOADW(0, g[4]), VLOADW(0, g[5])), p0);
    float3w e2 = sub3w(f3w(VLOADW(0, g[6]), VLOADW(0, g[7]), VLOADW(0, g[8])), p0);
    float3w le = f3w(VLOADW(0, g[9]), VLOADW(0, g[10]), VLOADW(0, g[11]));
    floatw su0 = sqrt(ux);
    floatw b1 = 1.0f - su0, b2 = uy * su0;
    float3w e1b = scale3w(e1, b1), e2b = scale3w(e2, b2);
    float3w lp = add3w(add3w(p0, e1b), e2b);
    float3w ln = normalize3w(cross3w(e1, e2));
    floatw lp_error = FLOAT_GAMMA(4) * dot3w(fabs3w(ln), add3w(add3w(fabs3w(p0), fabs3w(e1b)), fabs3w(e2b)));
    float3w d = sub3w(lp, v->p);
    floatw d2 = dot3w(d, d);
    float3w wi = scale3w(d, rsqrt(d2));
    floatw cos_light = fabs(dot3w(ln, wi));
    floatw pdf_w = d2 / (cos_light * area);
    intw lit = d2 != 0.0f && cos_light != 0.0f && pdf_w > 0.0f && dot3w(ln, neg3w(wi)) > 0.0f && !is_black3w(le);
    mask = mask && lit;
    float3w sampled_beta = scale3w(le, 1.0f / (pdf_w * select_pdf));
    floatw sampled_pdf_fwd = select((1.0f / area) * select_pdf, (floatw)(0.0f), d2 == 0.0f);
    /* vertex_f(v, sampled): the direction from the positions, as wi. */
    float3w L = mul3w(mul3w(beta, bsdf_f_w(&v->bsdf, v->wo, wi)), sampled_beta);
    L = scale3w(L, fabs(dot3w(wi, v->ns)));
    mask = mask && !is_black3w(L);
    if (!any_lane(mask)) return splat3w((float3)(0.0f));
    mask = mask && lanes_visible(scene, v->p, v->ng, v->p_error, lp, ln, lp_error, mask, rays);
    /* vertex_pdf(v, prev, sampled) */
    float3w wp = sub3w(prev_p, v->p);
    floatw dp2 = dot3w(wp, wp);
    wp = scale3w(wp, rsqrt(dp2));
    floatw pdf_bsdf = bsdf_pdf_w(&v->bsdf, wp, wi);
    pdf_bsdf = pdf_bsdf * fabs(dot3w(ln, scale3w(d, sqrt(1.0f / d2)))) * (1.0f / d2);
    pdf_bsdf = select(pdf_bsdf, (floatw)(0.0f), dp2 == 0.0f || d2 == 0.0f);
    floatw ratio = select((floatw)(0.0f), pdf_bsdf / sampled_pdf_fwd, pdf_bsdf > 0.0f && sampled_pdf_fwd > 0.0f);
    return select3w(splat3w((float3)(0.0f)), scale3w(L, 1.0f / (1.0f + ratio)), mask);
}

/* path_tracer_sample for the PT_LANES launch items from `first_item` (lanes at or past
 * params->pixel_count do nothing), each lane's result written to camera_out[item - first of the
 * launch] as the one-sample kernel writes it. */
inline void path_tracer_lanes(const SceneData* scene, const RenderParams* params, int first, __global float4* camera_out) {
    uint keys[PT_LANES], reversed[PT_LANES];
    float o_l[3][PT_LANES], d_l[3][PT_LANES], pdf_l[PT_LANES];
    int alive_l[PT_LANES];
    for (int k = 0; k < PT_LANES; ++k) {
        int gid = first + k;
        alive_l[k] = 0;
        keys[k] = reversed[k] = 0u;
        o_l[0][k] = o_l[1][k] = o_l[2][k] = 0.0f;
        d_l[0][k] = d_l[1][k] = 0.0f;
        d_l[2][k] = 1.0f;
        pdf_l[k] = 0.0f;
        if (gid >= params->pixel_count) continue;
        int item = params->first_pixel + gid;
        int pixel = launch_item_pixel(item, params->width, params->height, params->pixel_stride, params->run_pixel,
                                      params->run_length);
        uint run_sample = params->run_length > 0 ? (uint)(item / params->run_length) : 0u;
        int px = pixel % params->width, py = pixel / params->width;
        Rng rng = rng_init((uint)pixel, params->sample_index + run_sample, params->seed);
        Rng position_rng = rng_init((uint)pixel, params->position_sample_index + run_sample, params->position_seed);
        rng_seek(&position_rng, SAMPLE_DRAW_PIXEL);
        float2 raster = (float2)((float)px, (float)py) + rng_next2(&position_rng);
        float3 o, d;
        float pdf = camera_subpath_ray(scene, &rng, raster, &o, &d);
        keys[k] = rng.key;
        reversed[k] = rng.sample_index_reversed;
        o_l[0][k] = o.x, o_l[1][k] = o.y, o_l[2][k] = o.z;
        d_l[0][k] = d.x, d_l[1][k] = d.y, d_l[2][k] = d.z;
        pdf_l[k] = pdf;
        alive_l[k] = pdf != 0.0f ? -1 : 0;
    }
    uintw key = VLOADW(0, keys), index_reversed = VLOADW(0, reversed);
    float3w o = f3w(VLOADW(0, o_l[0]), VLOADW(0, o_l[1]), VLOADW(0, o_l[2]));
    float3w d = f3w(VLOADW(0, d_l[0]), VLOADW(0, d_l[1]), VLOADW(0, d_l[2]));
    floatw pdf_fwd = VLOADW(0, pdf_l);
    intw active = VLOADW(0, alive_l);
    intw rays = (intw)(0);
    float3w L = splat3w((float3)(0.0f));
    intw bad_strategy = (intw)(-1);

    /* The previous vertex: the camera's, then each surface vertex (its BSDF for the next
     * vertex's forward density). */
    SurfaceLanes prev;
    prev.p = o;
    intw prev_delta = (intw)(0);
    float3w beta = splat3w((float3)(1.0f));
    for (int i = 1; i <= MAX_DEPTH + 1; ++i) {
        active = active && !is_black3w(beta);
        if (!any_lane(active)) break;
        float g[GATHER_FIELDS][PT_LANES];
        int light[PT_LANES], kind[PT_LANES], act[PT_LANES];
        VSTOREW(active, 0, act);
        float rays_l[6][PT_LANES];
        store3w(o, rays_l, 0);
        store3w(d, rays_l, 3);
        for (int k = 0; k < PT_LANES; ++k) {
            Hit hit;
            light[k] = -1;
            kind[k] = MATERIAL_DIFFUSE;
            if (act[k] && intersect(scene->nodes, scene->triangles, &scene->cutouts, lane_of(rays_l, 0, k),
                                    lane_of(rays_l, 3, k), INFINITY, &hit)) {
                gather_hit(scene, &hit, k, g, &light[k], &kind[k]);
            } else {
                /* A lane without a vertex: a degenerate stand-in, masked from here on. */
                if (act[k]) act[k] = -2;
                for (int f = 0; f < GATHER_FIELDS; ++f) g[f][k] = 0.0f;
                g[3][k] = g[7][k] = 1.0f; /* a unit right triangle, so the stand-in stays finite */
            }
        }
        intw traced = VLOADW(0, act);
        rays += select((intw)(0), (intw)(1), traced != 0);
        active = traced == -1;
        if (!any_lane(active)) break;
        SurfaceLanes v;
        surface_lanes_from_gather(g, light, kind, prev.p, &v);
        /* The forward density from the positions (path_tracer_sample). */
        if (i > 1) {
            float3w w = normalize3w(sub3w(v.p, prev.p));
            pdf_fwd = select(pdf_fwd, bsdf_pdf_w(&prev.bsdf, prev.wo, w), !prev_delta);
        }
        /* convert_density(prev, pdf_fwd, v) */
        float3w w = sub3w(v.p, prev.p);
        floatw d2 = dot3w(w, w);
        floatw inv_d2 = 1.0f / d2;
        floatw v_pdf_fwd = pdf_fwd * fabs(dot3w(v.ng, scale3w(w, sqrt(inv_d2)))) * inv_d2;
        v_pdf_fwd = select(v_pdf_fwd, (floatw)(0.0f), d2 == 0.0f);

        int t = i + 1;
        /* s = 0: path_tracer_emitter_hit */
        intw emitter = active && v.light >= 0;
        if (any_lane(emitter)) {
            float3w to_prev = sub3w(prev.p, v.p);
            floatw dp2 = dot3w(to_prev, to_prev);
            to_prev = scale3w(to_prev, rsqrt(dp2));
            intw emits = emitter && dp2 != 0.0f && dot3w(v.ng, to_prev) > 0.0f;
            float3w Le = mul3w(v.le, beta);
            floatw ratio = select((floatw)(0.0f), v.light_pdf_origin / v_pdf_fwd,
                                  v.light_pdf_origin > 0.0f && v_pdf_fwd > 0.0f);
            floatw weight = select(1.0f / (1.0f + ratio), (floatw)(1.0f), (intw)(t < 3 ? -1 : 0) || prev_delta);
            lanes_add(&L, &bad_strategy, scale3w(Le, weight), emits, 0, t);
        }
        if (i == MAX_DEPTH + 1) break;
        /* The vertex's draws (cl/sample_dimensions.h): the light point's (choice, point) for
         * s = 1 and the bounce's (lobe, direction). */
        uint light_draw = sample_draw_light_connection(t), bounce_draw = sample_draw_camera_bounce(i - 1);
        floatw u_choice, u_unused, u_light_x, u_light_y, u_lobe, u_dir_x, u_dir_y;
        rng_draw_lanes(key, index_reversed, light_draw, &u_choice, &u_unused);
        rng_draw_lanes(key, index_reversed, light_draw + 1u, &u_light_x, &u_light_y);
        rng_draw_lanes(key, index_reversed, bounce_draw, &u_lobe, &u_unused);
        rng_draw_lanes(key, index_reversed, bounce_draw + 1u, &u_dir_x, &u_dir_y);
        intw connect = active && v.connectible;
        if (scene->info->light_count > 0 && any_lane(connect))
            lanes_add(&L, &bad_strategy,
                      lanes_light_sample(scene, &v, prev.p, beta, u_choice, u_light_x, u_light_y, connect, &rays),
                      connect, 1, t);

        float3w wi, f;
        floatw pdf;
        intw specular;
        intw sampled = bsdf_sample_w(&v.bsdf, v.wo, u_lobe, u_dir_x, u_dir_y, &wi, &f, &pdf, &specular);
        active = active && sampled && !is_black3w(f);
        beta = mul3w(beta, scale3w(f, fabs(dot3w(wi, v.ns)) / pdf));
        beta = select3w(splat3w((float3)(0.0f)), beta, active);
        pdf_fwd = select(pdf, (floatw)(0.0f), specular);
        prev_delta = specular;
        o = offset_ray_origin_w(v.p, v.ng, v.p_error, wi);
        d = wi;
        prev = v;
    }
    int bad[PT_LANES], ray_count[PT_LANES];
    float r[PT_LANES], gr[PT_LANES], bl[PT_LANES];
    VSTOREW(bad_strategy, 0, bad);
    VSTOREW(rays, 0, ray_count);
    VSTOREW(L.x, 0, r);
    VSTOREW(L.y, 0, gr);
    VSTOREW(L.z, 0, bl);
    for (int k = 0; k < PT_LANES; ++k) {
        int gid = first + k;
        if (gid >= params->pixel_count) break;
        camera_out[gid] = (float4)(r[k], gr[k], bl[k], bad[k] < 0 ? (float)ray_count[k] : -1.0f - (float)bad[k]);
    }
}

#endif
