/* Homogeneous participating media along rays (seed ch. 3 and 4.4.1; pbrt-v3 HomogeneousMedium,
 * VisibilityTester::Tr), compiled with HAS_MEDIA only.
 *
 * Where media are: every triangle's material names a medium behind it and one in front of it
 * (Material.interior_medium, exterior_medium; 1 + index, 0 = vacuum); a ray crossing a surface
 * enters the one on the side it goes to. Surfaces of MATERIAL_INTERFACE only switch the medium:
 * rays pass them unchanged, and no path vertex is ever made on one.
 *
 * Distance sampling with chromatic coefficients: a ray picks one of the three channels
 * uniformly and one optical depth tau = -ln(1 - u); it scatters where the optical depth of
 * that channel, summed over every medium it has crossed since it left its last vertex, reaches
 * tau (the exponential distribution is memoryless, so one draw serves the whole segment,
 * however many index-matched boundaries it crosses). The density of the outcome is the average
 * over the channels, a one-sample balance-heuristic combination (pbrt-v3's, here over the
 * whole segment): with T the segment's transmittance per channel,
 *     scattering at the segment's end, in medium m:  mean_c(T_c sigma_t,m,c)
 *     reaching a surface or escaping:                mean_c(T_c)
 * and the throughput gains T sigma_s / density, or T / density. Both densities follow from T
 * and the ends alone, so a connection's MIS can evaluate them in either direction
 * (segment_distance_density): the MIS weights of paths through media are exact. */
#ifndef CLBDPT_MEDIUM_H
#define CLBDPT_MEDIUM_H

#include "bvh.h"
#include "lights.h"
#include "scene.h"

#define MEDIUM_VACUUM 0

/* Index-matched boundaries one segment may cross before it is given up (coplanar duplicates
 * of an interface could otherwise be crossed back and forth). */
#define MEDIUM_MAX_CROSSINGS 64

#define SEGMENT_LOST 0     /* escaped the scene, or gave up: no vertex */
#define SEGMENT_SURFACE 1  /* ended on a surface that scatters (hit holds it) */
#define SEGMENT_MEDIUM 2   /* scattered in a medium (the origin moved to the point) */

inline float3 medium_sigma_t(const SceneData* scene, int medium) {
    return medium == MEDIUM_VACUUM ? (float3)(0.0f) : xyz(scene->media[medium - 1].sigma_t);
}

/* The medium a ray enters when it leaves a surface of `material` toward w (ng: the triangle's
 * geometric normal, whose side is the exterior). */
inline int medium_beyond(const SceneData* scene, int material, float3 ng, float3 w) {
    __global const Material* m = &scene->materials[material];
    return dot(w, ng) > 0.0f ? m->exterior_medium : m->interior_medium;
}

/* exp(-sigma t) per channel, with exp(-0 * infinity) = 1. */
inline float3 beer_lambert(float3 sigma, float t) {
    return (float3)(sigma.x > 0.0f ? exp(-sigma.x * t) : 1.0f, sigma.y > 0.0f ? exp(-sigma.y * t) : 1.0f,
                    sigma.z > 0.0f ? exp(-sigma.z * t) : 1.0f);
}

inline float channel_of(float3 v, int c) { return c == 0 ? v.x : (c == 1 ? v.y : v.z); }

/* Moves a ray off an index-matched boundary it hit: into the medium beyond, from the far side
 * of the hit point's error bound. */
inline void cross_interface(const SceneData* scene, const Hit* hit, float3 d, float3* o, int* medium) {
    __global const Triangle* tri = &scene->triangles[hit->triangle];
    float2 b = (float2)(hit->b1, hit->b2);
    float3 ng = triangle_normal(tri);
    *medium = medium_beyond(scene, scene->infos[hit->triangle].material, ng, d);
    *o = offset_ray_origin(triangle_point(tri, b), ng, triangle_point_error(tri, b, ng), d);
}

/* Follows a ray from *o along the unit direction d, starting in *medium, through media and
 * index-matched boundaries until it scatters in a medium (SEGMENT_MEDIUM: *o is the point,
 * *medium its medium), reaches a scattering surface (SEGMENT_SURFACE: hit, *medium the one the
 * ray arrived in) or leaves the scene (SEGMENT_LOST). u: the channel and the optical depth
 * draws. *tr receives the transmittance of the path it followed, per channel. */
