/* One BDPT sample per work item: a camera subpath through the item's pixel, a light subpath,
 * and every enabled (s, t) connection between them (seed ch. 4-5). Camera-side contributions
 * go to the item's own pixel (camera_out, whose w holds the number of rays the item traced);
 * t = 1 contributions land elsewhere and are written as splat records in fixed slots (s - 1),
 * which the host adds in slot order, so the image does not depend on the order the items ran.
 *
 * Specialised per scene by -D flags (host/render/features.cpp): MAX_DEPTH, INTEGRATOR and
 * HAS_* for the light, material and camera features present.
 *
 * A contribution that is not finite is a bug; the item then reports the first strategy that
 * gave one, as camera_out.w = -1 - (s * STRATEGY_STRIDE + t) instead of its ray count, and the
 * host drops the whole sample (host/render/renderer.cpp). DEBUG_NAN_PIXEL (tests only) makes
 * that pixel's sample 0 give one. */
#include "connect.h"
#include "walk.h"
#ifdef HAS_CAUSTIC_MERGING
#include "caustic_merging.h"
#endif

#ifndef MAX_DEPTH
#define MAX_DEPTH 5
#endif

/* The path tracer makes its connections as its one subpath grows (cl/path_tracer.h), except
 * for per-strategy images and PT_FROM_SUBPATHS (tests and benchmarks: the generic route below,
 * to compare with). */
#if INTEGRATOR == INTEGRATOR_PT && !defined(STRATEGY_IMAGES) && !defined(PT_FROM_SUBPATHS)
#define PT_ONE_VERTEX_AT_A_TIME 1
#include "path_tracer.h"
#else
#define PT_ONE_VERTEX_AT_A_TIME 0
#endif

/* Splat records per item: one per light subpath vertex. A path tracer has no t = 1 strategy,
 * so nothing of its lands elsewhere: it has none (the host sizes the buffer the same way). */
#if INTEGRATOR == INTEGRATOR_PT
#define SPLAT_SLOTS 0
#else
#define SPLAT_SLOTS (MAX_DEPTH + 1)
#endif

/* --strategy-images: every (s, t) contribution is also recorded in its own slot
 * s * STRATEGY_STRIDE + t (own pixel for t > 1, the splat's for t = 1). */
#define STRATEGY_SLOTS ((MAX_DEPTH + 2) * STRATEGY_STRIDE)

/* The sample vector of sample sample_index of `seed` at pixel `pixel` (row-major). */
inline Rng pixel_sample_rng(const RenderParams* params, int pixel, uint sample_index, uint seed) {
#ifdef SAMPLER_ZSOBOL
    return rng_init_zsobol((uint)(pixel % params->width), (uint)(pixel / params->width), sample_index, seed,
                           params->zsobol_log2_spp, params->zsobol_base4_digits);
#else
    return rng_init((uint)pixel, sample_index, seed);
#endif
}

