/* Subpath generation (seed ch. 4; pbrt-v3 RandomWalk, GenerateCameraSubpath,
 * GenerateLightSubpath). Each new vertex gets pdf_fwd (area measure, or solid angle toward an
 * infinite light) and fills in its predecessor's pdf_rev; specular vertices are marked delta,
 * the densities of the vertices next to them are 0 (remap0, seed 5.4.2), and the first vertex
 * of a specular chain takes a chain entry's density (cl/vertex.h). Light subpaths carry
 * importance and use the adjoint BSDF (shading-normal correction, no 1/eta^2 on refraction). */
#ifndef CLBDPT_WALK_H
#define CLBDPT_WALK_H

#include "rng.h"
#include "russian_roulette.h"
#include "sample_dimensions.h"
#include "strategies.h"
#include "vertex.h"
#ifdef HAS_MEDIA
#include "medium.h"
#endif
#ifdef HAS_BUMP_MAPS
#include "bump.h"
#endif

/* Fills a surface vertex from a hit of a ray that left `prev`. */
inline void surface_vertex_from_hit(const SceneData* scene, const PathVertex* prev, const Hit* hit, PathVertex* v) {
    __global const TriangleRows* tri = &scene->triangles[hit->triangle];
    TriangleInfo info = scene->infos[hit->triangle];
    float2 b = (float2)(hit->b1, hit->b2);
    float3 ng = triangle_normal(tri);
    *v = vertex_at(VERTEX_SURFACE, triangle_point(tri, b), ng, triangle_point_error(tri, b, ng));
#ifdef HAS_SHADING_NORMALS
    if (info.normals >= 0) {
        __global const TriangleNormals* tn = &scene->normals[info.normals];
        float3 n = xyz(tn->n0) * (1.0f - hit->b1 - hit->b2) + xyz(tn->n1) * hit->b1 + xyz(tn->n2) * hit->b2;
        float n2 = length_squared(n);
        /* The winding decides the front face (emitters, glass); the shading normal follows it. */
        if (n2 > 0.0f) v->ns = face_forward(n * rsqrt(n2), v->ng);
    }
#endif
#ifdef HAS_TEXTURES
    float2 uv = triangle_uv(scene->uvs, hit->triangle, b.x, b.y);
    __global const Material* m = &scene->materials[info.material];
    textured_reflectances(scene, m, uv, &v->kd, &v->ks);
#ifdef HAS_BUMP_MAPS
    if (m->bump_texture) v->ns = bumped_normal(scene, tri, hit->triangle, m, uv, v->ns);
#endif
#endif
#ifdef HAS_EMISSION_TEXTURES
    if (info.light >= 0) v->le = area_light_le(scene, &scene->lights[info.light], b);
#endif
    v->wo = normalize(prev->p - v->p);
    v->material = info.material;
    v->light = info.light;
}

/* The unit direction from prev to v, where the walk from prev found v. A surface vertex's wo is
 * normalize(prev->p - v->p) (surface_vertex_from_hit), and negating a difference or a
 * normalisation is exact: -wo is normalize(v->p - prev->p) bit for bit, without its 20-odd
 * instructions. */
inline float3 direction_from(const PathVertex* prev, const PathVertex* v) {
    return v->type == VERTEX_SURFACE ? -v->wo : normalize(v->p - prev->p);
}

#ifdef HAS_MEDIA
/* One segment of a walk from vertex prev along the unit direction d (cl/medium.h): followed
 * from *o in *medium, with the values u_distance of the segment's distance draw (whose number
 * also names its random stream), to the medium or surface vertex where it ends (*v; left as it
 * is if the segment is lost), gathering *tally. Returns the SEGMENT_ kind. */
