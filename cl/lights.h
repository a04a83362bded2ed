/* Light sources (seed ch. 1.3 and 6; pbrt-v3 lights/): one-sided triangle area lights, point,
 * spot, directional and environment lights. For each: Sample_Li / Pdf_Li (reaching a scene
 * point), Sample_Le / Pdf_Le (emitting a ray, origin and direction densities apart), and the
 * emitted radiance. Lights are chosen by power (light_cdf).
 *
 * Measures: pdf_w is solid angle at the receiving point, pdf_pos is area on the light (or on
 * the scene's bounding disk for directional and environment lights), pdf_dir is solid angle
 * of the emitted direction. */
#ifndef CLBDPT_LIGHTS_H
#define CLBDPT_LIGHTS_H

#include "geometry.h"
#include "ray.h"
#include "sampling.h"
#include "scene.h"

/* ---- Selection ------------------------------------------------------------------------- */

/* The interval of the light CDF holding u, among its first n (n <= light_count). With many
 * lights (LIGHT_CDF_GUIDE, host/render/features.h) through the CDF's guide (cl/scene.h), which
 * covers all light_count intervals: the answer among the first n is the nearer of its answer
 * and the n-th (the CDF does not decrease). */
inline int light_cdf_interval(const SceneData* scene, int n, float u) {
#ifdef LIGHT_CDF_GUIDE
    int count = scene->info->light_count;
    return min(find_interval_guided(scene->light_cdf, count, scene->light_cdf + count + 1, count, u), n - 1);
#else
    return find_interval(scene->light_cdf, n, u);
#endif
}

/* The light that draw u picks by power, its probability, and u's rest for sampling a point on
 * it (rest_of_choice). */
inline int sample_light_index(const SceneData* scene, float u, float* select_pdf, float* u_rest) {
    __global const float* cdf = scene->light_cdf;
    int i = light_cdf_interval(scene, scene->info->light_count, u);
    *select_pdf = scene->lights[i].select_pdf;
    *u_rest = rest_of_choice(u, cdf[i], cdf[i + 1]);
    return i;
}

inline int light_is_delta_position(int kind) { return kind == LIGHT_POINT || kind == LIGHT_SPOT; }
inline int light_is_delta_direction(int kind) { return kind == LIGHT_DIRECTIONAL; }
inline int light_is_delta(int kind) { return light_is_delta_position(kind) || light_is_delta_direction(kind); }
/* "Infinite" in pbrt's sense: the light sits at infinity and its vertex stores a direction. */
inline int light_is_infinite(int kind) { return kind == LIGHT_ENVIRONMENT || kind == LIGHT_DIRECTIONAL; }

/* ---- Area lights ----------------------------------------------------------------------- */

/* The unit geometric normal, front face counter-clockwise (stored in the rows' w lanes). */
inline float3 triangle_normal(__global const TriangleRows* tri) {
    return (float3)(tri->row[0].w, tri->row[1].w, tri->row[2].w);
}

/* The three corners of a triangle stored by rows (cl/shared/types.h). */
inline void triangle_corners(__global const TriangleRows* tri, float3* p0, float3* p1, float3* p2) {
    float4 x = tri->row[0], y = tri->row[1], z = tri->row[2];
    *p0 = (float3)(x.s0, y.s0, z.s0);
    *p1 = (float3)(x.s1, y.s1, z.s1);
    *p2 = (float3)(x.s2, y.s2, z.s2);
}

/* The point of barycentrics b (of p1 and p2) as p0 + b1 (p1 - p0) + b2 (p2 - p0): an affine
 * combination whatever the rounding of b, so its only error off the plane is the rounding of
 * these few operations, bounded by triangle_point_error. */
inline float3 triangle_point(__global const TriangleRows* tri, float2 b) {
    float3 p0, p1, p2;
    triangle_corners(tri, &p0, &p1, &p2);
    return p0 + (p1 - p0) * b.x + (p2 - p0) * b.y;
}

/* A bound on the distance of triangle_point(tri, b) from the triangle's plane, along its unit
 * normal n: each coordinate is off by at most gamma(4) (|p0| + |b1 e1| + |b2 e2|) (the edge
 * e1 = p1 - p0 rounded once, its product with b1 once, two sums; pbrt-v3 eq. 3.15 bounds the
 * form b0 p0 + b1 p1 + b2 p2 likewise, with gamma(7)). */
