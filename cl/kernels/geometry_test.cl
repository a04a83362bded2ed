/* Test kernels for the geometric helpers (tests/geometry_test.cpp): convert_density,
 * geometry_term and vertices_visible (cl/vertex.h), offset_ray_origin (cl/ray.h) with the real
 * BVH queries (cl/bvh.h). */
#include "vertex.h"

/* A vertex from a position, a geometric and a shading normal (0 = not on a surface), its type
 * and light index. The host rounded the point to float from double: it is off its surface by at
 * most half an ULP per coordinate, so gamma(1) |p| along ng bounds its error (gamma(4) to
 * spare). */
inline PathVertex make_vertex(float4 p, float4 ng, float4 ns, int type, int light) {
    PathVertex v = vertex_at(type, p.xyz, ng.xyz, FLOAT_GAMMA(4) * dot(fabs(ng.xyz), fabs(p.xyz)));
    v.ns = ns.xyz;
    v.material = 0;
    v.light = light;
    return v;
}

/* Per item: in[3i] = v.p, in[3i + 1] = next.p, in[3i + 2] = next.ng; kind[i] = (next.type,
 * next.light); out[i] = convert_density(v, pdf[i], next). */
__kernel void convert_density_test(SCENE_KERNEL_ARGS, __global const float4* in, __global const int2* kind,
                                   __global const float* pdf, __global float* out) {
    int gid = get_global_id(0);
    uint rays = 0;
    SceneData scene = SCENE_DATA_FROM_KERNEL_ARGS(&rays);
    float4 zero = (float4)(0.0f);
    PathVertex v = make_vertex(in[3 * gid], zero, zero, VERTEX_SURFACE, -1);
    PathVertex next = make_vertex(in[3 * gid + 1], in[3 * gid + 2], in[3 * gid + 2], kind[gid].x, kind[gid].y);
    out[gid] = convert_density(&scene, &v, pdf[gid], &next);
}

/* Per item: in[6i ..] = a.p, a.ng, a.ns, b.p, b.ng, b.ns; out[i] = (geometry_term(a, b),
 * vertices_visible(a, b), vertices_visible(b, a), rays traced). */
__kernel void geometry_term_test(SCENE_KERNEL_ARGS, __global const float4* in, __global float4* out) {
    int gid = get_global_id(0);
    uint rays = 0;
    SceneData scene = SCENE_DATA_FROM_KERNEL_ARGS(&rays);
    __global const float4* x = in + 6 * gid;
    PathVertex a = make_vertex(x[0], x[1], x[2], VERTEX_SURFACE, -1);
    PathVertex b = make_vertex(x[3], x[4], x[5], VERTEX_SURFACE, -1);
    float g = geometry_term(&scene, &a, &b);
    int ab = vertices_visible(&scene, &a, &b);
    int ba = vertices_visible(&scene, &b, &a);
    out[gid] = (float4)(g, (float)ab, (float)ba, (float)rays);
}

/* Per item: a point on triangle `in[2i].z` at barycentrics in[2i].xy (computed as the renderer
 * does, triangle_point), a direction in[2i + 1].xyz. The ray from offset_ray_origin(p, ng, error, w)
 * along w: out[2i] = (origin, index of the triangle intersect hits or -1),
 * out[2i + 1] = (p, occluded to infinity). */
__kernel void offset_ray_test(SCENE_KERNEL_ARGS, __global const float4* in, __global float4* out) {
    int gid = get_global_id(0);
    int t = (int)in[2 * gid].z;
    float3 p = triangle_point(&triangles[t], in[2 * gid].xy);
    float3 ng = triangle_normal(&triangles[t]);
    float3 w = in[2 * gid + 1].xyz;
    float3 o = offset_ray_origin(p, ng, triangle_point_error(&triangles[t], in[2 * gid].xy, ng), w);
    Hit hit;
    int found = intersect(nodes, triangles, 0, o, w, INFINITY, &hit);
    int blocked = occluded(nodes, triangles, 0, o, w, INFINITY);
    out[2 * gid] = (float4)(o, found ? (float)hit.triangle : -1.0f);
    out[2 * gid + 1] = (float4)(p, (float)blocked);
}
