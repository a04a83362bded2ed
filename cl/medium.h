/* Participating media along rays (seed ch. 3 and 4.4.1; pbrt-v3 HomogeneousMedium,
 * VisibilityTester::Tr; Miller, Georgiev & Jarosz 2019 for grids), compiled with HAS_MEDIA only.
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
 * and the ends alone, so a connection's MIS can evaluate them in either direction: the MIS
 * weights of paths through homogeneous media are exact.
 *
 * Grid media (HAS_MEDIUM_GRIDS) have no closed-form transmittance, so they follow the
 * null-scattering path integral (Miller, Georgiev & Jarosz 2019). Inside a grid's box a ray meets
 * tentative collisions at the constant rate of the medium's majorant M (the largest extinction
 * of any channel anywhere in it), counted into the segment's optical depth with M for every
 * channel. A tentative collision at x is real, with probability sigma_t,c(x) / M for the
 * segment's channel c, or "null", where the ray goes on with a fresh optical depth. A null
 * collision is a vertex of the path in that formulation: the contribution carries
 * sigma_n,c(x) = M - sigma_t,c(x) there and the majorant's exp(-M d) along the way. A connection
 * crosses a grid by ratio tracking: it places null collisions at rate M and multiplies by
 * sigma_n,c / M at each, an unbiased transmittance.
 *
 * Relative to the density of the null collisions' positions (a Poisson process of rate M,
 * the same whichever strategy placed them, so it cancels from every MIS weight), a segment
 * sampled with channel c has density W_c e_c, where
 *     W_c = (homogeneous media's transmittance) x (product over its null collisions of sigma_n,c / M)
 * and e_c is sigma_t,c at the end if it scatters there (a grid's at that point), 1 at a surface;
 * the channel being uniform, the density is mean_c(W_c e_c), and the throughput gains
 * W sigma_s / density, or W / density. Without grids W is the transmittance T and this is the
 * homogeneous rule above. W is the same from either end, so for any set of null collisions the
 * MIS evaluates every strategy's density: the weights are exact with grids too, and each
 * channel's weight stays within 3 sigma_s / sigma_t (the one-sample balance heuristic over the
 * channels, here over the whole segment with its null collisions). Nothing is approximated but
 * the cap MEDIUM_MAX_EVENTS. */
#ifndef CLBDPT_MEDIUM_H
#define CLBDPT_MEDIUM_H

#include "bvh.h"
#include "lights.h"
#include "scene.h"

#define MEDIUM_VACUUM 0

/* Index-matched boundaries one segment may cross before it is given up (coplanar duplicates
 * of an interface could otherwise be crossed back and forth). */
#define MEDIUM_MAX_CROSSINGS 64

/* Tentative collisions one segment may meet in grid media before it is given up (lost, or no
 * transmittance): a bias only where a ray's majorant optical depth exceeds ~10^5. */
#define MEDIUM_MAX_EVENTS 100000u

#define SEGMENT_LOST 0     /* escaped the scene, or gave up: no vertex */
#define SEGMENT_SURFACE 1  /* ended on a surface that scatters (hit holds it) */
#define SEGMENT_MEDIUM 2   /* scattered in a medium (the origin moved to the point) */

inline float mean3(float3 v) { return (v.x + v.y + v.z) * (1.0f / 3.0f); }

inline float channel_of(float3 v, int c) { return c == 0 ? v.x : (c == 1 ? v.y : v.z); }

#ifdef HAS_MEDIUM_GRIDS
inline int medium_is_grid(__global const Medium* m) { return m->grid_offset >= 0; }

inline float3 grid_coordinates(__global const Medium* m, float3 p) {
    return (float3)(dot(xyz(m->world_to_grid[0]), p) + m->world_to_grid[0].w,
                    dot(xyz(m->world_to_grid[1]), p) + m->world_to_grid[1].w,
                    dot(xyz(m->world_to_grid[2]), p) + m->world_to_grid[2].w);
}

/* The density at scene point p: trilinear between voxel centres, the edge voxels' values out
 * to the grid's faces, 0 beyond them. */
