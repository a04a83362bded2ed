/* Caustic merging: a density estimate for caustics seen through mirrors and glass, the one class
 * of paths that no BDPT strategy but s = 0 can sample where an area light or the environment
 * casts them, and none at all where a point, spot or directional light does.
 *
 * A connection joins two non-specular vertices, so a strategy that splits a path between x_(i-1)
 * and x_i exists only where neither is specular. In a path
 *     camera x_0, ..., x_k (non-specular), x_(k+1) ... x_(n-1) (specular), light x_n
 * in which no two neighbours of x_0 .. x_k are both non-specular (so x_(k-1) is specular, and x_1
 * too: E S ... S D S ... S L, such as the caustic under a glass ball seen through the ball), no
 * split exists at all. From an area light or the environment only the camera subpath that hits
 * the light (s = 0) samples it, its MIS weight is 1, and its variance is a path tracer's (on
 * cornell-specular these paths are 0.4% of the image's brightness, and leaving them out of a
 * 64-spp render and its reference lowered its squared error 1.34-1.49x). A point or spot light
 * (a position no ray can hit) or a directional one (a direction none can) leaves even s = 0 out:
 * every strategy renders such a caustic black (a spot light's pool of light under a glass, seen
 * through the glass).
 *
 * With merging on, s = 0 leaves these paths out (merged_by_caustic_photons) and the camera
 * subpath's x_k takes them from photons instead: light subpaths traced on their own for the pass
 * keep their first non-specular vertex where it follows one or more specular ones from a light
 * (caustic_photon_vertex), and x_k sums their power within a radius r, weighted by its BSDF, over
 * pi r^2 and the number of light subpaths (caustic_merges). Both sides are decided by the same
 * rule, so the two estimators split the paths between them and nothing is counted twice or lost;
 * a delta light's photons add paths nothing else counts. The estimate is biased by the blur of
 * the disk and consistent: the radius shrinks with the pass (host/render/caustic_photons.h).
 *
 * The photons' emitted rays are aimed at the sphere about the mirrors and glass, where their
 * first hit must lie (light_emission_aimed, cl/lights.h): an environment's or a directional
 * light's would otherwise start on a disk as wide as the scene, and few would meet a small glass
 * (sky with a glass ball of radius 0.45 added: no photon in 96 passes of 800 light subpaths).
 * A vertex scattered in a medium is non-specular (connectible) on both sides, and merging happens
 * on surfaces only, so a path that scatters in a medium next to x_k stays with the strategies
 * that sample it; segments through media carry their transmittance in both subpaths'
 * throughputs. Materials are either wholly specular (mirror, glass) or not at all, so a vertex's
 * delta flag is its material's. */
#ifndef CLBDPT_CAUSTIC_MERGING_H
#define CLBDPT_CAUSTIC_MERGING_H

#include "vertex.h"

/* Whether camera vertex k is where merging takes a path over: a non-specular surface vertex,
 * k >= 2, whose predecessor is specular, with no two non-specular neighbours among the vertices
 * before it (the camera vertex counts as non-specular), so that no strategy splits the path
 * before it. Both sides of the split between s = 0 and the photons ask this. */
inline int is_caustic_merge_vertex(const SceneData* scene, const PathVertex* camera_path, int k) {
    const PathVertex* v = &camera_path[k];
    if (k < 2 || !camera_path[k - 1].delta || v->type != VERTEX_SURFACE || !vertex_is_connectible(scene, v)) return 0;
    for (int i = 1; i < k - 1; ++i)
        if (!camera_path[i - 1].delta && !camera_path[i].delta) return 0;
    return 1;
}

/* Whether camera_path[0 .. t - 1], ending on an emitter (strategy s = 0: an area light's surface
 * or, for a subpath that escaped, the environment), is one of the paths the photons take over:
 * the vertex before the emitter is specular, and so is every vertex back to the last
 * non-specular one, which is a merge vertex. */
