/* Joining a light subpath prefix of s vertices to a camera subpath prefix of t vertices
 * (seed 4.6; pbrt-v3 ConnectBDPT): the four cases
 *   s = 0        the camera subpath itself ends on an emitter;
 *   t = 1        the light subpath's last vertex is joined to a freshly sampled lens point and
 *                lands at its own raster position (a splat into the light image);
 *   s = 1        a freshly sampled point on a light is joined to the camera subpath's end;
 *   s > 1, t > 1 the two last vertices are joined with a shadow ray and the geometric term.
 * Returns the contribution before MIS weighting; `weight` receives the MIS weight (0 when there
 * is no contribution) and `raster` the splat position when t = 1. */
#ifndef CLBDPT_CONNECT_H
#define CLBDPT_CONNECT_H

#include "mis.h"
#include "rng.h"
#include "sample_dimensions.h"
#ifdef HAS_MEDIA
#include "medium.h"
#endif
#ifdef HAS_CAUSTIC_MERGING
#include "caustic_merging.h"
#endif

/* Multiplies a connection's contribution by the visibility of the segment between a and b, or,
 * with media, by its transmittance; then *to_a and *to_b receive the distance-sampling densities
 * of the segment toward each end for the MIS (cl/medium.h; 1 without media). The connection
 * (s, t) numbers its own random stream for grid media. Forced inline: as a call, bdpt on
 * point-spot measured 2% slower on PoCL (medians of 6, at the edge of the run-to-run noise). */
__attribute__((always_inline)) inline float3 connection_visibility(const SceneData* scene, const Rng* rng, int s,
                                                                   int t, const PathVertex* a, const PathVertex* b,
                                                                   float3 L, float* to_a, float* to_b) {
    *to_a = 1.0f;
    *to_b = 1.0f;
    if (is_black(L)) return L;
#ifdef HAS_MEDIA
    return L * vertices_transmittance(scene, rng, connection_stream(s, t), a, b, to_a, to_b);
#else
    return vertices_visible(scene, a, b) ? L : (float3)(0.0f);
#endif
}

/* The number of light samples strategy (s, t) takes: one, but for s = 1 with NEE_EVERY_LIGHT one
 * of each light group (cl/lights.h), each connected by its own call of connect_bdpt. */
inline int connection_light_samples(const SceneData* scene, int s, int t) {
#ifdef NEE_EVERY_LIGHT
    if (s == 1 && t >= 2) return nee_group_count(scene);
#endif
    return 1;
}

/* nee_group: for s = 1 with NEE_EVERY_LIGHT, which light group to sample (else unused).
 * light_s1_scale: light_subpath_s1_scale of light_path (cl/mis.h).
 * outer_share: null, or where the MIS's share of the outer strategies goes (cl/mis.h; set
 * where the contribution is not black). */
inline float3 connect_bdpt(const SceneData* scene, const StrategyMix* mix, Rng* rng, const PathVertex* light_path,
                           const PathVertex* camera_path, int s, int t, int nee_group, float light_s1_scale,
                           float2* raster, float* weight, float* outer_share) {
    float3 L = (float3)(0.0f);
    PathVertex sampled;
    float to_qs = 1.0f, to_pt = 1.0f;
    *weight = 0.0f;
    /* An escaped camera ray's light vertex can only be used as it is (s = 0): there is no point
     * at infinity to connect to (seed ch. 6). */
    if (t > 1 && s != 0 && camera_path[t - 1].type == VERTEX_LIGHT) return L;

    if (s == 0) {
        const PathVertex* pt = &camera_path[t - 1];
        if (!vertex_is_light(pt)) return L;
#ifdef HAS_CAUSTIC_MERGING
        /* The pass's caustic photons estimate these paths instead (render.cl). */
        if (merged_by_caustic_photons(scene, camera_path, t)) return L;
#endif
        L = vertex_le(scene, pt, &camera_path[t - 2]) * pt->beta;
    } else if (t == 1) {
        const PathVertex* qs = &light_path[s - 1];
        rng_seek(rng, sample_draw_lens_connection(s));
        float2 u = rng_next2(rng);
        if (!vertex_is_connectible(scene, qs)) return L;
        float3 lens_point, wi;
        float pdf_w;
        float we = camera_sample_wi(scene->camera, qs->p, u, &lens_point, &wi, &pdf_w, raster);
        if (pdf_w > 0.0f && we > 0.0f) {
            /* The lens is no scene surface: nothing to offset its point from. */
            sampled = vertex_at(VERTEX_CAMERA, lens_point, xyz(scene->camera->forward), 0.0f);
            sampled.beta = (float3)(we / pdf_w);
            L = qs->beta * vertex_f(scene, qs, &sampled, TRANSPORT_IMPORTANCE) * sampled.beta;
            L *= surface_cosine_or_one(qs, qs->ns, wi);
            L = connection_visibility(scene, rng, s, t, qs, &sampled, L, &to_qs, &to_pt);
        }
    } else if (s == 1) {
        const PathVertex* pt = &camera_path[t - 1];
        rng_seek(rng, sample_draw_light_connection(t));
        float2 u = rng_next2(rng); /* u.x picks the light, its rest and u.y the point */
        if (!vertex_is_connectible(scene, pt) || scene->info->light_count == 0) return L;
        float select_pdf, u_rest;
#ifdef NEE_EVERY_LIGHT
        int light = nee_group_light(scene, nee_group, pt->p, u.x, &select_pdf, &u_rest);
#else
        int light = sample_light_for_point(scene, pt->p, u.x, &select_pdf, &u_rest);
#endif
        LightSample ls;
        if (light >= 0 && light_sample_li(scene, light, pt->p, (float2)(u_rest, u.y), &ls)) {
            sampled = vertex_at(VERTEX_LIGHT, ls.p, ls.n, ls.p_error);
            sampled.beta = ls.li / (ls.pdf_w * select_pdf);
            sampled.light = light;
            sampled.pdf_fwd = vertex_pdf_light_origin(scene, &sampled, pt);
            L = pt->beta * vertex_f(scene, pt, &sampled, TRANSPORT_RADIANCE) * sampled.beta;
            L *= surface_cosine_or_one(pt, pt->ns, ls.wi);
            L = connection_visibility(scene, rng, s, t, pt, &sampled, L, &to_pt, &to_qs);
        }
    } else {
        const PathVertex* qs = &light_path[s - 1];
        const PathVertex* pt = &camera_path[t - 1];
        if (vertex_is_connectible(scene, qs) && vertex_is_connectible(scene, pt)) {
            L = qs->beta * vertex_f(scene, qs, pt, TRANSPORT_IMPORTANCE) * vertex_f(scene, pt, qs, TRANSPORT_RADIANCE) * pt->beta;
            if (!is_black(L)) L = connection_visibility(scene, rng, s, t, qs, pt, L * geometry_cosines(qs, pt), &to_qs, &to_pt);
        }
    }
    if (is_black(L)) return L;
    *weight = mis_weight_and_outer_share(scene, mix, light_path, camera_path, &sampled, s, t, to_qs, to_pt,
                                         light_s1_scale, outer_share);
    return L;
}

#endif