inline float grid_density(const SceneData* scene, __global const Medium* m, float3 p) {
    float3 g = grid_coordinates(m, p);
    int nx = m->grid_size[0], ny = m->grid_size[1], nz = m->grid_size[2];
    float3 upper = (float3)((float)nx - 0.5f, (float)ny - 0.5f, (float)nz - 0.5f);
    if (g.x < -0.5f || g.y < -0.5f || g.z < -0.5f || g.x > upper.x || g.y > upper.y || g.z > upper.z) return 0.0f;
    g = clamp(g, (float3)(0.0f), upper - 0.5f);
    /* g >= 0: truncation is floor (PoCL's floor costs 17 instructions a vector). */
    int x0 = (int)g.x, y0 = (int)g.y, z0 = (int)g.z;
    float3 f = g - (float3)((float)x0, (float)y0, (float)z0);
    int x1 = min(x0 + 1, nx - 1), y1 = min(y0 + 1, ny - 1), z1 = min(z0 + 1, nz - 1);
    __global const float* v = scene->densities + m->grid_offset;
#define VOXEL(x, y, z) v[(x) + nx * ((y) + ny * (z))]
    float c00 = mix(VOXEL(x0, y0, z0), VOXEL(x1, y0, z0), f.x), c10 = mix(VOXEL(x0, y1, z0), VOXEL(x1, y1, z0), f.x);
    float c01 = mix(VOXEL(x0, y0, z1), VOXEL(x1, y0, z1), f.x), c11 = mix(VOXEL(x0, y1, z1), VOXEL(x1, y1, z1), f.x);
#undef VOXEL
    return mix(mix(c00, c10, f.y), mix(c01, c11, f.y), f.z);
}

/* The part [*t0, *t1] of the ray o + t d that lies inside the grid's box; false if none. */
inline int grid_interval(__global const Medium* m, float3 o, float3 d, float* t0, float* t1) {
    float3 go = grid_coordinates(m, o);
    float3 gd = (float3)(dot(xyz(m->world_to_grid[0]), d), dot(xyz(m->world_to_grid[1]), d),
                         dot(xyz(m->world_to_grid[2]), d));
    float3 lo = (float3)(-0.5f);
    float3 hi = (float3)((float)m->grid_size[0], (float)m->grid_size[1], (float)m->grid_size[2]) - 0.5f;
    for (int axis = 0; axis < 3; ++axis) {
        float o_a = channel_of(go, axis), d_a = channel_of(gd, axis);
        float lo_a = channel_of(lo, axis), hi_a = channel_of(hi, axis);
        if (d_a == 0.0f) {
            if (o_a < lo_a || o_a > hi_a) return 0;
            continue;
        }
        float ta = (lo_a - o_a) / d_a, tb = (hi_a - o_a) / d_a;
        *t0 = fmax(*t0, fmin(ta, tb));
        *t1 = fmin(*t1, fmax(ta, tb));
    }
    return *t0 < *t1;
}
#endif

/* Extinction per channel at point p of a medium (1 + index). */
inline float3 medium_sigma_t_at(const SceneData* scene, int medium, float3 p) {
    if (medium == MEDIUM_VACUUM) return (float3)(0.0f);
    __global const Medium* m = &scene->media[medium - 1];
#ifdef HAS_MEDIUM_GRIDS
    if (medium_is_grid(m)) return xyz(m->sigma_t) * grid_density(scene, m, p);
#endif
    return xyz(m->sigma_t);
}

/* The medium a ray enters when it leaves a surface of `material` toward w (ng: the triangle's
 * geometric normal, whose side is the exterior). */
inline int medium_beyond(const SceneData* scene, int material, float3 ng, float3 w) {
    __global const Material* m = &scene->materials[material];
    return dot(w, ng) > 0.0f ? m->exterior_medium : m->interior_medium;
}

/* exp(-sigma t) per channel, with exp(-0 * infinity) = 1. One vector exp for the three
 * channels: three scalar calls were an eighth of a path-traced sample's instructions in fog. */
inline float3 beer_lambert(float3 sigma, float t) {
    return select(exp_of_nonpositive(-sigma * t), (float3)(1.0f), sigma <= 0.0f);
}

/* Moves a ray off an index-matched boundary it hit: into the medium beyond, from the far side
 * of the hit point's error bound. */
inline void cross_interface(const SceneData* scene, const Hit* hit, float3 d, float3* o, int* medium) {
    __global const TriangleRows* tri = &scene->triangles[hit->triangle];
    float2 b = (float2)(hit->b1, hit->b2);
    float3 ng = triangle_normal(tri);
    *medium = medium_beyond(scene, scene->infos[hit->triangle].material, ng, d);
    *o = offset_ray_origin(triangle_point(tri, b), ng, triangle_point_error(tri, b, ng), d);
}