inline int merged_by_caustic_photons(const SceneData* scene, const PathVertex* camera_path, int t) {
    int e = t - 1;
    if (e < 4 || !camera_path[e - 1].delta) return 0;
#ifdef HAS_ENVIRONMENT
    /* The environment's light subpaths, and so its photons, leave only along the directions its
     * sampling can take (bdpt's takes the map's texels above its mean, cl/lights.h): along the
     * others s = 0 keeps the path. */
    if (camera_path[e].type == VERTEX_LIGHT && environment_pdf_w(scene, -camera_path[e].wo) <= 0.0f) return 0;
#endif
    int k = e - 1;
    while (camera_path[k].delta) --k; /* stops at the camera vertex at the latest */
    return is_caustic_merge_vertex(scene, camera_path, k);
}

/* The index of a light subpath's caustic photon: its first non-specular vertex, if that is a
 * surface vertex reached from the light through specular ones only (index >= 2); else 0. */
inline int caustic_photon_vertex(const SceneData* scene, const PathVertex* light_path, int n_light) {
    if (n_light < 3) return 0;
    for (int i = 1; i < n_light; ++i) {
        const PathVertex* v = &light_path[i];
        if (v->type != VERTEX_SURFACE) return 0;
        if (vertex_is_connectible(scene, v)) return i >= 2 ? i : 0;
    }
    return 0;
}

typedef struct {
    __global const CausticPhoton* photons;
    __global const uint* cells;
    __global const MergeSlice* slices;
} CausticMap;

inline uint merge_cell_slot(const MergeSlice* slice, int3 c) {
    return merge_cell_hash(c.x, c.y, c.z) & slice->cell_mask;
}

/* The photons' estimate at camera vertex v (the camera subpath's k-th), per unit of v's
 * throughput: sum of f(wo, wi_photon) x photon power within the slice's radius on v's surface,
 * over pi r^2 and the pass's light subpaths. Only photons whose path joined to v's stays within
 * MAX_DEPTH bounces count. */
inline float3 caustic_photon_estimate(const SceneData* scene, const CausticMap* map, uint slice_index,
                                      const PathVertex* v, int k) {
    MergeSlice slice = map->slices[slice_index];
    float r = slice.radius;
    float r2 = r * r;
    Bsdf b = vertex_bsdf(scene, v);
    float3 sum = (float3)(0.0f);
    int3 lo = convert_int3(floor((v->p - (float3)(r)) * slice.inv_cell));
    /* The 2 x 2 x 2 cells the disk may overlap; cells whose hashes collide share a slot, which
     * is visited once. */
    uint visited[8];
    int n_visited = 0;
    for (int c = 0; c < 8; ++c) {
        uint slot = merge_cell_slot(&slice, lo + (int3)(c & 1, (c >> 1) & 1, c >> 2));
        int seen = 0;
        for (int j = 0; j < n_visited; ++j) seen |= visited[j] == slot;
        if (seen) continue;
        visited[n_visited++] = slot;
        uint begin = map->cells[slice.cell_begin + slot], end = map->cells[slice.cell_begin + slot + 1];
        for (uint i = begin; i < end; ++i) {
            __global const CausticPhoton* ph = &map->photons[slice.photon_begin + i];
            float3 d = xyz(ph->p) - v->p;
            if (dot(d, d) > r2) continue;
            /* On v's surface: a photon on a wall meeting it at a corner is not v's. */
            if (fabs(dot(xyz(ph->ng), v->ng)) < 0.9f) continue;
            if ((int)ph->p.w + k - 1 > MAX_DEPTH) continue;
            float3 wi = xyz(ph->wi);
            sum += xyz(ph->beta) * bsdf_f(&b, v->wo, wi);
        }
    }
    return sum * slice.estimate_scale;
}

/* What the photons of slice `slice_index` add to the camera subpath's pixel: their estimate at
 * every merge vertex (is_caustic_merge_vertex), times its throughput. */
inline float3 caustic_merges(const SceneData* scene, const CausticMap* map, uint slice_index,
                             const PathVertex* camera_path, int n_camera) {
    float3 L = (float3)(0.0f);
    for (int k = 2; k < n_camera; ++k) {
        /* Past two non-specular neighbours no later vertex is a merge vertex. */
        if (!camera_path[k - 2].delta && !camera_path[k - 1].delta) break;
        if (is_caustic_merge_vertex(scene, camera_path, k))
            L += camera_path[k].beta * caustic_photon_estimate(scene, map, slice_index, &camera_path[k], k);
    }
    return L;
}

#endif