inline int walk_segment(const SceneData* scene, const Rng* rng, uint distance_draw, float2 u_distance,
                        const PathVertex* prev, float3* o, float3 d, int* medium, PathVertex* v, SegmentTally* tally) {
    Hit hit;
    int segment = trace_through_media(scene, rng, distance_draw, o, d, medium, u_distance, &hit, tally);
    if (segment == SEGMENT_MEDIUM) {
        *v = vertex_at(VERTEX_MEDIUM, *o, (float3)(0.0f), 0.0f);
        v->wo = -d;
        v->medium = *medium;
        v->density = tally->density;
    } else if (segment == SEGMENT_SURFACE) {
        surface_vertex_from_hit(scene, prev, &hit, v);
    }
    return segment;
}

/* The segment's distance sampling, weighted by its own density (cl/medium.h): v->dist_fwd, and
 * *beta times the segment's weight over it (and sigma_s where v is a medium vertex). Returns 0,
 * and leaves *beta, where the density is 0: the walk ends there. */
inline int walk_segment_throughput(const SceneData* scene, const SegmentTally* tally, PathVertex* v, float3* beta) {
    v->dist_fwd = segment_distance_density(scene, tally->weight, v);
    if (v->dist_fwd == 0.0f) return 0;
    float3 gain = tally->weight / v->dist_fwd;
    if (v->type == VERTEX_MEDIUM) gain *= xyz(scene->media[v->medium - 1].sigma_s) * v->density;
    *beta *= gain;
    return 1;
}

/* Scattering at medium vertex v with draw u: the phase function samples itself (up to the
 * isotropic shortcut of sample_phase_hg); *wi gets the direction, *beta the phase value over its
 * density, which is returned. No delta, no shading normals; the medium stays. */
inline float walk_scatter_in_medium(const SceneData* scene, const PathVertex* v, float2 u, float3* wi, float3* beta) {
    float g = vertex_phase_g(scene, v);
    float pdf = sample_phase_hg(v->wo, g, u, wi);
    *beta *= phase_hg(v->wo, *wi, g) / pdf;
    return pdf;
}
#endif

/* Extends a subpath: path[start - 1] is the vertex the ray (o, d) leaves (the camera or the
 * light vertex), with throughput beta and solid-angle density pdf_dir of d. Writes at most
 * max_vertices vertices from path[start] on and returns how many; stops before tracing a ray
 * whose throughput is black, or where Russian roulette ends the subpath (cl/russian_roulette.h;
 * its throughput's share is of beta, the one it starts with). Bounce k draws from
 * first_draw + SAMPLE_DRAWS_PER_BOUNCE * k.
 *
 * Densities between surface vertices are evaluated from the vertex positions, exactly as every
 * MIS evaluation later does, not from the sampled direction: the ray leaves from an offset
 * origin, so the direction to where it landed differs from the sampled one by up to ~1e-5 rad,
 * and a near-specular glossy lobe's density changes by percents over that. With positions on
 * both sides the MIS weights of a path sum to 1 to float precision (tests/mis_test.cpp).
 *
 * With media (cl/medium.h) a segment may end in a medium vertex instead, crosses index-matched
 * boundaries without a vertex, and its distance-sampling densities become factors of the
 * densities at both of its ends (PathVertex.dist_fwd, dist_rev). d must be unit length. */