/* The distance-sampling density of a segment with weight w (W above) ending at vertex v: what
 * a random walk along the segment toward v multiplies v's area density by. */
inline float segment_distance_density(const SceneData* scene, float3 w, const PathVertex* v) {
    if (v->type != VERTEX_MEDIUM) return mean3(w);
    return mean3(w * (xyz(scene->media[v->medium - 1].sigma_t) * v->density));
}

/* What a segment gathers on its way: W per channel (the top of this file), the tentative
 * collisions drawn in grid media, and the density where it scattered (1 if homogeneous). */
typedef struct {
    float3 weight;
    uint events;
    float density;
} SegmentTally;

inline SegmentTally segment_tally_begin(void) {
    SegmentTally s;
    s.weight = (float3)(1.0f);
    s.events = 0u;
    s.density = 1.0f;
    return s;
}

/* Follows a ray from *o along the unit direction d, starting in *medium, through media and
 * index-matched boundaries until it scatters in a medium (SEGMENT_MEDIUM: *o is the point,
 * *medium its medium), reaches a scattering surface (SEGMENT_SURFACE: hit, *medium the one the
 * ray arrived in) or leaves the scene (SEGMENT_LOST). u: the channel and the first optical
 * depth; the choices at tentative collisions in grids and the optical depths after null ones
 * come from the random stream `stream`. *tally gathers the segment's weight W. */
