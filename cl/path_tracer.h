/* The path tracer (INTEGRATOR_PT) one vertex at a time: the strategies s <= 1 of cl/connect.h,
 * made as the camera subpath grows instead of after it is stored.
 *
 * A path tracer's strategies need at most the vertex just found and the one before it: s = 0
 * reads the emitter's forward density and its predecessor's position (the MIS ratio to s = 1
 * through it), s = 1 samples a light point from the newest vertex. So the walk keeps two
 * vertices, not the MAX_DEPTH + 2 of a stored subpath, and makes each connection as soon as its
 * vertex exists (the same order as the generic kernel's t-major loop over (s, t), so the sums
 * are made in the same order).
 *
 * It computes what the generic route computes (cl/walk.h random_walk, cl/connect.h
 * connect_bdpt, cl/mis.h mis_weight with STRATEGY_MAX_LIGHT_VERTICES = 1), from the same draws
 * and the same vertex functions, so its images equal that route's; tests/path_tracer_test.cpp
 * compares the two (PT_FROM_SUBPATHS builds the generic one). What it leaves out:
 *   - the densities mis_weight computes and then does not use (the ratio through a direct hit
 *     seen from the camera, or through a delta vertex);
 *   - the weight recursions themselves: with one light vertex at most, each weight is one
 *     ratio (below);
 *   - the stored subpath, its copies into mis_weight, and the loops over (s, t) pairs that
 *     a path tracer's strategy set rules out.
 * Scenes with media and --strategy-images keep the generic route (render.cl). */
#ifndef CLBDPT_PATH_TRACER_H
#define CLBDPT_PATH_TRACER_H

#include "mis.h"
#include "walk.h"

/* A sample's weighted sum, and the first strategy that gave a value that is not finite
 * (s * STRATEGY_STRIDE + t; -1: none). */
typedef struct {
    float3 L;
    int bad_strategy;
#ifdef DEBUG_NAN_PIXEL
    int poisoned; /* tests: every contribution of this sample is made NaN */
#endif
} PathTracerSum;

inline void path_tracer_add(PathTracerSum* sum, float3 c, int s, int t) {
#ifdef DEBUG_NAN_PIXEL
    if (sum->poisoned && !is_black(c)) c = (float3)(NAN);
#endif
    /* NaN or Inf in any channel makes the difference NaN. */
    float probe = c.x + c.y + c.z;
    if (probe - probe != 0.0f && sum->bad_strategy < 0) sum->bad_strategy = s * STRATEGY_STRIDE + t;
    sum->L += c;
}

/* s = 0, the path's t-th vertex v (t >= 2) is an emitter: its radiance toward prev, weighted
 * against s = 1 at v, the light point that a light sample from prev could have picked (pbrt-v3
 * MISWeight with one ratio: p_1 / p_0 = the light's origin density over v's BSDF-sampled area
 * density). s = 1 cannot reach v from the camera vertex (t = 2: (1, 1) is no pt strategy) nor
 * through a delta vertex: the weight is then 1. */
inline float3 path_tracer_emitter_hit(const SceneData* scene, const PathVertex* prev, const PathVertex* v, int t) {
    float3 L = vertex_le(scene, v, prev) * v->beta;
    if (is_black(L) || t < 3 || prev->delta) return L;
    float pdf_light = vertex_pdf_light_origin(scene, v, prev);
    float ratio = mis_ratio(pdf_light, 0, v->pdf_fwd, 0);
#ifdef NEE_OWN_SELECTION
    ratio *= light_sample_selection_ratio(scene, v->light, prev->p); /* pdf_light has select_pdf */
#endif
    return L * (1.0f / (1.0f + ratio));
}

/* s = 1 at the path's vertex v: a light point sampled from v on `light` (taken with
 * probability select_pdf; -1: none) with draw u and joined to it, weighted against s = 0 (the
 * same path found by sampling v's BSDF toward the light point; p_0 / p_1 = its area density
 * over the light's origin density; weight 1 for a delta light). */
inline float3 path_tracer_light_sample(const SceneData* scene, int light, float select_pdf, float2 u,
                                       const PathVertex* prev, const PathVertex* v, const Bsdf* b) {
    LightSample ls;
    if (light < 0 || !light_sample_li(scene, light, v->p, u, &ls)) return (float3)(0.0f);
    PathVertex sampled = vertex_at(VERTEX_LIGHT, ls.p, ls.n, ls.p_error);
    sampled.beta = ls.li / (ls.pdf_w * select_pdf);
    sampled.light = light;
    sampled.pdf_fwd = vertex_pdf_light_origin(scene, &sampled, v);
    float3 wi;
    float3 L = v->beta * surface_vertex_f(v, b, &sampled, TRANSPORT_RADIANCE, &wi) * sampled.beta;
    if (vertex_on_surface(v)) L *= fabs(dot(ls.wi, v->ns));
    if (is_black(L) || !vertices_visible(scene, v, &sampled)) return (float3)(0.0f);
    if (vertex_is_delta_light(scene, &sampled)) return L;
    float pdf_bsdf = surface_vertex_pdf(scene, v, b, prev, &sampled, wi);
    float ratio = mis_ratio(pdf_bsdf, 0, sampled.pdf_fwd, 0);
#ifdef NEE_OWN_SELECTION
    ratio /= light_sample_selection_ratio(scene, light, v->p); /* sampled.pdf_fwd has select_pdf */
#endif
    return L * (1.0f / (1.0f + ratio));
}

