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
 * With media (cl/medium.h) a segment may end in a medium vertex, whose phase function takes the
 * BSDF's place, and a light sample's visibility is the segment's transmittance, whose distance
 * density toward the light point enters the ratio as random_walk's and mis_weight's do.
 * --strategy-images keeps the generic route (render.cl). */
#ifndef CLBDPT_PATH_TRACER_H
#define CLBDPT_PATH_TRACER_H

#include "mis.h"
#include "walk.h"

/* Whether the scene's lights are all delta lights (point, spot, directional): then no ray can
 * hit an emitter, so s = 0 never adds anything, and s = 1 is the only strategy for every path
 * (its weight is 1). The walk then needs no densities at all: not the forward density of each
 * vertex (one BSDF density evaluation per bounce, for s = 0's weight), nor the light's origin
 * density (for s = 1's). The images are the same bit for bit; only unused values go. */
#if !defined(HAS_AREA_LIGHTS) && !defined(HAS_ENVIRONMENT)
#define PT_DELTA_LIGHTS_ONLY 1
#else
#define PT_DELTA_LIGHTS_ONLY 0
#endif

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

/* s = 1 at the path's t-th vertex v: a light point sampled from v on `light` (taken with
 * probability select_pdf; -1: none) with draw u and joined to it, weighted against s = 0 (the
 * same path found by sampling v's BSDF toward the light point; p_0 / p_1 = its area density
 * over the light's origin density; weight 1 for a delta light). b: v's BSDF (unused at a
 * medium vertex). */
inline float3 path_tracer_light_sample(const SceneData* scene, const Rng* rng, int t, int light, float select_pdf,
                                       float2 u, const PathVertex* prev, const PathVertex* v, const Bsdf* b) {
    LightSample ls;
    if (light < 0 || !light_sample_li(scene, light, v->p, u, &ls)) return (float3)(0.0f);
    PathVertex sampled = vertex_at(VERTEX_LIGHT, ls.p, ls.n, ls.p_error);
    sampled.beta = ls.li / (ls.pdf_w * select_pdf);
    sampled.light = light;
    float3 wi;
#ifdef HAS_MEDIA
    int in_medium = v->type == VERTEX_MEDIUM;
    float3 f = in_medium ? vertex_f(scene, v, &sampled, TRANSPORT_RADIANCE)
                         : surface_vertex_f(v, b, &sampled, TRANSPORT_RADIANCE, &wi);
#else
    float3 f = surface_vertex_f(v, b, &sampled, TRANSPORT_RADIANCE, &wi);
#endif
    float3 L = v->beta * f * sampled.beta;
    L *= surface_cosine_or_one(v, v->ns, ls.wi);
#ifdef HAS_MEDIA
    /* connect_bdpt's s = 1 with its stream: transmittance, and the distance densities. */
    if (is_black(L)) return (float3)(0.0f);
    float to_v, to_light;
    L *= vertices_transmittance(scene, rng, connection_stream(1, t), v, &sampled, &to_v, &to_light);
    if (is_black(L)) return (float3)(0.0f);
#else
    if (is_black(L) || !vertices_visible(scene, v, &sampled)) return (float3)(0.0f);
#endif
    if (PT_DELTA_LIGHTS_ONLY || vertex_is_delta_light(scene, &sampled)) return L;
    sampled.pdf_fwd = vertex_pdf_light_origin(scene, &sampled, v);
#ifdef HAS_MEDIA
    float pdf_bsdf = in_medium ? vertex_pdf(scene, v, prev, &sampled)
                               : surface_vertex_pdf(scene, v, b, prev, &sampled, wi);
    pdf_bsdf *= to_light;
#else
    float pdf_bsdf = surface_vertex_pdf(scene, v, b, prev, &sampled, wi);
#endif
    float ratio = mis_ratio(pdf_bsdf, 0, sampled.pdf_fwd, 0);
#ifdef NEE_OWN_SELECTION
    ratio /= light_sample_selection_ratio(scene, light, v->p); /* sampled.pdf_fwd has select_pdf */
#endif
    return L * (1.0f / (1.0f + ratio));
}

/* The s = 1 strategy samples at the path's vertex v (draw u: u.x picks the light, its rest and
 * u.y the point): one light sample, or with NEE_EVERY_LIGHT one of each light group
 * (cl/lights.h), each added on its own. */
inline void path_tracer_light_samples(const SceneData* scene, const Rng* rng, float2 u, const PathVertex* prev,
                                      const PathVertex* v, const Bsdf* b, int t, PathTracerSum* sum) {
    if (!vertex_is_connectible(scene, v) || scene->info->light_count == 0) return;
    float select_pdf, u_rest;
#ifdef NEE_EVERY_LIGHT
    int groups = nee_group_count(scene);
    for (int g = 0; g < groups; ++g) {
        int light = nee_group_light(scene, g, v->p, u.x, &select_pdf, &u_rest);
        float3 c = path_tracer_light_sample(scene, rng, t, light, select_pdf, (float2)(u_rest, u.y), prev, v, b);
        path_tracer_add(sum, c, 1, t);
    }
#else
    int light = sample_light_for_point(scene, v->p, u.x, &select_pdf, &u_rest);
    float3 c = path_tracer_light_sample(scene, rng, t, light, select_pdf, (float2)(u_rest, u.y), prev, v, b);
    path_tracer_add(sum, c, 1, t);
#endif
}

/* One path tracer sample through raster position `raster`: the camera subpath of cl/walk.h
 * (generate_camera_subpath, random_walk in radiance mode) with its s = 0 and s = 1
 * connections made at each vertex, added into *sum (L 0 and bad_strategy -1 on entry). */