inline int random_walk(const SceneData* scene, Rng* rng, float3 o, float3 d, float3 beta, float pdf_dir,
                       int max_vertices, int mode, uint first_draw, PathVertex* path, int start) {
    const int end = start + max_vertices;
    const float beta_start_max = max_channel(beta);
    const int roulette_from = mode == TRANSPORT_RADIANCE ? scene->roulette_camera_from : scene->roulette_light_from;
    float pdf_fwd = pdf_dir;
    int i = start;
#ifdef HAS_MEDIA
    int medium = vertex_medium_toward(scene, &path[start - 1], d);
#endif
    /* Bounce draws (lobe, direction) two bounces at a time: lanes 0 and 1 for an even bounce,
     * 2 and 3 for the odd one after it (rng_draws4). */
    float4 bounce_x, bounce_y;
#ifdef HAS_MEDIA
    float4 distance_x, distance_y;
#endif
    while (i < end && !is_black(beta)) {
        PathVertex* vertex = &path[i];
        PathVertex* prev = &path[i - 1];
#ifdef HAS_MEDIA
        /* Distance draws four segments at a time (as the bounces' draws, below). */
        int segment = i - start;
        uint distance_draw = first_draw + SAMPLE_DRAWS_PER_BOUNCE * (uint)segment + SAMPLE_DRAW_BOUNCE_DISTANCE;
        if ((segment & 3) == 0) {
            uint4 draws = (uint4)(distance_draw) + (uint4)(0u, 1u, 2u, 3u) * SAMPLE_DRAWS_PER_BOUNCE;
            rng_draws4(rng, draws, &distance_x, &distance_y);
        }
        int lane = segment & 3;
        float2 u_distance = lane == 0 ? (float2)(distance_x.s0, distance_y.s0)
                          : lane == 1 ? (float2)(distance_x.s1, distance_y.s1)
                          : lane == 2 ? (float2)(distance_x.s2, distance_y.s2)
                                      : (float2)(distance_x.s3, distance_y.s3);
        SegmentTally tally;
        int found =
            walk_segment(scene, rng, distance_draw, u_distance, prev, &o, d, &medium, vertex, &tally) != SEGMENT_LOST;
#else
        Hit hit;
        int found = intersect(scene->nodes, scene->triangles, &scene->cutouts, o, d, INFINITY, &hit);
        ++*scene->rays_traced;
        if (found) surface_vertex_from_hit(scene, prev, &hit, vertex);
#endif
        if (!found) {
#ifdef HAS_ENVIRONMENT
            /* An escaped camera ray ends on the environment light (seed ch. 6); its density
             * stays in solid angle. */
            if (mode != TRANSPORT_RADIANCE || scene->info->environment_light < 0) break;
            *vertex = vertex_at(VERTEX_LIGHT, prev->p + d * (2.0f * scene_radius(scene)), (float3)(0.0f), 0.0f);
            vertex->wo = -d;
            vertex->light = scene->info->environment_light;
#else
            break;
#endif
        }
#ifdef HAS_MEDIA
        vertex->dist_rev = segment_distance_density(scene, tally.weight, prev);
        if (!walk_segment_throughput(scene, &tally, vertex, &beta)) break;
#endif
        vertex->beta = beta;
        /* A scattering predecessor: its forward density toward this vertex and its own
         * predecessor's reverse density, both from the positions (see above). */
        if (i > start && !prev->delta) {
            float3 w = direction_from(prev, vertex);
#if STRATEGIES_READ_SUBPATH_PDF_REV
            float pdf_rev;
            vertex_scatter_pdfs(scene, prev, prev->wo, w, &pdf_fwd, &pdf_rev);
            path[i - 2].pdf_rev = density_toward(scene, prev, pdf_rev, &path[i - 2]);
#ifdef HAS_MEDIA
            path[i - 2].pdf_rev *= prev->dist_rev;
#endif
#else
            pdf_fwd = vertex_scatter_pdf(scene, prev, prev->wo, w);
#endif
        }
        /* Kept in solid angle too, for when this vertex turns out specular (below). */
        const float pdf_w_toward_vertex = pdf_fwd;
        vertex->pdf_fwd = convert_density(scene, prev, pdf_fwd, vertex);
#ifdef HAS_MEDIA
        vertex->pdf_fwd *= vertex->dist_fwd;
#endif
        ++i;
        if (vertex->type == VERTEX_LIGHT || i == end) break;
#ifdef HAS_CAUSTIC_MERGING
        if (scene->walk_ends_at_scattering && vertex_is_connectible(scene, vertex)) break;
#endif

        int bounce = i - 1 - start;
        if ((bounce & 1) == 0) {
            uint draw = first_draw + SAMPLE_DRAWS_PER_BOUNCE * (uint)bounce;
            uint next = draw + SAMPLE_DRAWS_PER_BOUNCE;
            rng_draws4(rng, (uint4)(draw, draw + 1u, next, next + 1u), &bounce_x, &bounce_y);
        }
        float u_lobe = (bounce & 1) ? bounce_x.s2 : bounce_x.s0;
        float2 u_dir = (bounce & 1) ? (float2)(bounce_x.s3, bounce_y.s3) : (float2)(bounce_x.s1, bounce_y.s1);
        float u_roulette = (bounce & 1) ? bounce_y.s2 : bounce_y.s0; /* the lobe draw's second value */
#ifdef HAS_MEDIA
        if (vertex->type == VERTEX_MEDIUM) {
            float3 wi;
            pdf_fwd = walk_scatter_in_medium(scene, vertex, u_dir, &wi, &beta);
            if (!russian_roulette_continues(bounce, roulette_from, beta_start_max, u_roulette, &beta)) break;
            o = vertex->p;
            d = wi;
            continue;
        }
#endif
        float3 u = (float3)(u_lobe, u_dir.x, u_dir.y);
        Bsdf b = vertex_bsdf(scene, vertex);
        BsdfSample bs;
        if (!bsdf_sample(&b, vertex->wo, u, mode, &bs) || is_black(bs.f)) break;
        pdf_fwd = bs.pdf;
        beta *= bs.f * (fabs(dot(bs.wi, vertex->ns)) / bs.pdf);
        if (bs.specular) {
            /* A delta lobe has no density to compare with (seed 5.4.2): both are 0. */
            vertex->delta = 1;
            /* The first vertex of a specular chain: its density is a chain entry's (cl/vertex.h,
             * specular_chain_entry_density); past the chain's first vertex remap0 holds. */
            if (!prev->delta) {
                vertex->pdf_fwd = specular_chain_entry_density(scene, prev, pdf_w_toward_vertex, vertex);
#ifdef HAS_MEDIA
                vertex->pdf_fwd *= vertex->dist_fwd;
#endif
            }
            pdf_fwd = 0.0f;
            prev->pdf_rev = 0.0f;
        }
        beta *= correct_shading_normal(vertex, vertex->wo, bs.wi, mode);
        if (!bs.specular && !russian_roulette_continues(bounce, roulette_from, beta_start_max, u_roulette, &beta)) break;
        o = offset_ray_origin(vertex->p, vertex->ng, vertex->p_error, bs.wi);
        d = bs.wi;
#ifdef HAS_MEDIA
        medium = medium_beyond(scene, vertex->material, vertex->ng, d);
#endif
    }
    return i - start;
}