inline int trace_through_media(const SceneData* scene, const Rng* rng, uint stream, float3* o, float3 d, int* medium,
                               float2 u, Hit* hit, SegmentTally* tally) {
    int channel = min((int)(u.x * 3.0f), 2);
    float tau = sample_unit_exponential(u.y);
    *tally = segment_tally_begin();
    for (int crossing = 0; crossing <= MEDIUM_MAX_CROSSINGS; ++crossing) {
        int found = intersect(scene->nodes, scene->triangles, &scene->cutouts, *o, d, INFINITY, hit);
        ++*scene->rays_traced;
        float t_max = found ? hit->t : INFINITY;
        if (*medium != MEDIUM_VACUUM) {
            __global const Medium* m = &scene->media[*medium - 1];
#ifdef HAS_MEDIUM_GRIDS
            float t0 = 0.0f, t1 = t_max;
            if (medium_is_grid(m) && m->majorant > 0.0f && grid_interval(m, *o, d, &t0, &t1)) {
                /* Tentative collisions at rate M within the box: each is real or null. */
                float majorant = m->majorant;
                float t = t0; /* the last tentative collision, or where the box begins */
                while (t + tau / majorant < t1) {
                    t += tau / majorant;
                    float3 p = *o + d * t;
                    float density = grid_density(scene, m, p);
                    float3 sigma_t = xyz(m->sigma_t) * density;
                    uint k = 2u * tally->events;
                    if (++tally->events > MEDIUM_MAX_EVENTS) return SEGMENT_LOST;
                    if (rng_stream_value(rng, stream, k) * majorant < channel_of(sigma_t, channel)) {
                        *o = p;
                        tally->density = density;
                        return SEGMENT_MEDIUM;
                    }
                    tally->weight *= ((float3)(majorant) - sigma_t) * (1.0f / majorant);
                    tau = sample_unit_exponential(rng_stream_value(rng, stream, k + 1u));
                }
                tau -= majorant * (t1 - t); /* the depth left over for the media beyond */
            }
            if (!medium_is_grid(m)) {
#else
            {
#endif
                float3 sigma_t = xyz(m->sigma_t);
                float sigma = channel_of(sigma_t, channel);
                float t_scatter = sigma > 0.0f ? tau / sigma : INFINITY;
                if (t_scatter < t_max) {
                    tally->weight *= beer_lambert(sigma_t, t_scatter);
                    *o += d * t_scatter;
                    return SEGMENT_MEDIUM;
                }
                tally->weight *= beer_lambert(sigma_t, t_max);
                tau -= sigma * t_max;
            }
        }
        if (!found) return SEGMENT_LOST;
#ifdef HAS_MEDIUM_INTERFACES
        if (scene->materials[scene->infos[hit->triangle].material].kind != MATERIAL_INTERFACE) return SEGMENT_SURFACE;
        cross_interface(scene, hit, d, o, medium);
#else
        return SEGMENT_SURFACE;
#endif
    }
    return SEGMENT_LOST;
}

/* The medium a ray leaving vertex v toward w starts in. */
inline int vertex_medium_toward(const SceneData* scene, const PathVertex* v, float3 w) {
    switch (v->type) {
    case VERTEX_MEDIUM: return v->medium;
    case VERTEX_CAMERA: return scene->info->camera_medium;
    case VERTEX_LIGHT: {
        __global const Light* light = &scene->lights[v->light];
        if (light->kind != LIGHT_AREA) return light->medium; /* vacuum for infinite lights */
        return medium_beyond(scene, scene->infos[light->triangle].material, v->ng, w);
    }
    default: return medium_beyond(scene, v->material, v->ng, w);
    }
}

/* The random stream of connection (s, t)'s transmittance through grid media: one per strategy,
 * apart from every segment's stream (those are numbered by their distance draws, below 2^31). */
inline uint connection_stream(int s, int t) { return 0x80000000u | ((uint)s << 12) | (uint)t; }

/* Transmittance between two vertices, per channel: 0 if any surface but an index-matched
 * boundary lies between them; through grid media an unbiased estimate by ratio tracking
 * (random stream `stream`), W of the top of this file. *to_a and *to_b receive the segment's
 * distance densities toward each end, for the same null collisions. Both ends leave their
 * surfaces by their error bounds and the surfaces at the ends are excluded, as in
 * vertices_visible. */
inline float3 vertices_transmittance(const SceneData* scene, const Rng* rng, uint stream, const PathVertex* a,
                                     const PathVertex* b, float* to_a, float* to_b) {
    float3 o = offset_ray_origin(a->p, a->ng, a->p_error, b->p - a->p);
    float3 target = offset_ray_origin(b->p, b->ng, b->p_error, o - b->p);
    int medium = vertex_medium_toward(scene, a, target - o);
    SegmentTally tally = segment_tally_begin();
    for (int crossing = 0; crossing <= MEDIUM_MAX_CROSSINGS; ++crossing) {
        float3 d = target - o;
        if (d.x == 0.0f && d.y == 0.0f && d.z == 0.0f) return (float3)(0.0f);
        Hit hit;
        ++*scene->rays_traced;
#ifdef HAS_MEDIUM_INTERFACES
        int found = intersect_segment(scene->nodes, scene->triangles, &scene->cutouts, o, d, &hit);
#else
        /* No index-matched boundary to cross: whatever surface lies between blocks the segment,
         * and an any-hit query finds one sooner than the closest hit (the same triangle test). */
        if (occluded(scene->nodes, scene->triangles, &scene->cutouts, o, d, 1.0f)) return (float3)(0.0f);
        const int found = 0;
#endif
        float length_d = length(d);
        float t_max = (found ? hit.t : 1.0f) * length_d;
        if (medium != MEDIUM_VACUUM) {
            __global const Medium* m = &scene->media[medium - 1];
#ifdef HAS_MEDIUM_GRIDS
            float3 dn = d / length_d;
            float t0 = 0.0f, t1 = t_max;
            if (medium_is_grid(m) && m->majorant > 0.0f && grid_interval(m, o, dn, &t0, &t1)) {
                float majorant = m->majorant;
                for (float t = t0;;) {
                    /* Every draw is counted, the one that overshoots the piece too: the next
                     * piece must not reuse it (it is no longer uniform, knowing it overshot). */
                    if (++tally.events > MEDIUM_MAX_EVENTS) return (float3)(0.0f);
                    t += sample_unit_exponential(rng_stream_value(rng, stream, tally.events)) / majorant;
                    if (!(t < t1)) break;
                    float3 sigma_t = medium_sigma_t_at(scene, medium, o + dn * t);
                    tally.weight *= ((float3)(majorant) - sigma_t) * (1.0f / majorant);
                    if (is_black(tally.weight)) return (float3)(0.0f);
                }
            }
            if (!medium_is_grid(m))
#endif
                tally.weight *= beer_lambert(xyz(m->sigma_t), t_max);
        }
        if (!found) {
            *to_a = segment_distance_density(scene, tally.weight, a);
            *to_b = segment_distance_density(scene, tally.weight, b);
            return tally.weight;
        }
        if (scene->materials[scene->infos[hit.triangle].material].kind != MATERIAL_INTERFACE) return (float3)(0.0f);
        cross_interface(scene, &hit, normalize(d), &o, &medium);
    }
    return (float3)(0.0f);
}

#endif
