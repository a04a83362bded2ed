/* Ray-casting entry points for the BVH tests (tests/bvh_test.cpp) and the traversal benchmark
 * (host/bench/traversal_bench.cpp). One ray per work item. */
#include "shared/types.h"
#include "ray.h"
#include "bvh.h"

/* Closest hit. ray_o: origin, w = tmax; ray_d: direction (w unused). out: (t, b1, b2,
 * as_float(triangle)), triangle = -1 and t = tmax on a miss. */
__kernel void trace_closest(__global const BvhNode* nodes, __global const Triangle* tris,
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
__kernel void trace_any(__global const BvhNode* nodes, __global const Triangle* tris,
                        __global const float4* ray_o, __global const float4* ray_d,
                        __global int* occluded_out, int count) {
    int i = get_global_id(0);
    if (i >= count) return;
    float4 o = ray_o[i];
    float4 d = ray_d[i];
    occluded_out[i] = occluded(nodes, tris, 0, o.xyz, d.xyz, o.w) ? 1 : 0;
}

#include "bvh_packet.h"

/* EXPERIMENT: 8 rays per work item, one packet traversal (cl/bvh_packet.h). Rays 8i .. 8i + 7;
 * a short last packet repeats its last ray. */
__kernel void trace_closest_packet(__global const BvhNode* nodes, __global const Triangle* tris,
                                   __global const float4* ray_o, __global const float4* ray_d,
                                   __global float4* out, int count) {
    int first = get_global_id(0) * 8;
    if (first >= count) return;
    float3 o[8], d[8];
    float tm[8];
    for (int j = 0; j < 8; ++j) {
        int k = min(first + j, count - 1);
        float4 a = ray_o[k], b = ray_d[k];
        o[j] = a.xyz, d[j] = b.xyz, tm[j] = a.w;
    }
    PacketRay r = packet_ray(o, d);
    float8 t, b1, b2;
    int8 tri;
    packet_intersect(nodes, tris, &r, vload8(0, tm), &t, &b1, &b2, &tri);
    float ts[8], b1s[8], b2s[8];
    int tris_[8];
    vstore8(t, 0, ts), vstore8(b1, 0, b1s), vstore8(b2, 0, b2s), vstore8(tri, 0, tris_);
    for (int j = 0; j < 8 && first + j < count; ++j) out[first + j] = (float4)(ts[j], b1s[j], b2s[j], as_float(tris_[j]));
}

__kernel void trace_any_packet(__global const BvhNode* nodes, __global const Triangle* tris,
                               __global const float4* ray_o, __global const float4* ray_d,
                               __global int* occluded_out, int count) {
    int first = get_global_id(0) * 8;
    if (first >= count) return;
    float3 o[8], d[8];
    float tm[8];
    for (int j = 0; j < 8; ++j) {
        int k = min(first + j, count - 1);
        float4 a = ray_o[k], b = ray_d[k];
        o[j] = a.xyz, d[j] = b.xyz, tm[j] = a.w;
    }
    PacketRay r = packet_ray(o, d);
    int8 occ = packet_occluded(nodes, tris, &r, vload8(0, tm));
    int os[8];
    vstore8(occ, 0, os);
    for (int j = 0; j < 8 && first + j < count; ++j) occluded_out[first + j] = os[j] ? 1 : 0;
}