/* A camera subpath's first ray through raster position `raster`, from the lens point of the
 * sample's lens draw: its origin, direction and the direction's solid-angle density (0: none). */
inline float camera_subpath_ray(const SceneData* scene, Rng* rng, float2 raster, float3* o, float3* d) {
    rng_seek(rng, SAMPLE_DRAW_LENS);
    float2 u_lens = rng_next2(rng);
    camera_generate_ray(scene->camera, raster, u_lens, o, d);
    float pdf_pos, pdf_dir;
    camera_pdf_we(scene->camera, *o, *d, &pdf_pos, &pdf_dir);
    return pdf_dir;
}

/* Camera subpath through raster position `raster`: at most max_depth + 2 vertices (the camera,
 * max_depth scattering vertices and the emitter); max_depth = -1 gives the camera vertex alone. */
inline int generate_camera_subpath(const SceneData* scene, Rng* rng, float2 raster, int max_depth, PathVertex* path) {
    float3 o, d;
    float pdf_dir = camera_subpath_ray(scene, rng, raster, &o, &d);
    PathVertex* cam = &path[0];
    *cam = vertex_at(VERTEX_CAMERA, o, (float3)(0.0f), 0.0f);
    cam->beta = (float3)(1.0f);
    if (pdf_dir == 0.0f) return 1;
    return random_walk(scene, rng, o, d, cam->beta, pdf_dir, max_depth + 1, TRANSPORT_RADIANCE,
                       sample_draw_camera_bounce(0), path, 1) + 1;
}