__kernel void render_bdpt(SCENE_KERNEL_ARGS, RenderParams params, __global float4* camera_out,
                          __global SplatRecord* splats, __global const int* run_pixels,
                          __global float2* subset_moments
#ifdef HAS_CAUSTIC_MERGING
                          , __global const CausticPhoton* photons, __global const uint* merge_cells,
                          __global const MergeSlice* merge_slices, uint merge_slice_count
#endif
#ifdef STRATEGY_IMAGES
                          , __global SplatRecord* strategy_records
#endif
) {
    int gid = get_global_id(0);
    if (gid >= params.pixel_count) return;
    uint rays_traced = 0;
    SceneData scene = SCENE_DATA_FROM_KERNEL_ARGS(&rays_traced);
    scene.roulette_camera_from = params.roulette_camera_from;
    scene.roulette_light_from = params.roulette_light_from;

    int item = params.first_pixel + gid;
    int pixel = params.run_listed ? run_pixels[params.run_pixel + item % params.run_length]
                                  : launch_item_pixel(item, params.width, params.height, params.pixel_stride,
                                                      params.run_pixel, params.run_length);
    /* A run's items go through its pixels once per sample. */
    uint run_sample = params.run_length > 0 ? (uint)(item / params.run_length) : 0u;
    uint sample_index = params.sample_index + run_sample;
    uint position_sample_index = params.position_sample_index + run_sample;
    int px = pixel % params.width, py = pixel / params.width;
    /* The whole sample, both subpaths and every connection, draws from the pixel's own sample
     * vector at the draws cl/sample_dimensions.h assigns. */
    Rng rng = pixel_sample_rng(&params, pixel, sample_index, params.seed);
    /* Only the strategy pilot's passes draw the pixel position from another sample than the
     * rest (host/render/strategy_pilot.cpp); every other pass takes both from one stream, so
     * it sets up one. */
    Rng position_rng = rng;
    if (params.position_seed != params.seed || params.position_sample_index != params.sample_index)
        position_rng = pixel_sample_rng(&params, pixel, position_sample_index, params.position_seed);
    rng_seek(&position_rng, SAMPLE_DRAW_PIXEL);
    float2 raster = (float2)((float)px, (float)py) + rng_next2(&position_rng);
#if PT_ONE_VERTEX_AT_A_TIME
    PathTracerSum sum;
    sum.L = (float3)(0.0f);
    sum.bad_strategy = -1;
#ifdef DEBUG_NAN_PIXEL
    sum.poisoned = pixel == DEBUG_NAN_PIXEL && sample_index == 0;
#endif
    path_tracer_sample(&scene, &rng, raster, &sum);
    camera_out[gid] = (float4)(sum.L.x, sum.L.y, sum.L.z,
                               sum.bad_strategy < 0 ? (float)rays_traced : -1.0f - (float)sum.bad_strategy);
#else
    StrategyMix mix = strategy_mix_of(&params);

    PathVertex camera_path[MAX_DEPTH + 2];
    PathVertex light_path[MAX_DEPTH + 1];
    /* Each strategy set traces only the subpaths it uses: a light tracer joins light vertices to
     * freshly sampled lens points (t = 1), so its camera subpath is the camera vertex alone, and
     * no t = 1 connection reads even that (connect_bdpt and mis_weight use the sampled lens
     * point): it is left unset (1.7% of a light tracer's time on lamp-ceiling went to making it);
     * a path tracer samples a fresh light point for s = 1 and needs no light subpath. */
#if INTEGRATOR == INTEGRATOR_LT
    int n_camera = 1;
#else
    int n_camera = generate_camera_subpath(&scene, &rng, raster, MAX_DEPTH, camera_path);
#endif
#if INTEGRATOR == INTEGRATOR_PT
    int n_light = 0; /* s = 0 and s = 1 only; light_path is never read */
    int light_is_area = 0;
    float light_s1_scale = 1.0f;
#else
    /* A fraction of light subpaths per pixel sample is a probability (cl/strategies.h). */
    int n_light = 0;
    rng_seek(&rng, SAMPLE_DRAW_TRACE_LIGHT_SUBPATH);
    if (rng_next(&rng) < mix.light_subpaths && !(params.camera_image_only && !mix.inner_connections))
        n_light = generate_light_subpath(&scene, &rng, MAX_DEPTH, light_path);
    int light_is_area = n_light > 0 && lights[light_path[0].light].kind == LIGHT_AREA;
    mis_fill_camera_tails(&mix, camera_path, n_camera);
    float light_s1_scale = light_subpath_s1_scale(&scene, light_path, n_light);
    mis_fill_light_tails(&scene, &mix, light_path, n_light, light_s1_scale);
#endif

    __global SplatRecord* my_splats = splats + (size_t)gid * SPLAT_SLOTS;
    for (int k = 0; k < SPLAT_SLOTS; ++k) my_splats[k].pixel = -1;

#ifdef STRATEGY_IMAGES
    __global SplatRecord* my_strategies = strategy_records + (size_t)gid * STRATEGY_SLOTS;
    for (int k = 0; k < STRATEGY_SLOTS; ++k) my_strategies[k].pixel = -1;
#endif

    float3 L = (float3)(0.0f);
    int bad_strategy = -1;
    /* params.subset_moments (the strategy pilot's passes of full bdpt): the sum of the sample's
     * squared contributions (summed over the channels) and the same with each divided by the
     * share of its MIS weights that the outer strategies have (cl/mis.h): an estimate of the
     * sum that a mix without inner connections would have for the same paths, which sees the
     * paths that such a mix samples rarely and so its own passes miss. */
    float2 moments = (float2)(0.0f);
    float outer_share = 1.0f;
#ifdef HAS_CAUSTIC_MERGING
    /* The pass's photons (its slice) stand in for s = 0 on caustics seen through specular
     * vertices (cl/caustic_merging.h); a non-finite estimate is reported as strategy 0. */
    {
        CausticMap merge_map = {photons, merge_cells, merge_slices};
        L = caustic_merges(&scene, &merge_map, sample_index % merge_slice_count, camera_path, n_camera);
        float probe = L.x + L.y + L.z;
        if (probe - probe != 0.0f) bad_strategy = 0;
    }
#endif
    for (int t = 1; t <= n_camera; ++t) {
        /* s = 1 with t >= 2 samples its own light point: it needs no light subpath. */
        for (int s = 0; s <= max(n_light, 1); ++s) {
            int depth = s + t - 2;
            if (depth < 0 || depth > MAX_DEPTH) continue;
            if (strategy_uses_light_subpath(s, t) && s > n_light) continue;
            if (!strategy_enabled(&mix, s, t, light_is_area)) continue;
            /* s = 1 may take several light samples (connection_light_samples, cl/connect.h). */
            int light_samples = connection_light_samples(&scene, s, t);
            for (int g = 0; g < light_samples; ++g) {
                float2 splat_raster;
                float weight;
                float3 unweighted = connect_bdpt(&scene, &mix, &rng, light_path, camera_path, s, t, g, light_s1_scale,
                                                 &splat_raster, &weight, params.subset_moments ? &outer_share : 0);
#ifdef DEBUG_NAN_PIXEL
                /* Every strategy the sample tries, whether or not its connection carries light. */
                if (pixel == DEBUG_NAN_PIXEL && sample_index == 0) unweighted = (float3)(NAN);
#endif
                if (is_black(unweighted)) continue;
                /* Divided by the strategy's samples per pixel sample (its light subpath may be
                 * traced for only a fraction of the samples). */
                float3 c = unweighted * (weight / strategy_sample_count(&mix, s, t));
                /* NaN or Inf in any channel makes the difference NaN (isfinite on each channel
                 * cost PoCL 15% of a path tracer's samples per second). */
                float probe = c.x + c.y + c.z;
                if (probe - probe != 0.0f && bad_strategy < 0) bad_strategy = s * STRATEGY_STRIDE + t;
                if (params.subset_moments) {
                    float squared = c.x * c.x + c.y * c.y + c.z * c.z;
                    moments.x += squared;
                    /* A share of 0: the mix cannot make the path at all (a delta light by way of
                     * a mirror; the pilot leaves that mix out there). */
                    if (outer_share > 0.0f) moments.y += squared / outer_share;
                }
                int target = pixel;
                if (t == 1) {
                    int sx = min((int)splat_raster.x, params.width - 1);
                    int sy = min((int)splat_raster.y, params.height - 1);
                    target = sy * params.width + sx;
                    __global SplatRecord* rec = &my_splats[s - 1];
                    rec->r = c.x;
                    rec->g = c.y;
                    rec->b = c.z;
                    rec->pixel = target;
                } else {
                    L += c;
                }
#ifdef STRATEGY_IMAGES
                __global SplatRecord* srec = &my_strategies[s * STRATEGY_STRIDE + t];
#ifdef STRATEGY_IMAGES_UNWEIGHTED
                float3 shown = unweighted;
#else
                float3 shown = c;
#endif
                if (srec->pixel == target) { /* another light group's sample of this (s, t) */
                    srec->r += shown.x;
                    srec->g += shown.y;
                    srec->b += shown.z;
                } else {
                    srec->r = shown.x;
                    srec->g = shown.y;
                    srec->b = shown.z;
                    srec->pixel = target;
                }
#endif
            }
        }
    }
#ifdef DEBUG_NAN_PIXEL
    /* A sample that tried no strategy (its camera ray left the scene past mirrors): its camera
     * image, reported as s = 0 with t = the camera subpath's vertices. */
    if (pixel == DEBUG_NAN_PIXEL && sample_index == 0 && bad_strategy < 0) {
        L = (float3)(NAN);
        bad_strategy = n_camera;
    }
#endif
    camera_out[gid] = (float4)(L.x, L.y, L.z, bad_strategy < 0 ? (float)rays_traced : -1.0f - (float)bad_strategy);
    if (params.subset_moments) subset_moments[gid] = moments;
#endif
}

