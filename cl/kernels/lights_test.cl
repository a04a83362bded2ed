/* Test kernels for cl/lights.h (tests/lights_test.cpp): Sample_Li, Sample_Le, their pdfs
 * evaluated separately, the environment pdf at given directions and light selection, on the
 * scene arguments every light-transport kernel takes. Build with the scene's kernel_defines. */
#include "lights.h"
#include "rng.h"

/* One light_sample_li per item from `ref`. Per item, four float4:
 *   (wi, pdf_w), (p, returned value), (n, the same density evaluated separately), (li, 0)
 * The separate density: light_pdf_li_area for area lights, environment_pdf_w for the
 * environment, 1 for delta lights (their pdf_w is a convention). */
__kernel void light_li_test(SCENE_KERNEL_ARGS, int light, float4 ref, uint seed, __global float4* out) {
    int gid = get_global_id(0);
    uint rays = 0;
    SceneData scene = SCENE_DATA_FROM_KERNEL_ARGS(&rays);
    Rng rng = rng_init((uint)gid, 0u, seed);
    float2 u = rng_next2(&rng);
    LightSample ls;
    ls.p = (float3)(0.0f);
    ls.wi = (float3)(0.0f);
    int ok = light_sample_li(&scene, light, ref.xyz, u, &ls);
    float pdf_eval = 1.0f;
    int kind = lights[light].kind;
    if (kind == LIGHT_AREA) pdf_eval = light_pdf_li_area(&lights[light], ref.xyz, ls.p, ls.n);
#ifdef HAS_ENVIRONMENT
    if (kind == LIGHT_ENVIRONMENT) pdf_eval = environment_pdf_w(&scene, ls.wi);
#endif
    out[4 * gid] = (float4)(ls.wi, ls.pdf_w);
    out[4 * gid + 1] = (float4)(ls.p, (float)ok);
    out[4 * gid + 2] = (float4)(ls.n, pdf_eval);
    out[4 * gid + 3] = (float4)(ls.li, 0.0f);
}

/* One light_sample_le per item. Per item, five float4:
 *   (origin, pdf_pos), (dir, pdf_dir), (n, returned value), (le, 0),
 *   (light_pdf_le(n, dir): pdf_pos, pdf_dir, 0, 0) */
__kernel void light_le_test(SCENE_KERNEL_ARGS, int light, uint seed, __global float4* out) {
    int gid = get_global_id(0);
    uint rays = 0;
    SceneData scene = SCENE_DATA_FROM_KERNEL_ARGS(&rays);
    Rng rng = rng_init((uint)gid, 0u, seed);
    float2 u_pos = rng_next2(&rng), u_dir = rng_next2(&rng);
    EmittedRay er;
    er.origin = (float3)(0.0f);
    er.dir = (float3)(0.0f);
    er.n = (float3)(0.0f);
    int ok = light_sample_le(&scene, light, u_pos, u_dir, &er);
    float pdf_pos = 0.0f, pdf_dir = 0.0f;
    light_pdf_le(&scene, light, er.n, er.dir, &pdf_pos, &pdf_dir);
    out[5 * gid] = (float4)(er.origin, er.pdf_pos);
    out[5 * gid + 1] = (float4)(er.dir, er.pdf_dir);
    out[5 * gid + 2] = (float4)(er.n, (float)ok);
    out[5 * gid + 3] = (float4)(er.le, 0.0f);
    out[5 * gid + 4] = (float4)(pdf_pos, pdf_dir, 0.0f, 0.0f);
}

/* environment_pdf_w and environment_radiance at given directions: out[i] = (pdf_w, L). */
__kernel void environment_eval_test(SCENE_KERNEL_ARGS, __global const float4* dirs, __global float4* out) {
    int gid = get_global_id(0);
    uint rays = 0;
    SceneData scene = SCENE_DATA_FROM_KERNEL_ARGS(&rays);
    float3 w = dirs[gid].xyz;
#ifdef HAS_ENVIRONMENT
    out[gid] = (float4)(environment_pdf_w(&scene, w), environment_radiance(&scene, w));
#else
    out[gid] = (float4)(0.0f);
#endif
}

