/* Path vertices and their densities (seed ch. 3; pbrt-v3 bdpt.h struct Vertex).
 *
 * pdf_fwd: density of this vertex when sampled from its predecessor on its own subpath;
 * pdf_rev: density if it were sampled from the other direction. Both are area densities,
 * except where the vertex is an infinite light (environment, directional): those stay solid
 * angle (seed ch. 6), and convert_density leaves them alone. */
#ifndef CLBDPT_VERTEX_H
#define CLBDPT_VERTEX_H

#include "bsdf.h"
#include "bvh.h"
#include "camera.h"
#include "lights.h"
#include "phase.h"
#include "scene.h"

#define VERTEX_CAMERA 0
#define VERTEX_LIGHT 1
#define VERTEX_SURFACE 2
#define VERTEX_MEDIUM 3 /* scattered inside a participating medium (cl/medium.h) */

typedef struct {
    float3 p;    /* position; for an escaped camera ray a point 2 scene radii along it */
    float3 ng;   /* geometric normal; 0 where the vertex is not on a surface */
    float3 ns;   /* shading normal (= ng without per-vertex normals) */
    float3 wo;   /* surface, medium: unit direction toward the previous vertex of its subpath */
    float3 beta; /* throughput of the subpath up to and including this vertex */
    float pdf_fwd;
    float pdf_rev;
    float p_error; /* bound on p's distance from its surface along ng (cl/ray.h); 0 off surfaces */
    int type;      /* VERTEX_* */
    int delta;     /* sampled by a specular (delta) lobe */
    int material;  /* surface: material index */
    int light;     /* light vertex: its light; surface: the area light of the triangle, or -1 */
    /* bdpt: the MIS recursion's sum over the strategies that split the subpath at this vertex
     * or nearer its start, relative to the strategy that splits it just past this vertex
     * (mis_fill_camera_tails, mis_fill_light_tails in cl/mis.h); it fills the padding after
     * `light`, so the vertex does not grow */
    float mis_tail;
#ifdef HAS_TEXTURES
    /* surface: the material's reflectances with its textures applied at the hit, looked up
     * once when the vertex is made (vertex_bsdf runs many times per vertex: sampling, every
     * connection, every MIS density) */
    float3 kd, ks;
#endif
#ifdef HAS_EMISSION_TEXTURES
    float3 le; /* on an area light (a light vertex, or a surface vertex on an emitter): the
                  radiance emitted at this point, map_Ke applied */
#endif
#ifdef HAS_MEDIA
    int medium;    /* medium vertex: its medium (1 + index) */
    float density; /* medium vertex: the medium's density there (1 if homogeneous), looked up
                      once where the walk scattered, not again by every connection to it */
    /* The distance-sampling densities of the segment from the previous vertex of the subpath
     * (cl/medium.h): of reaching this vertex along it (a factor of pdf_fwd), and of reaching
     * the previous vertex from this one (a factor of the previous vertex's pdf_rev). 1 where
     * the segment runs in vacuum. */
    float dist_fwd, dist_rev;
#endif
} PathVertex;

/* A vertex of `type` at p, with geometric (and shading) normal ng, 0 off surfaces, and p's error
 * bound along it; no material, light, direction, throughput or densities yet. */
inline PathVertex vertex_at(int type, float3 p, float3 ng, float p_error) {
    PathVertex v;
    v.p = p;
    v.ng = ng;
    v.ns = ng;
    v.wo = (float3)(0.0f);
    v.beta = (float3)(0.0f);
    v.pdf_fwd = 0.0f;
    v.pdf_rev = 0.0f;
    v.p_error = p_error;
    v.type = type;
    v.delta = 0;
    v.material = -1;
    v.light = -1;
    v.mis_tail = 0.0f;
#ifdef HAS_TEXTURES
    v.kd = (float3)(0.0f);
    v.ks = (float3)(0.0f);
#endif
#ifdef HAS_EMISSION_TEXTURES
    v.le = (float3)(0.0f);
#endif
#ifdef HAS_MEDIA
    v.medium = 0;
    v.dist_fwd = 1.0f;
    v.dist_rev = 1.0f;
    v.density = 1.0f;
#endif
    return v;
}

inline int vertex_on_surface(const PathVertex* v) { return v->ng.x != 0.0f || v->ng.y != 0.0f || v->ng.z != 0.0f; }

/* |dot(n, w)| at a surface vertex, 1 elsewhere (camera, light point, medium). Both sides are
 * computed and one is selected: whether a path's next vertex lies on a surface is too
 * irregular for a branch predictor (valgrind's branch model counted 9% of the Cornell box's
 * bdpt mispredictions on this test when it was a branch). */