#ifdef HAS_CAUSTIC_MERGING
/* The caustic photons of passes first_slice, first_slice + 1, ...: item i (first_item + the work
 * item's index) traces light subpath i % paths_per_slice of pass first_slice + i / paths_per_slice
 * from its own sample sequence, as far as its first non-specular vertex, and appends that vertex
 * to out if it is a caustic photon (cl/caustic_merging.h), with i in beta.w's bits: the host
 * orders them by it, so the order the items ran in does not matter. *count holds the number
 * appended. aim: the sphere (xyz centre, w radius) that bounds every mirror and glass triangle;
 * the subpaths' emitted rays are aimed at it (light_emission_aimed). */
__kernel void trace_caustic_photons(SCENE_KERNEL_ARGS, uint paths_per_slice, uint first_slice, uint first_item,
                                    uint item_count, uint seed, __global CausticPhoton* out,
                                    __global volatile uint* count, float4 aim) {
    if (get_global_id(0) >= item_count) return;
    uint item = first_item + (uint)get_global_id(0);
    uint rays_traced = 0;
    SceneData scene = SCENE_DATA_FROM_KERNEL_ARGS(&rays_traced);
    scene.walk_ends_at_scattering = 1;
    Rng rng = rng_init(item % paths_per_slice, first_slice + item / paths_per_slice, seed ^ 0x63a9f1d5u);
    PathVertex light_path[MAX_DEPTH + 1];
    /* Aimed at the sphere about every mirror and glass triangle, which a caustic photon's first
     * hit lies on (the host's CausticPhotons). */
    int n_light = generate_light_subpath_aimed(&scene, &rng, MAX_DEPTH, light_path, &aim);
    int m = caustic_photon_vertex(&scene, light_path, n_light);
    if (m == 0) return;
    const PathVertex* v = &light_path[m];
    CausticPhoton ph;
    ph.p = (float4)(v->p, (float)m);
    ph.ng = (float4)(v->ng, 0.0f);
    ph.wi = (float4)(v->wo, 0.0f);
    ph.beta = (float4)(v->beta, as_float(item));
    out[atomic_inc(count)] = ph;
}
#endif
