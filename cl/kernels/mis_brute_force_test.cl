/* Test kernel for tests/mis_brute_force_test.cpp: mis_weight (cl/mis.h) on subpaths the host
 * builds vertex by vertex, with pdf_fwd / pdf_rev filled as random_walk and
 * generate_*_subpath would fill them. The host computes every strategy's path density in
 * double precision from its definition and compares the balance-heuristic weights.
 *
 * The vertex and case structs below are compiled both here and by the test (which includes
 * this file as C++; the kernel itself is skipped there), like kernels/layout_test.cl. */
#include "shared/types.h"

/* A path vertex in a layout both compilers agree on (PathVertex holds float3, 16 bytes on the
 * device): 4 x 16 + 8 + 16 + 8 + 16 = 112 bytes. With media (HAS_MEDIA) a vertex also has its
 * medium and the distance densities of the segment that reached it (PathVertex.dist_fwd,
 * dist_rev). */
typedef struct {
    clbdpt_float4 p, ng, ns, wo;
    float pdf_fwd, pdf_rev;
    clbdpt_int type, delta, material, light;
    float dist_fwd, dist_rev;
    clbdpt_int medium, pad0, pad1, pad2;
} TestVertex;

/* Strategy (s, t): light_path = vertices[light_offset ..] (s of them), camera_path =
 * vertices[camera_offset ..] (t of them); to_qs, to_pt: the connection's distance densities
 * toward its ends (1 in vacuum). */
typedef struct {
    clbdpt_int s, t, light_offset, camera_offset;
    float to_qs, to_pt;
    clbdpt_int pad0, pad1;
} MisCase;

#ifdef CLBDPT_DEVICE

#include "mis.h"

#define TEST_MAX_VERTICES 8

inline PathVertex path_vertex(__global const TestVertex* v) {
    PathVertex r = vertex_at(v->type, v->p.xyz, v->ng.xyz, 0.0f);
    r.ns = v->ns.xyz;
    r.wo = v->wo.xyz;
    r.beta = (float3)(1.0f);
    r.pdf_fwd = v->pdf_fwd;
    r.pdf_rev = v->pdf_rev;
    r.delta = v->delta;
    r.material = v->material;
    r.light = v->light;
#ifdef HAS_MEDIA
    r.medium = v->medium;
    r.dist_fwd = v->dist_fwd;
    r.dist_rev = v->dist_rev;
#endif
    return r;
}

/* out[i] = mis_weight of case i under the strategy mix (light_subpaths, inner_connections,
 * light_to_lens), with the freshly sampled connection vertex built exactly as
 * connect_bdpt builds it: for t = 1 the lens point (normal = the viewing direction, densities
 * 0), for s = 1 (t > 1) the light point with pdf_fwd = vertex_pdf_light_origin toward the
 * camera subpath's end. */
__kernel void mis_weight_test(SCENE_KERNEL_ARGS, __global const TestVertex* vertices, __global const MisCase* cases,
                              __global float* out, float light_subpaths, int inner_connections,
                              int light_to_lens) {
    int gid = get_global_id(0);
    uint rays = 0;
    SceneData scene = SCENE_DATA_FROM_KERNEL_ARGS(&rays);
    MisCase c = cases[gid];
    StrategyMix mix;
    mix.light_subpaths = light_subpaths;
    mix.inner_connections = inner_connections;
    mix.light_to_lens = light_to_lens;
    PathVertex light_path[TEST_MAX_VERTICES], camera_path[TEST_MAX_VERTICES];
    for (int j = 0; j < c.s; ++j) light_path[j] = path_vertex(&vertices[c.light_offset + j]);
    for (int j = 0; j < c.t; ++j) camera_path[j] = path_vertex(&vertices[c.camera_offset + j]);
    mis_fill_light_tails(&scene, &mix, light_path, c.s, light_subpath_s1_scale(&scene, light_path, c.s));
    mis_fill_camera_tails(&mix, camera_path, c.t);
    PathVertex sampled;
    if (c.t == 1) {
        sampled = camera_path[0];
        sampled.type = VERTEX_CAMERA;
        sampled.ng = xyz(scene.camera->forward);
        sampled.ns = sampled.ng;
        sampled.pdf_fwd = 0.0f;
        sampled.pdf_rev = 0.0f;
        sampled.delta = 0;
        sampled.light = -1;
    } else if (c.s == 1) {
        sampled = light_path[0];
        sampled.type = VERTEX_LIGHT;
        sampled.delta = 0;
        sampled.pdf_rev = 0.0f;
        sampled.pdf_fwd = vertex_pdf_light_origin(&scene, &sampled, &camera_path[c.t - 1]);
    }
    out[gid] = mis_weight(&scene, &mix, light_path, camera_path, &sampled, c.s, c.t, c.to_qs, c.to_pt);
}

#endif
