#include "bvh/bvh_query.h"

#include <algorithm>
#include <cmath>

namespace clbdpt {
namespace {

Vec3 corner(const clbdpt_float4& p) { return {p.s[0], p.s[1], p.s[2]}; }

// Möller-Trumbore; two-sided like the device test. Precision matters little for probe rays.
float hit_triangle(const Triangle& tri, Vec3 o, Vec3 d) {
    const Vec3 p0 = corner(tri.p0), e1 = corner(tri.p1) - p0, e2 = corner(tri.p2) - p0;
    const Vec3 pv = cross(d, e2);
    const float det = dot(e1, pv);
    if (det == 0.0f) return INFINITY;
    const float inv = 1.0f / det;
    const Vec3 tv = o - p0;
    const float u = dot(tv, pv) * inv;
    if (u < 0.0f || u > 1.0f) return INFINITY;
    const Vec3 qv = cross(tv, e1);
    const float v = dot(d, qv) * inv;
    if (v < 0.0f || u + v > 1.0f) return INFINITY;
    const float t = dot(e2, qv) * inv;
    return t > 0.0f ? t : INFINITY;
}

}  // namespace

float closest_hit_distance(const std::vector<BvhNode>& nodes, const std::vector<Triangle>& triangles, Vec3 o, Vec3 d) {
    float t = INFINITY;
    closest_hit_triangle(nodes, triangles, o, d, &t);
    return t;
}

int closest_hit_triangle(const std::vector<BvhNode>& nodes, const std::vector<Triangle>& triangles, Vec3 o, Vec3 d,
                         float* distance) {
    *distance = INFINITY;
    if (nodes.empty()) return -1;
    const Vec3 inv(1.0f / d.x, 1.0f / d.y, 1.0f / d.z);
    float closest = INFINITY;
    int closest_triangle = -1;
    std::vector<int> stack{0};
    while (!stack.empty()) {
        const int entry = stack.back();
        stack.pop_back();
        if (entry < 0) {
            const int first = BVH_LEAF_FIRST(entry), count = BVH_LEAF_COUNT(entry);
            for (int i = first; i < first + count; ++i) {
                const float t = hit_triangle(triangles[size_t(i)], o, d);
                if (t < closest) {
                    closest = t;
                    closest_triangle = i;
                }
            }
            continue;
        }
        const BvhNode& node = nodes[size_t(entry)];
        for (int c = 0; c < BVH_WIDTH; ++c) {
            if (node.bounds[0][c] > node.bounds[1][c]) continue;  // an unused slot
            float t0 = 0.0f, t1 = closest;
            for (int axis = 0; axis < 3; ++axis) {
                float a = (node.bounds[2 * axis][c] - o[axis]) * inv[axis];
                float b = (node.bounds[2 * axis + 1][c] - o[axis]) * inv[axis];
                if (a > b) std::swap(a, b);
                t0 = std::fmax(t0, a);
                t1 = std::fmin(t1, b);
            }
            if (t0 <= t1) stack.push_back(node.child[c]);
        }
    }
    *distance = closest;
    return closest_triangle;
}

}  // namespace clbdpt