inline float triangle_point_error(__global const TriangleRows* tri, float2 b, float3 n) {
    float3 p0, p1, p2;
    triangle_corners(tri, &p0, &p1, &p2);
    float3 magnitude = fabs(p0) + fabs((p1 - p0) * b.x) + fabs((p2 - p0) * b.y);
    return FLOAT_GAMMA(4) * dot(fabs(n), magnitude);
}

/* Radiance le leaving an area light at a point with geometric normal n, seen in direction w:
 * one-sided, the front face is the counter-clockwise one. */
inline float3 area_light_radiance(float3 le, float3 n, float3 w) {
    return dot(n, w) > 0.0f ? le : (float3)(0.0f);
}

/* The radiance an area light emits at barycentrics b of its triangle: Ke, times its map_Ke
 * there where the material has one (MTL's rule for maps). */
inline float3 area_light_le(const SceneData* scene, __global const Light* light, float2 b) {
#ifdef HAS_EMISSION_TEXTURES
    __global const Material* m = &scene->materials[scene->infos[light->triangle].material];
    if (m->ke_texture) {
        float2 uv = triangle_uv(scene->uvs, light->triangle, b.x, b.y);
        return xyz(light->emission) * fmax(texture_lookup(&scene->textures, m->ke_texture, uv).xyz, 0.0f);
    }
#endif
    return xyz(light->emission);
}

/* ---- Spot falloff ---------------------------------------------------------------------- */

/* Whether unit direction w (away from the light) is inside the spot's cone. */
inline int spot_contains(__global const Light* light, float3 w) {
    return one_minus_cos_between(w, xyz(light->direction)) <= light->one_minus_cos_total;
}

/* Whether scene point x is inside the spot's cone. The direction is d * rsqrt(d . d): PoCL's
 * normalize is that product, after guards for zero, tiny and huge vectors (13 instructions a
 * call, on every light sample's selection in a scene with spots). At the light's own position
 * it is NaN, which the comparison counts as outside. */
inline int spot_contains_point(__global const Light* light, float3 x) {
    float3 d = x - xyz(light->position);
    return spot_contains(light, d * rsqrt(dot(d, d)));
}

/* pbrt-v3 SpotLight::Falloff: 1 inside the inner cone, 0 outside the outer one, a quartic ramp
 * in cos between; in terms of 1 - cos, which keeps a cone of any width apart from its axis. */
inline float spot_falloff(__global const Light* light, float3 w) {
    float v = one_minus_cos_between(w, xyz(light->direction));
    if (v > light->one_minus_cos_total) return 0.0f;
    if (v <= light->one_minus_cos_falloff) return 1.0f;
    float delta = (light->one_minus_cos_total - v) / (light->one_minus_cos_total - light->one_minus_cos_falloff);
    return (delta * delta) * (delta * delta);
}

/* ---- Selection for a light sample from a point ------------------------------------------
 * Light subpaths pick their light by power (sample_light_index). A light sample taken from a
 * point x (strategy s = 1) does the same, except with NEE_CONE_AWARE (a scene with spot lights
 * and few lights, host/render/features.cpp): there a spot light lights only the points inside
 * its cone, where it is as bright as a point light of its intensity, yet by power it would be
 * picked in proportion to the sphere its cone covers (6.5% of the time on point-spot, beside a
 * point light of similar intensity: pt's MSE 3.9x that of the choice below at 64 spp). So the
 * sample from x picks light l with probability w_l(x) / sum_k w_k(x), with w = select_pdf for
 * lights other than spots, and for a spot nee_weight (4 pi I over the lights' total power) if
 * its cone contains x, else 0: no sample is spent on a spot that cannot light x, which a weight
 * that ignores x would spend (fog-spot: a fixed 4 pi I weight made bdpt's MSE 2.7x). The MIS
 * weights account for the two distributions (light_sample_selection_ratio, cl/mis.h). */
#ifdef NEE_CONE_AWARE
inline float light_weight_at(const SceneData* scene, int i, float3 x) {
    __global const Light* light = &scene->lights[i];
    if (light->kind != LIGHT_SPOT) return light->select_pdf;
    return spot_contains_point(light, x) ? light->nee_weight : 0.0f;
}

inline float light_weights_total_at(const SceneData* scene, float3 x) {
    float total = 0.0f;
    for (int i = 0; i < scene->info->light_count; ++i) total += light_weight_at(scene, i, x);
    return total;
}
#endif