inline int trace_through_media(const SceneData* scene, float3* o, float3 d, int* medium, float2 u, Hit* hit,
                               float3* tr) {
    int channel = min((int)(u.x * 3.0f), 2);
    float tau = -log(1.0f - u.y);
    *tr = (float3)(1.0f);
    for (int crossing = 0; crossing <= MEDIUM_MAX_CROSSINGS; ++crossing) {
        int found = intersect(scene->nodes, scene->triangles, &scene->cutouts, *o, d, INFINITY, hit);
        ++*scene->rays_traced;
        float t_max = found ? hit->t : INFINITY;
        if (*medium != MEDIUM_VACUUM) {
            float3 sigma_t = medium_sigma_t(scene, *medium);
            float sigma = channel_of(sigma_t, channel);
            float t_scatter = sigma > 0.0f ? tau / sigma : INFINITY;
            if (t_scatter < t_max) {
                *tr *= beer_lambert(sigma_t, t_scatter);
                *o += d * t_scatter;
                return SEGMENT_MEDIUM;
            }
            *tr *= beer_lambert(sigma_t, t_max);
            tau -= sigma * t_max;
        }
        if (!found) return SEGMENT_LOST;
        if (scene->materials[scene->infos[hit->triangle].material].kind != MATERIAL_INTERFACE) return SEGMENT_SURFACE;
        cross_interface(scene, hit, d, o, medium);
    }
    return SEGMENT_LOST;
}

/* The medium a ray leaving vertex v toward w starts in. */
inline int vertex_medium_toward(const SceneData* scene, const PathVertex* v, float3 w) {
    switch (v->type) {
    case VERTEX_MEDIUM: return v->medium;
    case VERTEX_CAMERA: return scene->info.camera_medium;
    case VERTEX_LIGHT: {
        __global const Light* light = &scene->lights[v->light];
        if (light->kind != LIGHT_AREA) return light->medium; /* vacuum for infinite lights */
        return medium_beyond(scene, scene->infos[light->triangle].material, v->ng, w);
    }
    default: return medium_beyond(scene, v->material, v->ng, w);
    }
}

/* Transmittance between two vertices, per channel: 0 if any surface but an index-matched
 * boundary lies between them. Both ends leave their surfaces by their error bounds and the
 * surfaces at the ends are excluded, as in vertices_visible. */
inline float3 vertices_transmittance(const SceneData* scene, const PathVertex* a, const PathVertex* b) {
    float3 o = offset_ray_origin(a->p, a->ng, a->p_error, b->p - a->p);
    float3 target = offset_ray_origin(b->p, b->ng, b->p_error, o - b->p);
    int medium = vertex_medium_toward(scene, a, target - o);
    float3 tr = (float3)(1.0f);
    for (int crossing = 0; crossing <= MEDIUM_MAX_CROSSINGS; ++crossing) {
        float3 d = target - o;
        if (d.x == 0.0f && d.y == 0.0f && d.z == 0.0f) return (float3)(0.0f);
        Hit hit;
        ++*scene->rays_traced;
        int found = intersect_segment(scene->nodes, scene->triangles, &scene->cutouts, o, d, &hit);
        float t_max = found ? hit.t : 1.0f;
        if (medium != MEDIUM_VACUUM) tr *= beer_lambert(medium_sigma_t(scene, medium), t_max * length(d));
        if (!found) return tr;
        if (scene->materials[scene->infos[hit.triangle].material].kind != MATERIAL_INTERFACE) return (float3)(0.0f);
        cross_interface(scene, &hit, normalize(d), &o, &medium);
    }
    return (float3)(0.0f);
}

/* The distance-sampling density of a segment with transmittance tr ending at `end` (see the
 * top of this file): what a random walk along the segment toward `end` multiplies the
 * end's area density by. */
inline float segment_distance_density(const SceneData* scene, float3 tr, const PathVertex* end) {
    float3 weight = end->type == VERTEX_MEDIUM ? medium_sigma_t(scene, end->medium) : (float3)(1.0f);
    return (tr.x * weight.x + tr.y * weight.y + tr.z * weight.z) * (1.0f / 3.0f);
}

#endif
