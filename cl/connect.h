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

inline float3 connect_bdpt(const SceneData* scene, const StrategyMix* mix, Rng* rng, const PathVertex* light_path,
                           const PathVertex* camera_path, int s, int t, float2* raster, float* weight) {
    float3 L = (float3)(0.0f);
    PathVertex sampled;
    *weight = 0.0f;
    /* An escaped camera ray's light vertex can only be used as it is (s = 0): there is no point
     * at infinity to connect to (seed ch. 6). */
    if (t > 1 && s != 0 && camera_path[t - 1].type == VERTEX_LIGHT) return L;

    if (s == 0) {
        const PathVertex* pt = &camera_path[t - 1];
        if (vertex_is_light(pt)) L = vertex_le(scene, pt, &camera_path[t - 2]) * pt->beta;
    } else if (t == 1) {
        const PathVertex* qs = &light_path[s - 1];
        rng_seek(rng, sample_draw_lens_connection(s));
        float2 u = rng_next2(rng);
        if (!vertex_is_connectible(scene, qs)) return L;
        float3 lens_point, wi;
        float pdf_w;
        float we = camera_sample_wi(&scene->camera, qs->p, u, &lens_point, &wi, &pdf_w, raster);
        if (pdf_w > 0.0f && we > 0.0f) {
            /* The lens is no scene surface: nothing to offset its point from. */
            sampled = vertex_at(VERTEX_CAMERA, lens_point, xyz(scene->camera.forward), 0.0f);
            sampled.beta = (float3)(we / pdf_w);
            L = qs->beta * vertex_f(scene, qs, &sampled, TRANSPORT_IMPORTANCE) * sampled.beta;
            if (vertex_on_surface(qs)) L *= fabs(dot(wi, qs->ns));
            if (!is_black(L) && !vertices_visible(scene, qs, &sampled)) L = (float3)(0.0f);
        }
    } else if (s == 1) {
        const PathVertex* pt = &camera_path[t - 1];
        rng_seek(rng, sample_draw_light_connection(t));
        float u_light = rng_next(rng);
        float2 u = rng_next2(rng);
        if (!vertex_is_connectible(scene, pt) || scene->info.light_count == 0) return L;
        float select_pdf;
        int light = sample_light_index(scene, u_light, &select_pdf);
        LightSample ls;
        if (light_sample_li(scene, light, pt->p, u, &ls)) {
            sampled = vertex_at(VERTEX_LIGHT, ls.p, ls.n, ls.p_error);
            sampled.beta = ls.li / (ls.pdf_w * select_pdf);
            sampled.light = light;
            sampled.pdf_fwd = vertex_pdf_light_origin(scene, &sampled, pt);
            L = pt->beta * vertex_f(scene, pt, &sampled, TRANSPORT_RADIANCE) * sampled.beta;
            if (vertex_on_surface(pt)) L *= fabs(dot(ls.wi, pt->ns));
            if (!is_black(L) && !vertices_visible(scene, pt, &sampled)) L = (float3)(0.0f);
        }
    } else {
        const PathVertex* qs = &light_path[s - 1];
        const PathVertex* pt = &camera_path[t - 1];
        if (vertex_is_connectible(scene, qs) && vertex_is_connectible(scene, pt)) {
            L = qs->beta * vertex_f(scene, qs, pt, TRANSPORT_IMPORTANCE) * vertex_f(scene, pt, qs, TRANSPORT_RADIANCE) * pt->beta;
            if (!is_black(L)) L *= geometry_term(scene, qs, pt);
        }
    }
    if (is_black(L)) return L;
    *weight = mis_weight(scene, mix, light_path, camera_path, &sampled, s, t);
    return L;
}

#endif