/* The light a light sample from x picks with draw u, the probability it had, and u's rest
 * (rest_of_choice); -1 if no light can reach x. */
inline int sample_light_for_point(const SceneData* scene, float3 x, float u, float* select_pdf, float* u_rest) {
#ifdef NEE_CONE_AWARE
    /* Each light's weight once, summed as light_weights_total_at does: a spot's costs a cone
     * test. */
    float weights[NEE_CONE_AWARE_MAX_LIGHTS];
    float total = 0.0f;
    for (int i = 0; i < scene->info->light_count; ++i) {
        weights[i] = light_weight_at(scene, i, x);
        total += weights[i];
    }
    float target = u * total;
    int chosen = -1;
    float chosen_weight = 0.0f;
    for (int i = 0; i < scene->info->light_count; ++i) {
        float w = weights[i];
        if (w <= 0.0f) continue;
        chosen = i; /* the last light with weight, should rounding leave target >= total */
        chosen_weight = w;
        if (target < w) break;
        target -= w;
    }
    *select_pdf = chosen >= 0 ? chosen_weight / total : 0.0f;
    *u_rest = rest_of_choice(target, 0.0f, chosen_weight);
    return chosen;
#else
    return sample_light_index(scene, u, select_pdf, u_rest);
#endif
}

/* ---- A light sample of every light (NEE_EVERY_LIGHT) -------------------------------------
 * With few lights (host/render/features.cpp) the light samples from a point x (strategy s = 1)
 * are taken of every light group at once, each group's sample a strategy sample of its own:
 * the area lights form one group (one triangle picked by power among them, with the draw
 * u_light), every other light is a group by itself, sampled with probability 1 (a spot only
 * where its cone contains x, as NEE_CONE_AWARE). One pick among the lights leaves a pixel lit
 * by one of them dark whenever the other is picked: on point-spot (a point and a spot light)
 * that choice made 61% of pt's squared error at 64 spp, for one shadow ray more per vertex.
 * Lights are stored area lights first (host/render/device_scene.cpp), so the area group's
 * picks are the light CDF's first area_light_count intervals. */
#ifdef NEE_EVERY_LIGHT
inline int nee_group_count(const SceneData* scene) {
    int area = scene->info->area_light_count;
    return scene->info->light_count - area + (area > 0 ? 1 : 0);
}

/* The probability that the light samples from x take light i. */
inline float nee_light_probability(const SceneData* scene, int i, float3 x) {
    int area = scene->info->area_light_count;
    __global const Light* light = &scene->lights[i];
    if (i < area) {
        float area_total = scene->light_cdf[area];
        return area_total > 0.0f ? light->select_pdf / area_total : 0.0f;
    }
    if (light->kind == LIGHT_SPOT) return spot_contains_point(light, x) ? 1.0f : 0.0f;
    return 1.0f;
}

/* The light that group g's sample from x takes with draw u_light, the probability it had
 * (*pick_pdf, the one the MIS weights use) and u_light's rest (rest_of_choice; u_light itself
 * for a group of one light); -1 if the group cannot light x. */
inline int nee_group_light(const SceneData* scene, int g, float3 x, float u_light, float* pick_pdf, float* u_rest) {
    int area = scene->info->area_light_count;
    int i;
    *u_rest = u_light;
    if (area > 0 && g == 0) {
        __global const float* cdf = scene->light_cdf;
        float area_total = cdf[area];
        float target = u_light * area_total;
        i = area_total > 0.0f ? light_cdf_interval(scene, area, target) : 0;
        *u_rest = rest_of_choice(target, cdf[i], cdf[i + 1]);
    } else {
        i = area + g - (area > 0 ? 1 : 0);
    }
    *pick_pdf = nee_light_probability(scene, i, x);
    return *pick_pdf > 0.0f ? i : -1;
}
#endif

/* Whether light samples from a point choose their lights otherwise than light subpaths do (by
 * select_pdf): the MIS weights then scale the s = 1 terms by light_sample_selection_ratio. */
#if defined(NEE_CONE_AWARE) || defined(NEE_EVERY_LIGHT)
#define NEE_OWN_SELECTION
#endif