inline float surface_cosine_or_one(const PathVertex* v, float3 n, float3 w) {
    float cosine = fabs(dot(n, w));
    return vertex_on_surface(v) ? cosine : 1.0f;
}

inline int vertex_light_kind(const SceneData* scene, const PathVertex* v) { return scene->lights[v->light].kind; }

inline int vertex_is_light(const PathVertex* v) {
    return v->type == VERTEX_LIGHT || (v->type == VERTEX_SURFACE && v->light >= 0);
}

inline int vertex_is_infinite_light(const SceneData* scene, const PathVertex* v) {
    return v->type == VERTEX_LIGHT && light_is_infinite(vertex_light_kind(scene, v));
}

inline int vertex_is_delta_light(const SceneData* scene, const PathVertex* v) {
    return v->type == VERTEX_LIGHT && light_is_delta(vertex_light_kind(scene, v));
}

/* Whether a deterministic connection to this vertex can carry energy (pbrt IsConnectible). */
inline int vertex_is_connectible(const SceneData* scene, const PathVertex* v) {
    switch (v->type) {
    case VERTEX_CAMERA: return 1;
    case VERTEX_LIGHT: return !light_is_delta_direction(vertex_light_kind(scene, v));
    case VERTEX_MEDIUM: return 1;
    default: {
        int kind = scene->materials[v->material].kind;
        return kind != MATERIAL_MIRROR && kind != MATERIAL_GLASS;
    }
    }
}

#ifdef HAS_TEXTURES
/* A material's reflectances at texture coordinates uv: maps multiply the constants (the MTL
 * rule), clamped to [0, 1] so that a float texture cannot make a surface reflect more than it
 * receives (kd + ks <= 1 holds for the constants, see mtl_materials.cpp). */
inline void textured_reflectances(const SceneData* scene, __global const Material* m, float2 uv, float3* kd,
                                  float3* ks) {
    *kd = xyz(m->kd);
    *ks = xyz(m->ks);
    if (m->kd_texture) *kd *= clamp(texture_lookup(&scene->textures, m->kd_texture, uv).xyz, 0.0f, 1.0f);
    if (m->ks_texture) *ks *= clamp(texture_lookup(&scene->textures, m->ks_texture, uv).xyz, 0.0f, 1.0f);
}
#endif

/* The radiance an emitter vertex (vertex_is_light, on an area light) emits at its point. */
inline float3 vertex_area_le(const SceneData* scene, const PathVertex* v) {
#ifdef HAS_EMISSION_TEXTURES
    return v->le;
#else
    return xyz(scene->lights[v->light].emission);
#endif
}

inline Bsdf vertex_bsdf(const SceneData* scene, const PathVertex* v) {
    Bsdf b = bsdf_make(&scene->materials[v->material], v->ns, v->ng);
#ifdef HAS_TEXTURES
    b.kd = v->kd;
    b.ks = v->ks;
#endif
    return b;
}

#ifdef HAS_MEDIA
inline float vertex_phase_g(const SceneData* scene, const PathVertex* v) { return scene->media[v->medium - 1].g; }
#endif

/* Solid-angle density of scattering at surface or medium vertex v from direction wo into wi. */
inline float vertex_scatter_pdf(const SceneData* scene, const PathVertex* v, float3 wo, float3 wi) {
#ifdef HAS_MEDIA
    if (v->type == VERTEX_MEDIUM) return phase_hg(wo, wi, vertex_phase_g(scene, v));
#endif
    Bsdf b = vertex_bsdf(scene, v);
    return bsdf_pdf(&b, wo, wi);
}

/* Both directions' solid-angle densities at surface or medium vertex v: wo -> wi into *fwd and
 * wi -> wo into *rev, from one BSDF (a random walk needs the pair at every vertex). */
inline void vertex_scatter_pdfs(const SceneData* scene, const PathVertex* v, float3 wo, float3 wi, float* fwd,
                                float* rev) {
#ifdef HAS_MEDIA
    if (v->type == VERTEX_MEDIUM) {
        *fwd = *rev = phase_hg(wo, wi, vertex_phase_g(scene, v)); /* symmetric */
        return;
    }
#endif
    Bsdf b = vertex_bsdf(scene, v);
    *fwd = bsdf_pdf(&b, wo, wi);
    *rev = bsdf_pdf(&b, wi, wo);
}

