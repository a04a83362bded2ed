/* Ray-casting entry points for the BVH tests (tests/bvh_test.cpp) and the traversal benchmark
 * (host/bench/traversal_bench.cpp). One ray per work item. */
#include "shared/types.h"
#include "ray.h"
#include "bvh.h"

/* Closest hit. ray_o: origin, w = tmax; ray_d: direction (w unused). out: (t, b1, b2,
 * as_float(triangle)), triangle = -1 and t = tmax on a miss. */
__kernel void trace_closest(__global const BvhNode* nodes, __global const TriangleRows* tris,
                            __global const float4* ray_o, __global const float4* ray_d,
                            __global float4* out, int count) {
    int i = get_global_id(0);
    if (i >= count) return;
    float4 o = ray_o[i];
    float4 d = ray_d[i];
    Hit hit;
    intersect(nodes, tris, 0, o.xyz, d.xyz, o.w, &hit);
    out[i] = (float4)(hit.t, hit.b1, hit.b2, as_float(hit.triangle));
}

/* Any hit: occluded[i] = 1 if something is hit with t in (0, tmax), else 0. */
__kernel void trace_any(__global const BvhNode* nodes, __global const TriangleRows* tris,
                        __global const float4* ray_o, __global const float4* ray_d,
                        __global int* occluded_out, int count) {
    int i = get_global_id(0);
    if (i >= count) return;
    float4 o = ray_o[i];
    float4 d = ray_d[i];
    occluded_out[i] = occluded(nodes, tris, 0, o.xyz, d.xyz, o.w) ? 1 : 0;
}