/* The light subpath that starts with emitted ray er from `light` (chosen with probability
 * select_pdf): at most max_depth + 1 vertices. */
__attribute__((always_inline)) inline int light_subpath_from(const SceneData* scene, Rng* rng, int max_depth,
                                                             int light, float select_pdf, const EmittedRay* emitted,
                                                             PathVertex* path) {
    const EmittedRay er = *emitted;
    int kind = scene->lights[light].kind;
    PathVertex* lv = &path[0];
    *lv = kind == LIGHT_AREA ? vertex_at(VERTEX_LIGHT, er.origin, er.n, er.origin_error)
                             : vertex_at(VERTEX_LIGHT, er.origin, (float3)(0.0f), 0.0f);
    /* The positional part of the throughput, used only when this vertex is joined straight
     * to the lens (strategy (1,1)); vertex_f then supplies the emitted radiance. */
    lv->beta = (float3)(1.0f / (select_pdf * er.pdf_pos));
    lv->pdf_fwd = er.pdf_pos * select_pdf;
    lv->light = light;
#ifdef HAS_EMISSION_TEXTURES
    /* Cosine-weighted emission leaves the front face: er.le is the unmasked radiance. */
    lv->le = er.le;
#endif
    float3 beta = er.le * (fabs(dot(er.n, er.dir)) / (select_pdf * er.pdf_pos * er.pdf_dir));
    float3 o = offset_ray_origin(lv->p, lv->ng, lv->p_error, er.dir);
    int n = random_walk(scene, rng, o, er.dir, beta, er.pdf_dir, max_depth, TRANSPORT_IMPORTANCE,
                        sample_draw_light_bounce(0), path, 1);
    if (light_is_infinite(kind)) {
        /* Infinite lights: the first hit's density is that of the bounding disk, and the light
         * vertex's own density is the direction's (seed ch. 6). */
        if (n > 0) {
            path[1].pdf_fwd = er.pdf_pos;
            /* (The disk's density is per projected area: a specular chain's entry keeps it.) */
            if (vertex_on_surface(&path[1]) && !path[1].delta) path[1].pdf_fwd *= fabs(dot(er.dir, path[1].ng));
#ifdef HAS_MEDIA
            path[1].pdf_fwd *= path[1].dist_fwd;
#endif
        }
        lv->pdf_fwd = infinite_light_density(scene, er.dir);
    }
    return n + 1;
}

/* Light subpath: at most max_depth + 1 vertices (the light and max_depth scattering vertices).
 * With aim (caustic photons alone), its emitted ray is aimed at that sphere
 * (light_emission_aimed); its densities are then no BDPT strategy's. */
inline int generate_light_subpath_aimed(const SceneData* scene, Rng* rng, int max_depth, PathVertex* path,
                                        const float4* aim) {
    rng_seek(rng, SAMPLE_DRAW_LIGHT_POSITION);
    float2 u_pos = rng_next2(rng); /* u_pos.x picks the light, its rest and u_pos.y the point */
    rng_seek(rng, SAMPLE_DRAW_LIGHT_DIRECTION);
    float2 u_dir = rng_next2(rng);
    if (scene->info->light_count == 0) return 0;
    float select_pdf, u_rest;
    int light = sample_light_index(scene, u_pos.x, &select_pdf, &u_rest);
    EmittedRay er;
    if (!light_sample_le(scene, light, (float2)(u_rest, u_pos.y), u_dir, &er)) return 0;
    if (aim && !light_emission_aimed(scene, light, (float2)(u_rest, u_pos.y), u_dir, *aim, &er)) return 0;
    return light_subpath_from(scene, rng, max_depth, light, select_pdf, &er, path);
}

inline int generate_light_subpath(const SceneData* scene, Rng* rng, int max_depth, PathVertex* path) {
    return generate_light_subpath_aimed(scene, rng, max_depth, path, 0);
}

#endif