/* Solid angle density at `v` toward `next` -> area density at `next` (seed 3.2, ConvertDensity). */
inline float convert_density(const SceneData* scene, const PathVertex* v, float pdf_w, const PathVertex* next) {
    if (vertex_is_infinite_light(scene, next)) return pdf_w;
    float3 w = next->p - v->p;
    float d2 = length_squared(w);
    if (d2 == 0.0f) return 0.0f;
    float inv_d2 = 1.0f / d2;
    pdf_w *= surface_cosine_or_one(next, next->ng, w * sqrt(inv_d2));
    return pdf_w * inv_d2;
}

/* Density of `next` sampled from v by a solid-angle density pdf_w at v, where `next` is a
 * specular vertex: the first of a chain of specular vertices that the path enters from v. Such
 * a chain joins v to the non-specular vertex u at its other end through a generalised geometric
 * term G(v, u) = eta_v^2 |cos_v| |d w_v / d A_u| = eta_u^2 |cos_u| |d w_u / d A_v| (Jakob &
 * Marschner 2012, "Manifold exploration"; eta: the index of refraction each end lies in, as
 * etendue is conserved), so u's area density through the chain is pdf_w G / (eta_v^2 |cos_v|),
 * and the strategy sampling the chain from u's end has the same G. G cancels in every ratio of
 * the MIS recursion, and the chain's entry vertex takes pdf_w / (eta_v^2 |cos_v|), its
 * projected solid-angle density over eta_v^2 (no cosine off surfaces: camera, point light,
 * medium). eta_v is the glass's index where the chain enters glass through its back face (v is
 * inside), else 1: a chain that starts inside one glass and enters another is not told apart.
 * The chain's other vertices keep the remap0 convention. pbrt-v3 instead converts pdf_w to area
 * at the chain's first vertex, which swaps G for the first segment's cosine over distance
 * squared on each side: on cornell-specular's floor caustic (light, glass sphere, floor 0.1-0.3
 * from it, camera) that underweighted light tracing about 30x against the camera path hitting
 * the light. */
inline float specular_chain_entry_density(const SceneData* scene, const PathVertex* v, float pdf_w,
                                          const PathVertex* next) {
    float3 w = next->p - v->p;
    float d2 = length_squared(w);
    if (d2 == 0.0f) return 0.0f;
    w *= rsqrt(d2);
    __global const Material* m = &scene->materials[next->material];
    if (m->kind == MATERIAL_GLASS && dot(w, next->ng) > 0.0f) pdf_w /= m->ior * m->ior;
    if (!vertex_on_surface(v)) return pdf_w;
    float cos_v = fabs(dot(v->ng, w));
    return cos_v > 0.0f ? pdf_w / cos_v : 0.0f;
}

/* Density of `next` sampled from v by a solid-angle density pdf_w at v: area measure
 * (convert_density), or, where `next` is specular, that of a specular chain's entry vertex. */
inline float density_toward(const SceneData* scene, const PathVertex* v, float pdf_w, const PathVertex* next) {
    return next->delta ? specular_chain_entry_density(scene, v, pdf_w, next)
                       : convert_density(scene, v, pdf_w, next);
}

/* Veach's adjoint correction for shading normals on importance-transport paths
 * (pbrt-v3 eq. 16.18): |wo.ns| |wi.ng| / (|wo.ng| |wi.ns|). */
inline float correct_shading_normal(const PathVertex* v, float3 wo, float3 wi, int mode) {
#ifdef HAS_SHADING_NORMALS
    if (mode == TRANSPORT_IMPORTANCE) {
        float num = fabs(dot(wo, v->ns)) * fabs(dot(wi, v->ng));
        float denom = fabs(dot(wo, v->ng)) * fabs(dot(wi, v->ns));
        return denom == 0.0f ? 0.0f : num / denom;
    }
#endif
    return 1.0f;
}

/* vertex_f of surface vertex v whose BSDF b is at hand; *wi gets the unit direction toward
 * `next`, for surface_vertex_pdf (where next is at v's point, the result is 0 and *wi no
 * direction). */
inline float3 surface_vertex_f(const PathVertex* v, const Bsdf* b, const PathVertex* next, int mode, float3* wi) {
    *wi = next->p - v->p;
    float d2 = length_squared(*wi);
    if (d2 == 0.0f) return (float3)(0.0f);
    *wi *= rsqrt(d2);
    return bsdf_f(b, v->wo, *wi) * correct_shading_normal(v, v->wo, *wi, mode);
}