/* sample_light_index on counter-based u: out[i] = (index, reported select_pdf). */
__kernel void light_select_test(SCENE_KERNEL_ARGS, uint seed, __global float2* out) {
    int gid = get_global_id(0);
    uint rays = 0;
    SceneData scene = SCENE_DATA_FROM_KERNEL_ARGS(&rays);
    Rng rng = rng_init((uint)gid, 0u, seed);
    float select_pdf = 0.0f, u_rest;
    int i = sample_light_index(&scene, rng_next(&rng), &select_pdf, &u_rest);
    out[gid] = (float2)((float)i, select_pdf);
}

/* sample_light_for_point from point x on counter-based u: out[i] = (index, reported
 * probability, light_sample_selection_ratio of that light at x, 0). */
__kernel void light_select_at_point_test(SCENE_KERNEL_ARGS, uint seed, float4 x, __global float4* out) {
    int gid = get_global_id(0);
    uint rays = 0;
    SceneData scene = SCENE_DATA_FROM_KERNEL_ARGS(&rays);
    Rng rng = rng_init((uint)gid, 0u, seed);
    float select_pdf = 0.0f, u_rest;
    int i = sample_light_for_point(&scene, x.xyz, rng_next(&rng), &select_pdf, &u_rest);
    float ratio = i >= 0 ? light_sample_selection_ratio(&scene, i, x.xyz) : 0.0f;
    out[gid] = (float4)((float)i, select_pdf, ratio, 0.0f);
}

/* What a light choice leaves of its draw (rest_of_choice), on the evenly spaced draws
 * u = (i + 1/2) / n: out[i] = (light picked by power, its rest, light a sample from x picks
 * (with NEE_EVERY_LIGHT: among the area lights, group 0), its rest). */
__kernel void light_choice_rest_test(SCENE_KERNEL_ARGS, uint n, float4 x, __global float4* out) {
    int gid = get_global_id(0);
    uint rays = 0;
    SceneData scene = SCENE_DATA_FROM_KERNEL_ARGS(&rays);
    float u = ((float)gid + 0.5f) / (float)n;
    float select_pdf, rest_by_power, rest_at_point;
    int by_power = sample_light_index(&scene, u, &select_pdf, &rest_by_power);
#ifdef NEE_EVERY_LIGHT
    int at_point = nee_group_light(&scene, 0, x.xyz, u, &select_pdf, &rest_at_point);
#else
    int at_point = sample_light_for_point(&scene, x.xyz, u, &select_pdf, &rest_at_point);
#endif
    out[gid] = (float4)((float)by_power, rest_by_power, (float)at_point, rest_at_point);
}

#ifdef NEE_EVERY_LIGHT
/* The light samples of every light group from point x on counter-based u_light: out[4 i + g] =
 * (light of group g, its reported probability, light_sample_selection_ratio of that light at
 * x, group count); groups beyond the scene's are left alone. */
__kernel void light_groups_at_point_test(SCENE_KERNEL_ARGS, uint seed, float4 x, __global float4* out) {
    int gid = get_global_id(0);
    uint rays = 0;
    SceneData scene = SCENE_DATA_FROM_KERNEL_ARGS(&rays);
    Rng rng = rng_init((uint)gid, 0u, seed);
    float u_light = rng_next(&rng);
    int groups = nee_group_count(&scene);
    for (int g = 0; g < min(groups, 4); ++g) {
        float pick_pdf = 0.0f, u_rest;
        int i = nee_group_light(&scene, g, x.xyz, u_light, &pick_pdf, &u_rest);
        float ratio = i >= 0 ? light_sample_selection_ratio(&scene, i, x.xyz) : 0.0f;
        out[4 * gid + g] = (float4)((float)i, pick_pdf, ratio, (float)groups);
    }
}
#endif