/* For light i and a light sample from x: the probability of taking i there over select_pdf,
 * its probability for a light subpath (1 without NEE_OWN_SELECTION). 0 where no light sample
 * from x can take i: a point a spot's light subpath reached can still be outside its cone by
 * the rounding of the direction recomputed from the positions (a cone of 0.018 degrees, with
 * no other light, in tests/hard_cases_test.cpp), and 0 / 0 there would be NaN. */
inline float light_sample_selection_ratio(const SceneData* scene, int i, float3 x) {
#if defined(NEE_EVERY_LIGHT)
    float select_pdf = scene->lights[i].select_pdf; /* 0 only for a light of no power */
    return select_pdf > 0.0f ? nee_light_probability(scene, i, x) / select_pdf : 0.0f;
#elif defined(NEE_CONE_AWARE)
    float total_times_select = light_weights_total_at(scene, x) * scene->lights[i].select_pdf;
    return total_times_select > 0.0f ? light_weight_at(scene, i, x) / total_times_select : 0.0f;
#else
    return 1.0f;
#endif
}

/* ---- Environment map distribution ------------------------------------------------------
 * env_distribution holds, for a W x H map (row 0 = the +y pole):
 *   func      [W*H]       per texel, the density being sampled: the luminance's excess over the
 *                         map's mean times sin(theta), 0 at or below the mean (bdpt, pt), or the
 *                         luminance times sin(theta) (lt); host/render/device_scene.h says why
 *   cond_cdf  [H*(W+1)]   per-row CDFs over u
 *   marg_cdf  [H+1]       CDF over rows
 *   integral  [1]         mean of func = its integral over the unit square
 *   marg_guide [H+1]      the guide of marg_cdf (find_interval_guided, cl/sampling.h)
 *   cond_guide [H*(W+1)]  per row, the guide of its CDF
 * Directions: theta from +y (v = theta / pi), phi from +x toward +z (u = phi / 2 pi). */

inline float3 env_direction(float2 uv) {
    float2 theta_cs = unit_circle_turns(0.5f * uv.y), phi_cs = unit_circle_turns(uv.x);
    return (float3)(theta_cs.y * phi_cs.x, theta_cs.x, theta_cs.y * phi_cs.y);
}

inline float2 env_uv(float3 w) { return (float2)(atan2_turns(w.z, w.x), acos_half_turns(w.y)); }

inline int env_texel(const SceneData* scene, float2 uv) {
    int w = scene->info->env_width, h = scene->info->env_height;
    int x = min((int)(uv.x * (float)w), w - 1);
    int y = min((int)(uv.y * (float)h), h - 1);
    return y * w + x;
}

/* Radiance arriving from direction w (unit, pointing away from the scene). */
inline float3 environment_radiance(const SceneData* scene, float3 w) {
    __global const Light* light = &scene->lights[scene->info->environment_light];
    float3 scale = xyz(light->emission);
#ifdef HAS_ENVIRONMENT_MAP
    return scale * xyz(scene->env_texels[env_texel(scene, env_uv(w))]);
#else
    return scale;
#endif
}

/* Solid-angle density with which the environment light samples direction w. */
inline float environment_pdf_w(const SceneData* scene, float3 w) {
#ifdef HAS_ENVIRONMENT_MAP
    int width = scene->info->env_width, height = scene->info->env_height;
    __global const float* func = scene->env_distribution;
    float integral = func[width * height + height * (width + 1) + height + 1];
    float2 uv = env_uv(w);
    float sin_theta = unit_circle_turns(0.5f * uv.y).y;
    if (sin_theta == 0.0f || integral == 0.0f) return 0.0f;
    return (func[env_texel(scene, uv)] / integral) / (2.0f * PI_F * PI_F * sin_theta);
#else
    return INV_4PI_F;
#endif
}

/* Samples a direction toward the environment; returns it with its solid-angle density and the
 * radiance arriving from it (the sampled texel's: no mapping back from the direction). */