/* The scattering (or, for an area light vertex, emission) from v toward `next`. */
inline float3 vertex_f(const SceneData* scene, const PathVertex* v, const PathVertex* next, int mode) {
    if (v->type == VERTEX_SURFACE) {
        Bsdf b = vertex_bsdf(scene, v);
        float3 wi;
        return surface_vertex_f(v, &b, next, mode, &wi);
    }
    float3 wi = next->p - v->p;
    float d2 = length_squared(wi);
    if (d2 == 0.0f) return (float3)(0.0f);
    wi *= rsqrt(d2);
#ifdef HAS_MEDIA
    /* sigma_s is in the vertex's throughput (cl/walk.h), as in pbrt-v3. */
    if (v->type == VERTEX_MEDIUM) return (float3)(phase_hg(v->wo, wi, vertex_phase_g(scene, v)));
#endif
    if (v->type == VERTEX_LIGHT && vertex_light_kind(scene, v) == LIGHT_AREA)
        return area_light_radiance(vertex_area_le(scene, v), v->ng, wi);
    return (float3)(0.0f);
}

/* vertex_pdf of surface vertex v whose BSDF b is at hand, toward `next` along wn (from
 * surface_vertex_f): the same operations, without making the BSDF again. */
inline float surface_vertex_pdf(const SceneData* scene, const PathVertex* v, const Bsdf* b, const PathVertex* prev,
                                const PathVertex* next, float3 wn) {
    float3 wp = prev->p - v->p;
    float dp2 = length_squared(wp);
    if (dp2 == 0.0f) return 0.0f;
    wp *= rsqrt(dp2);
    return density_toward(scene, v, bsdf_pdf(b, wp, wn), next);
}

/* Radiance emitted from light vertex v toward `prev` (pbrt Vertex::Le). */
inline float3 vertex_le(const SceneData* scene, const PathVertex* v, const PathVertex* prev) {
    if (!vertex_is_light(v)) return (float3)(0.0f);
    float3 w = prev->p - v->p;
    float d2 = length_squared(w);
    if (d2 == 0.0f) return (float3)(0.0f);
    w *= rsqrt(d2);
#ifdef HAS_ENVIRONMENT
    if (v->type == VERTEX_LIGHT) return vertex_light_kind(scene, v) == LIGHT_ENVIRONMENT ? environment_radiance(scene, -w) : (float3)(0.0f);
#endif
    return area_light_radiance(vertex_area_le(scene, v), v->ng, w);
}

/* Solid-angle density of the environment light sampling direction -w, times its selection
 * probability; w points from the light into the scene (pbrt InfiniteLightDensity). */
inline float infinite_light_density(const SceneData* scene, float3 w) {
#ifdef HAS_ENVIRONMENT
    int env = scene->info->environment_light;
    if (env < 0) return 0.0f;
    return scene->lights[env].select_pdf * environment_pdf_w(scene, -w);
#else
    return 0.0f;
#endif
}

/* Area density at `next` of light vertex v emitting toward it (pbrt Vertex::PdfLight); for a
 * specular `next`, a specular chain's entry density (specular_chain_entry_density). */
inline float vertex_pdf_light(const SceneData* scene, const PathVertex* v, const PathVertex* next) {
    float3 w = next->p - v->p;
    float d2 = length_squared(w);
    if (d2 == 0.0f) return 0.0f;
    float inv_d2 = 1.0f / d2;
    w *= sqrt(inv_d2);
    float pdf;
    if (vertex_is_infinite_light(scene, v)) {
        /* Emission from an infinite light starts on the scene's bounding disk (seed ch. 6): the
         * disk's area density, carried along the parallel rays to `next` (light_pdf_le's pdf_pos
         * for these lights, without the lookup of the direction's density it would add). */
        float r = scene_radius(scene);
        pdf = 1.0f / (PI_F * r * r);
        /* A specular chain's entry: the disk's density is already one per projected area. */
        if (next->delta) return pdf;
    } else {
        float pdf_pos, pdf_dir;
        light_pdf_le(scene, v->light, v->ng, w, &pdf_pos, &pdf_dir);
        if (next->delta) return specular_chain_entry_density(scene, v, pdf_dir, next);
        pdf = pdf_dir * inv_d2;
    }
    pdf *= surface_cosine_or_one(next, next->ng, w);
    return pdf;
}

/* Density of choosing light vertex v as the origin of a light subpath that continues toward
 * `next`: selection times area density; for infinite lights the direction density
 * (pbrt Vertex::PdfLightOrigin). */
