// Binned-SAH BVH over triangles, collapsed to BVH_WIDTH-wide nodes and flattened depth-first
// into BvhNode (cl/shared/types.h); traversed by cl/bvh.h.
#pragma once

#include <cstdint>
#include <vector>

#include "shared/types.h"

namespace clbdpt {

struct Bvh {
    std::vector<BvhNode> nodes;
    std::vector<uint32_t> order;  // order[i] = index (before reordering) of the i-th triangle
    double build_seconds = 0;
    int max_depth = 0;   // wide nodes on the longest root-to-leaf path
    int leaf_count = 0;  // non-empty leaves
    int max_stack = 0;   // most traversal stack entries any ray can need (<= BVH_STACK_SIZE)
};

// Builds the BVH. Triangles must be finite (the scene loader guarantees it).
Bvh build_bvh(const std::vector<Triangle>& triangles);

// Reorders a per-triangle array to BVH order.
template <typename T>
std::vector<T> reorder(const std::vector<T>& items, const std::vector<uint32_t>& order) {
    std::vector<T> out;
    out.reserve(order.size());
    for (uint32_t i : order) out.push_back(items[i]);
    return out;
}

}  // namespace clbdpt