inline float3 environment_sample_direction(const SceneData* scene, float2 u, float* pdf_w, float3* radiance) {
    __global const Light* light = &scene->lights[scene->info->environment_light];
#ifdef HAS_ENVIRONMENT_MAP
    int width = scene->info->env_width, height = scene->info->env_height;
    __global const float* func = scene->env_distribution;
    __global const float* cond = func + width * height;
    __global const float* marg = cond + height * (width + 1);
    float integral = marg[height + 1];
    __global const float* marg_guide = marg + height + 2;
    __global const float* cond_guide = marg_guide + height + 1;
    int y = find_interval_guided(marg, height, marg_guide, height, u.y);
    float dv = (u.y - marg[y]) / (marg[y + 1] - marg[y]);
    __global const float* row = cond + y * (width + 1);
    int x = find_interval_guided(row, width, cond_guide + y * (width + 1), width, u.x);
    float du = (u.x - row[x]) / (row[x + 1] - row[x]);
    float2 uv = (float2)(((float)x + du) / (float)width, ((float)y + dv) / (float)height);
    float sin_theta = unit_circle_turns(0.5f * uv.y).y;
    *pdf_w = 0.0f;
    *radiance = (float3)(0.0f);
    if (sin_theta == 0.0f || integral == 0.0f) return (float3)(0.0f, 1.0f, 0.0f);
    *pdf_w = (func[y * width + x] / integral) / (2.0f * PI_F * PI_F * sin_theta);
    *radiance = xyz(light->emission) * xyz(scene->env_texels[y * width + x]);
    return env_direction(uv);
#else
    *pdf_w = INV_4PI_F;
    *radiance = xyz(light->emission);
    return sample_uniform_sphere(u);
#endif
}

/* ---- Sample_Li: a point on the light as seen from ref ---------------------------------- */

typedef struct {
    float3 p;     /* point on the light; for infinite lights a point 2 radii away along wi */
    float3 n;     /* geometric normal at p (area lights), else 0 */
    float p_error; /* area lights: bound on p's distance from the light's plane (cl/ray.h) */
    float3 wi;    /* unit direction from ref toward the light */
    float3 li;    /* incident radiance (area, environment) or its delta-light counterpart */
    float pdf_w;  /* solid angle at ref; 1 for delta lights */
} LightSample;

inline int light_sample_li(const SceneData* scene, int index, float3 ref, float2 u, LightSample* ls) {
    __global const Light* light = &scene->lights[index];
    ls->n = (float3)(0.0f);
    ls->p_error = 0.0f;
    ls->li = (float3)(0.0f);
    ls->pdf_w = 0.0f;
    switch (light->kind) {
#ifdef HAS_AREA_LIGHTS
    case LIGHT_AREA: {
        __global const TriangleRows* tri = &scene->triangles[light->triangle];
        float2 b = sample_uniform_triangle(u);
        ls->p = triangle_point(tri, b);
        ls->n = triangle_normal(tri);
        ls->p_error = triangle_point_error(tri, b, ls->n);
        float3 d = ls->p - ref;
        float d2 = length_squared(d);
        if (d2 == 0.0f) return 0;
        ls->wi = d * rsqrt(d2);
        float cos_light = fabs(dot(ls->n, ls->wi));
        if (cos_light == 0.0f) return 0;
        ls->pdf_w = d2 / (cos_light * light->area);
        ls->li = area_light_radiance(area_light_le(scene, light, b), ls->n, -ls->wi);
        break;
    }
#endif
#if defined(HAS_POINT_LIGHTS) || defined(HAS_SPOT_LIGHTS)
    case LIGHT_POINT:
    case LIGHT_SPOT: {
        ls->p = xyz(light->position);
        float3 d = ls->p - ref;
        float d2 = length_squared(d);
        if (d2 == 0.0f) return 0;
        ls->wi = d * rsqrt(d2);
        ls->pdf_w = 1.0f;
        float falloff = light->kind == LIGHT_SPOT ? spot_falloff(light, -ls->wi) : 1.0f;
        ls->li = xyz(light->emission) * (falloff / d2);
        break;
    }
#endif
#ifdef HAS_DIRECTIONAL_LIGHTS
    case LIGHT_DIRECTIONAL:
        ls->wi = -xyz(light->direction);
        ls->p = ref + ls->wi * (2.0f * scene_radius(scene));
        ls->pdf_w = 1.0f;
        ls->li = xyz(light->emission);
        break;
#endif
#ifdef HAS_ENVIRONMENT
    case LIGHT_ENVIRONMENT:
        ls->wi = environment_sample_direction(scene, u, &ls->pdf_w, &ls->li);
        ls->p = ref + ls->wi * (2.0f * scene_radius(scene));
        break;
#endif
    default:
        return 0;
    }
    return ls->pdf_w > 0.0f && !is_black(ls->li);
}