inline float vertex_pdf_light_origin(const SceneData* scene, const PathVertex* v, const PathVertex* next) {
    float3 w = next->p - v->p;
    float d2 = length_squared(w);
    if (d2 == 0.0f) return 0.0f;
    w *= rsqrt(d2);
    if (vertex_is_infinite_light(scene, v)) return infinite_light_density(scene, w);
    float pdf_pos, pdf_dir;
    light_pdf_le(scene, v->light, v->ng, w, &pdf_pos, &pdf_dir);
    return pdf_pos * scene->lights[v->light].select_pdf;
}

/* Area density at `next` of sampling it from v, which was reached from `prev` (prev may be
 * null for camera and light vertices) (pbrt Vertex::Pdf); for a specular `next`, a specular
 * chain's entry density (specular_chain_entry_density). */
inline float vertex_pdf(const SceneData* scene, const PathVertex* v, const PathVertex* prev, const PathVertex* next) {
    if (v->type == VERTEX_LIGHT) return vertex_pdf_light(scene, v, next);
    float3 wn = next->p - v->p;
    float dn2 = length_squared(wn);
    if (dn2 == 0.0f) return 0.0f;
    wn *= rsqrt(dn2);
    float pdf_w;
    if (v->type == VERTEX_CAMERA) {
        float pdf_pos;
        camera_pdf_we(scene->camera, v->p, wn, &pdf_pos, &pdf_w);
    } else {
        float3 wp = prev->p - v->p;
        float dp2 = length_squared(wp);
        if (dp2 == 0.0f) return 0.0f;
        wp *= rsqrt(dp2);
        pdf_w = vertex_scatter_pdf(scene, v, wp, wn);
    }
    return density_toward(scene, v, pdf_w, next);
}

/* vertex_pdf(v, a, b) into *toward_b and vertex_pdf(v, b, a) into *toward_a, from one
 * evaluation of v's BSDF (vertex_scatter_pdfs) and one normalisation of each direction: the
 * same operations, so the same values bit for bit. v is a surface or medium vertex. */
inline void vertex_pdfs_between(const SceneData* scene, const PathVertex* v, const PathVertex* a, const PathVertex* b,
                                float* toward_b, float* toward_a) {
    *toward_a = *toward_b = 0.0f;
    float3 wa = a->p - v->p, wb = b->p - v->p;
    float da2 = length_squared(wa), db2 = length_squared(wb);
    if (da2 == 0.0f || db2 == 0.0f) return;
    wa *= rsqrt(da2);
    wb *= rsqrt(db2);
    float pdf_ab, pdf_ba;
    vertex_scatter_pdfs(scene, v, wa, wb, &pdf_ab, &pdf_ba);
    *toward_b = density_toward(scene, v, pdf_ab, b);
    *toward_a = density_toward(scene, v, pdf_ba, a);
}

/* Whether nothing blocks the segment between two vertices. Both ends leave their surfaces by
 * their own error bounds (offset_ray_origin) and the occlusion test ignores hits within the
 * rounding error of t of either end, so the far vertex's own surface never blocks and an
 * occluder a few ULPs from it still does (pbrt-v3 shortens the ray by 1e-4 of its length
 * instead: 1 cm in a 100 m room, where light leaks at every contact). */
inline int vertices_visible(const SceneData* scene, const PathVertex* a, const PathVertex* b) {
    float3 o = offset_ray_origin(a->p, a->ng, a->p_error, b->p - a->p);
    float3 target = offset_ray_origin(b->p, b->ng, b->p_error, o - b->p);
    float3 d = target - o;
    if (d.x == 0.0f && d.y == 0.0f && d.z == 0.0f) return 0;
    ++*scene->rays_traced;
    return !occluded(scene->nodes, scene->triangles, &scene->cutouts, o, d, 1.0f);
}

/* The geometric term without visibility: cosines at the surface ends over distance^2. */
inline float geometry_cosines(const PathVertex* a, const PathVertex* b) {
    float3 d = a->p - b->p;
    float g = 1.0f / length_squared(d);
    d *= sqrt(g);
    g *= surface_cosine_or_one(a, a->ns, d);
    g *= surface_cosine_or_one(b, b->ns, d);
    return g;
}

/* Geometric term with visibility (pbrt bdpt.cpp G). */
inline float geometry_term(const SceneData* scene, const PathVertex* a, const PathVertex* b) {
    float g = geometry_cosines(a, b);
    if (g == 0.0f) return 0.0f;
    return vertices_visible(scene, a, b) ? g : 0.0f;
}

#endif