/* The s = 1 strategy samples at the path's vertex v (draw u: u.x picks the light, its rest and
 * u.y the point): one light sample, or with NEE_EVERY_LIGHT one of each light group
 * (cl/lights.h), each added on its own. */
inline void path_tracer_light_samples(const SceneData* scene, float2 u, const PathVertex* prev, const PathVertex* v,
                                      const Bsdf* b, int t, PathTracerSum* sum) {
    if (!vertex_is_connectible(scene, v) || scene->info->light_count == 0) return;
    float select_pdf, u_rest;
#ifdef NEE_EVERY_LIGHT
    int groups = nee_group_count(scene);
    for (int g = 0; g < groups; ++g) {
        int light = nee_group_light(scene, g, v->p, u.x, &select_pdf, &u_rest);
        path_tracer_add(sum, path_tracer_light_sample(scene, light, select_pdf, (float2)(u_rest, u.y), prev, v, b), 1, t);
    }
#else
    int light = sample_light_for_point(scene, v->p, u.x, &select_pdf, &u_rest);
    path_tracer_add(sum, path_tracer_light_sample(scene, light, select_pdf, (float2)(u_rest, u.y), prev, v, b), 1, t);
#endif
}

/* One path tracer sample through raster position `raster`: the camera subpath of cl/walk.h
 * (generate_camera_subpath, random_walk in radiance mode) with its s = 0 and s = 1
 * connections made at each vertex, added into *sum (L 0 and bad_strategy -1 on entry). */
inline void path_tracer_sample(const SceneData* scene, Rng* rng, float2 raster, PathTracerSum* sum) {
    float3 o, d;
    float pdf_fwd = camera_subpath_ray(scene, rng, raster, &o, &d);
    if (pdf_fwd == 0.0f) return;
    PathVertex prev = vertex_at(VERTEX_CAMERA, o, (float3)(0.0f), 0.0f);
    prev.beta = (float3)(1.0f);
    /* The BSDF of each surface vertex, made once: its light samples, its bounce and the next
     * vertex's forward density all read it (from prev_bsdf at the next vertex). */
    Bsdf prev_bsdf;
    float3 beta = prev.beta;
    /* Vertex i of the camera subpath (the camera is vertex 0), so its strategies have t = i + 1
     * camera vertices; the last, i = MAX_DEPTH + 1, can only be an emitter hit (s = 0). */
    for (int i = 1; i <= MAX_DEPTH + 1 && !is_black(beta); ++i) {
        PathVertex v;
        Hit hit;
        ++*scene->rays_traced;
        if (intersect(scene->nodes, scene->triangles, &scene->cutouts, o, d, INFINITY, &hit)) {
            surface_vertex_from_hit(scene, &prev, &hit, &v);
        } else {
#ifdef HAS_ENVIRONMENT
            /* An escaped ray ends on the environment light (seed ch. 6; as random_walk). */
            if (scene->info->environment_light < 0) break;
            v = vertex_at(VERTEX_LIGHT, prev.p + d * (2.0f * scene_radius(scene)), (float3)(0.0f), 0.0f);
            v.wo = -d;
            v.light = scene->info->environment_light;
#else
            break;
#endif
        }
        v.beta = beta;
        /* The forward density from the positions, as random_walk (cl/walk.h says why). */
        if (i > 1 && !prev.delta) pdf_fwd = bsdf_pdf(&prev_bsdf, prev.wo, direction_from(&prev, &v));
        v.pdf_fwd = convert_density(scene, &prev, pdf_fwd, &v);

        int t = i + 1;
        if (vertex_is_light(&v)) path_tracer_add(sum, path_tracer_emitter_hit(scene, &prev, &v, t), 0, t);
        if (v.type == VERTEX_LIGHT || i == MAX_DEPTH + 1) break;
        /* The vertex's draws (cl/sample_dimensions.h), all at once: the light sample's (light
         * and point) for s = 1 and the bounce's (lobe and Russian roulette, direction); the
         * fourth lane repeats one. */
        uint light_draw = sample_draw_light_connection(t), bounce_draw = sample_draw_camera_bounce(i - 1);
        float4 ux, uy;
        rng_draws4(rng, (uint4)(light_draw, bounce_draw, bounce_draw + 1u, bounce_draw + 1u), &ux, &uy);
        Bsdf b = vertex_bsdf(scene, &v);
        path_tracer_light_samples(scene, (float2)(ux.s0, uy.s0), &prev, &v, &b, t, sum);

        BsdfSample bs;
        if (!bsdf_sample(&b, v.wo, (float3)(ux.s1, ux.s2, uy.s2), TRANSPORT_RADIANCE, &bs) || is_black(bs.f)) break;
        pdf_fwd = bs.pdf;
        beta *= bs.f * (fabs(dot(bs.wi, v.ns)) / bs.pdf);
        if (!bs.specular && !russian_roulette_continues(i - 1, scene->roulette_camera_from, 1.0f, uy.s1, &beta)) break;
        if (bs.specular) {
            /* A delta lobe has no density to compare with (seed 5.4.2). */
            v.delta = 1;
            pdf_fwd = 0.0f;
        }
        o = offset_ray_origin(v.p, v.ng, v.p_error, bs.wi);
        d = bs.wi;
        prev = v;
        prev_bsdf = b;
    }
}

#endif