/* ---- Sample_Le: an emitted ray --------------------------------------------------------- */

typedef struct {
    float3 origin;
    float3 dir;     /* unit */
    float3 n;       /* normal at the origin used for the cosine in beta (pbrt's nLight) */
    float origin_error; /* area lights: bound on the origin's distance from the light's plane */
    float3 le;      /* emitted radiance (area, environment) or intensity (point, spot) */
    float pdf_pos;
    float pdf_dir;
} EmittedRay;

/* A point of the disk of `radius` about `center` across w_toward_light, moved `back` toward the
 * light: where an infinite light's emitted rays start. */
inline float3 disk_point_across(float3 center, float radius, float back, float3 w_toward_light, float2 u) {
    float3 s_axis, t_axis;
    coordinate_system(w_toward_light, &s_axis, &t_axis);
    float2 cd = sample_concentric_disk(u);
    float3 p_disk = center + radius * (cd.x * s_axis + cd.y * t_axis);
    return p_disk + back * w_toward_light;
}

inline void bounding_disk_point(const SceneData* scene, float3 w_toward_light, float2 u, float3* origin) {
    float r = scene_radius(scene);
    *origin = disk_point_across(scene_center(scene), r, r, w_toward_light, u);
}

inline int light_sample_le(const SceneData* scene, int index, float2 u_pos, float2 u_dir, EmittedRay* er) {
    __global const Light* light = &scene->lights[index];
    er->le = (float3)(0.0f);
    er->pdf_pos = 0.0f;
    er->pdf_dir = 0.0f;
    er->origin_error = 0.0f;
    switch (light->kind) {
#ifdef HAS_AREA_LIGHTS
    case LIGHT_AREA: {
        __global const TriangleRows* tri = &scene->triangles[light->triangle];
        float2 b = sample_uniform_triangle(u_pos);
        er->origin = triangle_point(tri, b);
        er->n = triangle_normal(tri);
        er->origin_error = triangle_point_error(tri, b, er->n);
        Frame f = frame_from_normal(er->n);
        float3 w_local = sample_cosine_hemisphere(u_dir);
        er->dir = from_local(&f, w_local);
        er->pdf_pos = 1.0f / light->area;
        er->pdf_dir = cosine_hemisphere_pdf(w_local.z);
        er->le = area_light_radiance(area_light_le(scene, light, b), er->n, er->dir);
        break;
    }
#endif
#ifdef HAS_POINT_LIGHTS
    case LIGHT_POINT:
        er->origin = xyz(light->position);
        er->dir = sample_uniform_sphere(u_dir);
        er->n = er->dir;
        er->pdf_pos = 1.0f;
        er->pdf_dir = INV_4PI_F;
        er->le = xyz(light->emission);
        break;
#endif
#ifdef HAS_SPOT_LIGHTS
    case LIGHT_SPOT: {
        er->origin = xyz(light->position);
        Frame f = frame_from_normal(xyz(light->direction));
        er->dir = from_local(&f, sample_uniform_cone(u_dir, light->one_minus_cos_total));
        er->n = er->dir;
        er->pdf_pos = 1.0f;
        er->pdf_dir = uniform_cone_pdf(light->one_minus_cos_total);
        er->le = xyz(light->emission) * spot_falloff(light, er->dir);
        break;
    }
#endif
#ifdef HAS_DIRECTIONAL_LIGHTS
    case LIGHT_DIRECTIONAL: {
        float3 w_light = -xyz(light->direction);
        bounding_disk_point(scene, w_light, u_pos, &er->origin);
        er->dir = xyz(light->direction);
        er->n = er->dir;
        float r = scene_radius(scene);
        er->pdf_pos = 1.0f / (PI_F * r * r);
        er->pdf_dir = 1.0f;
        er->le = xyz(light->emission);
        break;
    }
#endif
#ifdef HAS_ENVIRONMENT
    case LIGHT_ENVIRONMENT: {
        float pdf_w;
        float3 w_light = environment_sample_direction(scene, u_dir, &pdf_w, &er->le);
        bounding_disk_point(scene, w_light, u_pos, &er->origin);
        er->dir = -w_light;
        er->n = er->dir;
        float r = scene_radius(scene);
        er->pdf_pos = 1.0f / (PI_F * r * r);
        er->pdf_dir = pdf_w;
        break;
    }
#endif
    default:
        return 0;
    }
    return er->pdf_pos > 0.0f && er->pdf_dir > 0.0f && !is_black(er->le);
}

