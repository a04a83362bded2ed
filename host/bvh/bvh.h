// Binned-SAH BVH over triangles, collapsed to BVH_WIDTH-wide nodes and flattened depth-first
// into BvhNode (cl/shared/types.h); traversed by cl/bvh.h.
#pragma once

#include <cstdint>
#include <vector>

#include "shared/types.h"

namespace clbdpt {

struct BvhOptions {
    // Spatial splits (SBVH): at most this many extra triangle references, as a fraction of the
    // triangle count; 0 builds by object splits only.
    float spatial_split_budget = 0.3f;
};

struct Bvh {
    std::vector<BvhNode> nodes;
    // order[i] = index (before reordering) of the triangle at position i of the leaves. With
    // spatial splits a triangle may appear more than once (in leaves on both sides of a plane),
    // so order can be longer than the triangle list; every triangle appears at least once.
    std::vector<uint32_t> order;
    double build_seconds = 0;
    int max_depth = 0;   // wide nodes on the longest root-to-leaf path
    int leaf_count = 0;  // non-empty leaves
    int max_stack = 0;   // most traversal stack entries any ray can need (<= BVH_STACK_SIZE)
    int spatial_splits = 0;  // nodes split by a plane through triangles
};

// Builds the BVH. Triangles must be finite (the scene loader guarantees it).
Bvh build_bvh(const std::vector<Triangle>& triangles, const BvhOptions& options = BvhOptions());

// Reorders a per-triangle array to BVH order (repeating the entries of triangles referenced
// more than once).
template <typename T>
std::vector<T> reorder(const std::vector<T>& items, const std::vector<uint32_t>& order) {
    std::vector<T> out;
    out.reserve(order.size());
    for (uint32_t i : order) out.push_back(items[i]);
    return out;
}

}  // namespace clbdpt