inline void path_tracer_sample(const SceneData* scene, Rng* rng, float2 raster, PathTracerSum* sum) {
    /* The camera ray alone, without its density (camera_subpath_ray): that is vertex 1's
     * forward density, which no weight here reads (an emitter seen straight from the camera has
     * no other pt strategy), and whose film test (camera_raster_of) only dropped the rare sample
     * that rounding put just past the film's last row or column. */
    float3 o, d;
    rng_seek(rng, SAMPLE_DRAW_LENS);
    camera_generate_ray(scene->camera, raster, rng_next2(rng), &o, &d);
    float pdf_fwd = 0.0f;
    PathVertex prev = vertex_at(VERTEX_CAMERA, o, (float3)(0.0f), 0.0f);
    prev.beta = (float3)(1.0f);
    /* The BSDF of each surface vertex, made once: its light samples, its bounce and the next
     * vertex's forward density all read it (from prev_bsdf at the next vertex). */
    Bsdf prev_bsdf;
    float3 beta = prev.beta;
#ifdef HAS_MEDIA
    int medium = vertex_medium_toward(scene, &prev, d);
    /* The next segment's distance draw: the camera ray's here, the others' with each vertex's
     * draws (below). */
    rng_seek(rng, sample_draw_camera_bounce(0) + SAMPLE_DRAW_BOUNCE_DISTANCE);
    float2 u_distance = rng_next2(rng);
#endif
    /* Vertex i of the camera subpath (the camera is vertex 0), so its strategies have t = i + 1
     * camera vertices; the last, i = MAX_DEPTH + 1, can only be an emitter hit (s = 0). */
    for (int i = 1; i <= MAX_DEPTH + 1 && !is_black(beta); ++i) {
        PathVertex v;
#ifdef HAS_MEDIA
        /* random_walk's segment through media, from the same distance draw. */
        SegmentTally tally;
        uint distance_draw = sample_draw_camera_bounce(i - 1) + SAMPLE_DRAW_BOUNCE_DISTANCE;
        if (walk_segment(scene, rng, distance_draw, u_distance, &prev, &o, d, &medium, &v, &tally) == SEGMENT_LOST) {
#else
        Hit hit;
        ++*scene->rays_traced;
        if (intersect(scene->nodes, scene->triangles, &scene->cutouts, o, d, INFINITY, &hit)) {
            surface_vertex_from_hit(scene, &prev, &hit, &v);
        } else {
#endif
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
#ifdef HAS_MEDIA
        if (!walk_segment_throughput(scene, &tally, &v, &beta)) break;
#endif
        v.beta = beta;
        int t = i + 1;
        /* The forward density from the positions, as random_walk (cl/walk.h says why), and the
         * emitter the vertex may be: neither with delta lights only (the condition is constant). */
        if (!PT_DELTA_LIGHTS_ONLY) {
            if (i > 1) { /* vertex 1's is never read (above, at the camera ray) */
                if (!prev.delta) {
                    float3 w = direction_from(&prev, &v);
#ifdef HAS_MEDIA
                    pdf_fwd = prev.type == VERTEX_MEDIUM ? vertex_scatter_pdf(scene, &prev, prev.wo, w)
                                                         : bsdf_pdf(&prev_bsdf, prev.wo, w);
#else
                    pdf_fwd = bsdf_pdf(&prev_bsdf, prev.wo, w);
#endif
                }
                v.pdf_fwd = convert_density(scene, &prev, pdf_fwd, &v);
#ifdef HAS_MEDIA
                v.pdf_fwd *= v.dist_fwd;
#endif
            }
            if (vertex_is_light(&v)) path_tracer_add(sum, path_tracer_emitter_hit(scene, &prev, &v, t), 0, t);
        }
        if (v.type == VERTEX_LIGHT || i == MAX_DEPTH + 1) break;
        /* The vertex's draws (cl/sample_dimensions.h), all at once: the light sample's (light
         * and point) for s = 1 and the bounce's (lobe and Russian roulette, direction); the
         * fourth lane is the next segment's distance draw with media, else it repeats one. */
        uint light_draw = sample_draw_light_connection(t), bounce_draw = sample_draw_camera_bounce(i - 1);
#ifdef HAS_MEDIA
        uint fourth_draw = sample_draw_camera_bounce(i) + SAMPLE_DRAW_BOUNCE_DISTANCE;
#else
        uint fourth_draw = bounce_draw + 1u;
#endif
        float4 ux, uy;
        rng_draws4(rng, (uint4)(light_draw, bounce_draw, bounce_draw + 1u, fourth_draw), &ux, &uy);
#ifdef HAS_MEDIA
        u_distance = (float2)(ux.s3, uy.s3);
        if (v.type == VERTEX_MEDIUM) {
            path_tracer_light_samples(scene, rng, (float2)(ux.s0, uy.s0), &prev, &v, 0, t, sum);
            float3 wi;
            pdf_fwd = walk_scatter_in_medium(scene, &v, (float2)(ux.s2, uy.s2), &wi, &beta);
            if (!russian_roulette_continues(i - 1, scene->roulette_camera_from, 1.0f, uy.s1, &beta)) break;
            o = v.p;
            d = wi;
            prev = v;
            continue;
        }
#endif
        Bsdf b = vertex_bsdf(scene, &v);
        path_tracer_light_samples(scene, rng, (float2)(ux.s0, uy.s0), &prev, &v, &b, t, sum);

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
#ifdef HAS_MEDIA
        medium = medium_beyond(scene, v.material, v.ng, d);
#endif
        prev = v;
        prev_bsdf = b;
    }
}

#endif