/* Re-aims er, an emitted ray of light `index` from light_sample_le with the same draws, at the
 * sphere aim (xyz the centre, w the radius), so that every ray that can meet what the sphere
 * bounds is still drawn, with the densities of the aimed draw (caustic photons, whose first hit
 * must be a mirror or glass inside it: cl/caustic_merging.h). Infinite lights keep the
 * direction and take the origin on the disk of the sphere's radius about its centre, across the
 * direction and outside the scene; the others keep the origin and take the direction uniformly
 * in the cone of the sphere seen from it, unless the origin lies in the sphere. Returns 0 where
 * the aimed ray carries nothing (an area light's back, a spot light's outside). */
inline int light_emission_aimed(const SceneData* scene, int index, float2 u_pos, float2 u_dir, float4 aim,
                                EmittedRay* er) {
    __global const Light* light = &scene->lights[index];
    float3 c = aim.xyz;
    float r = aim.w;
    if (light_is_infinite(light->kind)) {
        /* Far enough back along the light's direction to be outside the scene's bounding sphere. */
        float back = length(c - scene_center(scene)) + scene_radius(scene) + r;
        er->origin = disk_point_across(c, r, back, -er->dir, u_pos);
        er->pdf_pos = 1.0f / (PI_F * r * r);
        return 1;
    }
    float3 to_c = c - er->origin;
    float d2 = dot(to_c, to_c);
    if (d2 <= r * r) return 1;
    float sin2 = r * r / d2;
    float one_minus_cos = sin2 / (1.0f + sqrt(1.0f - sin2)); /* 1 - cos without cancellation */
    Frame f = frame_from_normal(to_c * rsqrt(d2));
    float3 dir = from_local(&f, sample_uniform_cone(u_dir, one_minus_cos));
    er->pdf_dir = uniform_cone_pdf(one_minus_cos);
    er->dir = dir;
    switch (light->kind) {
    case LIGHT_AREA:
        /* A diffuse emitter's radiance is the same toward every direction in front of it. */
        return dot(er->n, dir) > 0.0f;
#ifdef HAS_SPOT_LIGHTS
    case LIGHT_SPOT:
        er->n = dir;
        er->le = xyz(light->emission) * spot_falloff(light, dir);
        return !is_black(er->le);
#endif
    default:
        er->n = dir;
        return 1;
    }
}

/* Pdf_Le: densities with which light_sample_le would emit from `p` (normal n) along `dir`. */
inline void light_pdf_le(const SceneData* scene, int index, float3 n, float3 dir, float* pdf_pos, float* pdf_dir) {
    __global const Light* light = &scene->lights[index];
    *pdf_pos = 0.0f;
    *pdf_dir = 0.0f;
    switch (light->kind) {
    case LIGHT_AREA:
        *pdf_pos = 1.0f / light->area;
        *pdf_dir = cosine_hemisphere_pdf(dot(n, dir));
        break;
    case LIGHT_POINT:
        *pdf_dir = INV_4PI_F;
        break;
    case LIGHT_SPOT:
        *pdf_dir = spot_contains(light, dir) ? uniform_cone_pdf(light->one_minus_cos_total) : 0.0f;
        break;
    case LIGHT_DIRECTIONAL: {
        float r = scene_radius(scene);
        *pdf_pos = 1.0f / (PI_F * r * r);
        break;
    }
    case LIGHT_ENVIRONMENT: {
#ifdef HAS_ENVIRONMENT
        float r = scene_radius(scene);
        *pdf_pos = 1.0f / (PI_F * r * r);
        *pdf_dir = environment_pdf_w(scene, -dir);
#endif
        break;
    }
    default:
        break;
    }
}

/* Pdf_Li of an area light for a point p (normal n) on it seen from ref: the solid-angle density
 * light_sample_li gives that point. (The environment's is environment_pdf_w; delta lights are
 * never hit.) */
inline float light_pdf_li_area(__global const Light* light, float3 ref, float3 p, float3 n) {
    float3 d = p - ref;
    float d2 = length_squared(d);
    if (d2 == 0.0f) return 0.0f;
    float cos_light = fabs(dot(n, d * rsqrt(d2)));
    return cos_light == 0.0f ? 0.0f : d2 / (cos_light * light->area);
}

#endif
