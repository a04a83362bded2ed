/* Test kernel: the MIS weights of all strategies that can produce one path sum to 1.
 *
 * Each work item traces a camera subpath (the real random_walk). Every prefix x_0 .. x_k that
 * ends on an emitter (an area light, or the environment for an escaped ray) is a complete path.
 * For every split (s, t), s + t = k + 1, the item rebuilds the light subpath that strategy would
 * have had — x_k .. x_t reversed, with forward densities computed from the light side and
 * reverse densities taken from the camera walk — and calls mis_weight. The weights of the
 * strategies that can produce the path (enabled, joining two non-specular vertices, and with a
 * light that emits toward the path at a density above 0) must add up to 1. With media, the
 * reversed vertices swap their segments' distance densities and the connection's are those of
 * the camera walk's segment it replaces.
 *
 * out[gid] = (largest |sum - 1| over the item's paths, number of paths checked). */
#include "connect.h"
#include "walk.h"

#ifndef MAX_DEPTH
#define MAX_DEPTH 5
#endif

/* Whether strategy (s, t) can produce the path x_0 .. x_k (its connection joins x_{t-1} and
 * x_t, and both must be non-specular; s = 0 uses no connection). */
inline int strategy_can_produce(const SceneData* scene, const StrategyMix* mix, const PathVertex* x, int s, int t,
                                int light_is_area) {
    if (!strategy_enabled(mix, s, t, light_is_area)) return 0;
    if (s == 0) return 1;
    /* x_t is the emitter itself when s = 1; its own delta flag (a specular emitter's scattering)
     * does not matter for a light vertex. */
    int emitter_is_xt = s == 1;
    return !x[t - 1].delta && (emitter_is_xt || !x[t].delta);
}

__kernel void mis_weight_sums(SCENE_KERNEL_ARGS, RenderParams params, __global float2* out) {
    int gid = get_global_id(0);
    if (gid >= params.pixel_count) return;
    uint rays = 0;
    SceneData scene = SCENE_DATA_FROM_KERNEL_ARGS(&rays);
    StrategyMix mix = strategy_mix_of(&params);
    int pixel = params.first_pixel + gid;
    Rng rng = rng_init((uint)pixel, params.sample_index, params.seed);
    float2 raster = (float2)((float)(pixel % params.width), (float)(pixel / params.width)) + rng_next2(&rng);

    PathVertex x[MAX_DEPTH + 2];
    int n = generate_camera_subpath(&scene, &rng, raster, MAX_DEPTH, x);
    mis_fill_camera_tails(&mix, x, n);
    float worst = 0.0f;
    int checked = 0;
    for (int k = 1; k < n; ++k) {
        /* A path carries light only if the emitter shines toward x_{k-1} (lights are one-sided). */
        if (!vertex_is_light(&x[k]) || is_black(vertex_le(&scene, &x[k], &x[k - 1]))) continue;
        /* The emitter as a light vertex. */
        PathVertex light0 = x[k];
        light0.type = VERTEX_LIGHT;
        light0.ns = light0.ng;
        light0.delta = 0;
        int light_is_area = vertex_light_kind(&scene, &light0) == LIGHT_AREA;

        float sum = 0.0f;
        int producers = 0;
        for (int t = 1; t <= k + 1; ++t) {
            int s = k + 1 - t;
            if (!strategy_can_produce(&scene, &mix, x, s, t, light_is_area)) continue;
            PathVertex light_path[MAX_DEPTH + 2];
            for (int j = 0; j < s; ++j) {
                PathVertex v = j == 0 ? light0 : x[k - j];
#ifdef HAS_MEDIA
                /* The segment from its light-side predecessor x_{k-j+1}, walked the other way. */
                v.dist_fwd = j == 0 ? 1.0f : x[k - j + 1].dist_rev;
                v.dist_rev = j == 0 ? 1.0f : x[k - j + 1].dist_fwd;
#endif
                /* Light-side density of this vertex, camera-side density as its reverse. */
                if (j == 0) v.pdf_fwd = vertex_pdf_light_origin(&scene, &light0, &x[k - 1]);
                else if (j == 1) v.pdf_fwd = vertex_pdf_light(&scene, &light_path[0], &v);
                else v.pdf_fwd = vertex_pdf(&scene, &light_path[j - 1], &light_path[j - 2], &v);
#ifdef HAS_MEDIA
                v.pdf_fwd *= v.dist_fwd;
#endif
                v.pdf_rev = x[k - j].pdf_fwd;
                light_path[j] = v;
            }
            /* A light that never emits toward x_{k-1} from x_k (an environment map's texel at or
             * below its mean, render/device_scene.h) leaves the path to s = 0. */
            if (s > 0 && light_path[0].pdf_fwd == 0.0f) continue;
            mis_fill_light_tails(&scene, &mix, light_path, s, light_subpath_s1_scale(&scene, light_path, s));
            /* The connection joins x_{t-1} and x_t along the walk's own segment. */
            float to_qs = 1.0f, to_pt = 1.0f;
#ifdef HAS_MEDIA
            if (s > 0 && t > 0) {
                to_qs = x[t].dist_fwd;
                to_pt = x[t].dist_rev;
            }
#endif
            PathVertex sampled;
            if (t == 1) {
                sampled = x[0];
                sampled.ng = xyz(scene.camera->forward);
                sampled.ns = sampled.ng;
            } else if (s == 1) {
                sampled = light_path[0];
            }
            float w = mis_weight(&scene, &mix, light_path, x, &sampled, s, t, to_qs, to_pt);
#ifdef MIS_TEST_DEBUG
            printf("gid %d k %d s %d t %d w %g\n", gid, k, s, t, w);
#endif
            sum += w;
            ++producers;
        }
        if (producers == 0) continue; /* e.g. the sky seen directly, for a light tracer */
        worst = fmax(worst, fabs(sum - 1.0f));
        ++checked;
    }
    out[gid] = (float2)(worst, (float)checked);
}
