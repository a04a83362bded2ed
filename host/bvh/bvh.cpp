// Binned-SAH BVH build (Wald 2007, "On fast Construction of SAH-based Bounding Volume
// Hierarchies"; pbrt-v3 BVHAccel::recursiveBuild with SplitMethod::SAH), flattened depth-first
// into BvhNode.
//
// The build works on PrimRefs (a triangle's bounds and its index), partitioned in place, so a
// node's triangles are always a contiguous range [first, first + count) of the ref array and the
// final triangle order is just the ref order. Binary nodes go to a shared array with an atomic
// allocator, so subtrees can be built on several threads; the flattening pass then lays them out
// depth-first (first child right after its parent).
#include "bvh/bvh.h"

#include <algorithm>
#include <atomic>
#include <cassert>
#include <chrono>
#include <cmath>
#include <cstring>
#include <thread>

#include "util/error.h"

namespace clbdpt {
namespace {

// ---- SAH constants ------------------------------------------------------------------------
// Cost of one ray-box traversal step relative to one ray-triangle test. The watertight test
// (cl/bvh.h) costs about as much as a slab test plus the stack work of a node visit, so the
// two are taken equal (pbrt-v3 uses 1/8 for a cheaper triangle relative to its traversal;
// measured here with traversal_bench: 1:1 gave the fastest traversal on PoCL).
constexpr float kTraversalCost = 1.0f;
constexpr float kIntersectionCost = 1.0f;

// Number of bins per axis for the SAH sweep. 32 bins are within a percent or two of a full
// sweep in tree quality (Wald 2007) at a fraction of the cost.
constexpr int kBinCount = 32;

// Largest leaf. SAH decides below it (a leaf of up to this many triangles is made when it is
// cheaper than the best split); above it the node is always split.
constexpr int kMaxLeafSize = 4;

// Subtrees with fewer triangles than this are built on the calling thread; larger ones split
// their second child off to a new thread while the spawn depth allows it.
constexpr int kParallelThreshold = 16 * 1024;

// A leaf's triangle count must fit its bits in BvhNode::meta.
static_assert(kMaxLeafSize <= int(BVH_META_COUNT_MASK), "leaf count does not fit BvhNode::meta");

struct Box {
    float lo[3] = {INFINITY, INFINITY, INFINITY};
    float hi[3] = {-INFINITY, -INFINITY, -INFINITY};

    void extend(const float* plo, const float* phi) {
        for (int k = 0; k < 3; ++k) {
            lo[k] = std::min(lo[k], plo[k]);
            hi[k] = std::max(hi[k], phi[k]);
        }
    }
    void extend(const Box& b) { extend(b.lo, b.hi); }
    void extend_point(const float* p) { extend(p, p); }
    float half_area() const {
        float dx = hi[0] - lo[0], dy = hi[1] - lo[1], dz = hi[2] - lo[2];
        if (!(dx >= 0)) return 0;  // empty box
        return dx * dy + dy * dz + dz * dx;
    }
};

// One triangle's bounds and its index in the input; 32 bytes so partitioning moves little.
struct PrimRef {
    float lo[3];
    uint32_t index;
    float hi[3];
    float pad;
    float centroid2(int axis) const { return lo[axis] + hi[axis]; }  // twice the box centre
};

// A binary node of the build. Interior: children at `left` and `left + 1` (allocated as a
// pair). Leaf: `count` > 0 refs from `first`.
struct BuildNode {
    Box box;
    int left = -1;
    int first = 0;
    int count = 0;
    int axis = 0;
};

int ceil_log2(uint64_t n) {
    int k = 0;
    while ((uint64_t(1) << k) < n) ++k;
    return k;
}

class Builder {
public:
    Builder(std::vector<PrimRef>& refs, int max_threads)
        : refs_(refs), nodes_(std::max<size_t>(1, 2 * refs.size() - 1)) {
        spawn_depth_ = 0;
        while ((1 << spawn_depth_) < max_threads) ++spawn_depth_;
        spawn_depth_ += 1;  // a few more tasks than cores, so uneven splits still balance
    }

    // Builds the subtree of refs [first, first + count) into node `index`.
    void build(int index, int first, int count, int depth) {
        BuildNode& node = nodes_[index];
        Box box, centroids;
        for (int i = first; i < first + count; ++i) {
            const PrimRef& r = refs_[i];
            box.extend(r.lo, r.hi);
            float c[3] = {r.centroid2(0), r.centroid2(1), r.centroid2(2)};
            centroids.extend_point(c);
        }
        node.box = box;
        node.first = first;
        node.count = count;
        if (count == 1) return make_leaf(depth);

        // Depth guarantee: a median split halves the count, so it finishes a subtree of n refs
        // within ceil(log2 n) more levels. Once SAH could run past BVH_MAX_DEPTH, split at the
        // median only. The traversal stack (cl/bvh.h) then never overflows.
        bool median_only = depth + ceil_log2(uint64_t(count)) >= BVH_MAX_DEPTH - 1;

        int axis = 0, mid = -1;
        float split_cost = INFINITY;
        if (!median_only) find_sah_split(first, count, box, centroids, &axis, &mid, &split_cost);

        if (mid < 0) {
            // No SAH split separates the centroids (all in one bin on every axis: equal or
            // nearly equal centroids), or the depth limit: split by count at the median of the
            // widest centroid axis, or make a leaf if the node is small enough.
            if (count <= kMaxLeafSize) return make_leaf(depth);
            axis = widest_axis(centroids);
            mid = first + count / 2;
            std::nth_element(refs_.begin() + first, refs_.begin() + mid, refs_.begin() + first + count,
                             [axis](const PrimRef& a, const PrimRef& b) {
                                 return a.centroid2(axis) < b.centroid2(axis);
                             });
        } else if (count <= kMaxLeafSize && kIntersectionCost * float(count) <= split_cost) {
            return make_leaf(depth);
        }

        int left = alloc_pair();
        node.left = left;
        node.axis = axis;
        node.count = 0;
        int left_count = mid - first, right_count = count - left_count;
        if (count >= kParallelThreshold && depth < spawn_depth_) {
            std::thread worker([=] { build(left + 1, mid, right_count, depth + 1); });
            build(left, first, left_count, depth + 1);
            worker.join();
        } else {
            build(left, first, left_count, depth + 1);
            build(left + 1, mid, right_count, depth + 1);
        }
    }

    int node_count() const { return next_.load(); }
    const std::vector<BuildNode>& nodes() const { return nodes_; }
    int max_depth() const { return max_depth_.load(); }
    int leaf_count() const { return leaf_count_.load(); }

private:
    void make_leaf(int depth) {
        leaf_count_.fetch_add(1, std::memory_order_relaxed);
        int d = max_depth_.load(std::memory_order_relaxed);
        while (depth > d && !max_depth_.compare_exchange_weak(d, depth)) {
        }
    }

    int alloc_pair() { return next_.fetch_add(2, std::memory_order_relaxed); }

    static int widest_axis(const Box& b) {
        float e[3] = {b.hi[0] - b.lo[0], b.hi[1] - b.lo[1], b.hi[2] - b.lo[2]};
        return e[0] >= e[1] && e[0] >= e[2] ? 0 : (e[1] >= e[2] ? 1 : 2);
    }

    // Binned SAH over the centroid bounds on all three axes. On success sets the axis, the
    // partition point (refs reordered) and the SAH cost of the split, in units of
    // kIntersectionCost-weighted triangle tests as for a leaf; mid stays -1 if no bin boundary
    // separates the centroids.
    void find_sah_split(int first, int count, const Box& box, const Box& centroids, int* axis_out,
                        int* mid_out, float* cost_out) {
        struct Bin {
            Box box;
            int count = 0;
        };
        Bin bins[3][kBinCount];
        float scale[3], offset[3];
        for (int k = 0; k < 3; ++k) {
            float extent = centroids.hi[k] - centroids.lo[k];
            // Slightly under kBinCount / extent so the largest centroid lands in the last bin.
            scale[k] = extent > 0 ? float(kBinCount) * (1.0f - 1e-6f) / extent : 0.0f;
            offset[k] = centroids.lo[k];
        }
        auto bin_of = [&](const PrimRef& r, int k) {
            int b = int((r.centroid2(k) - offset[k]) * scale[k]);
            return std::min(std::max(b, 0), kBinCount - 1);
        };
        for (int i = first; i < first + count; ++i) {
            const PrimRef& r = refs_[i];
            for (int k = 0; k < 3; ++k) {
                Bin& bin = bins[k][bin_of(r, k)];
                bin.count++;
                bin.box.extend(r.lo, r.hi);
            }
        }

        float best = INFINITY;
        int best_axis = -1, best_bin = -1;
        for (int k = 0; k < 3; ++k) {
            if (scale[k] == 0) continue;
            // Right-to-left sweep: cost of the right side of every boundary.
            float right_cost[kBinCount];
            Box acc;
            int n = 0;
            for (int b = kBinCount - 1; b > 0; --b) {
                acc.extend(bins[k][b].box);
                n += bins[k][b].count;
                right_cost[b] = n ? acc.half_area() * float(n) : INFINITY;
            }
            acc = Box();
            n = 0;
            for (int b = 0; b < kBinCount - 1; ++b) {
                acc.extend(bins[k][b].box);
                n += bins[k][b].count;
                if (n == 0) continue;
                float cost = acc.half_area() * float(n) + right_cost[b + 1];
                if (cost < best) {
                    best = cost;
                    best_axis = k;
                    best_bin = b + 1;  // bins [0, b] go left
                }
            }
        }
        if (best_axis < 0 || !(best < INFINITY)) return;
        float parent_area = box.half_area();
        *cost_out = parent_area > 0 ? kTraversalCost + kIntersectionCost * best / parent_area
                                    : kTraversalCost + kIntersectionCost * float(count);
        PrimRef* begin = refs_.data() + first;
        PrimRef* split = std::partition(begin, begin + count,
                                        [&](const PrimRef& r) { return bin_of(r, best_axis) < best_bin; });
        int mid = int(split - refs_.data());
        if (mid == first || mid == first + count) return;  // cannot happen; be safe
        *axis_out = best_axis;
        *mid_out = mid;
    }

    std::vector<PrimRef>& refs_;
    std::vector<BuildNode> nodes_;
    std::atomic<int> next_{1};  // node 0 is the root
    std::atomic<int> max_depth_{0};
    std::atomic<int> leaf_count_{0};
    int spawn_depth_ = 0;
};

// Writes the subtree of build node `index` depth-first to `out`.
void flatten(const std::vector<BuildNode>& nodes, int index, std::vector<BvhNode>& out) {
    // Explicit stack of (build node, parent slot to patch with our position).
    struct Item {
        int index;
        int parent;  // flattened parent whose `offset` is this node's position, or -1
    };
    std::vector<Item> stack;
    stack.push_back({index, -1});
    while (!stack.empty()) {
        Item item = stack.back();
        stack.pop_back();
        const BuildNode& b = nodes[item.index];
        int pos = int(out.size());
        if (item.parent >= 0) out[item.parent].offset = pos;
        BvhNode n;
        std::memcpy(n.lo, b.box.lo, sizeof n.lo);
        std::memcpy(n.hi, b.box.hi, sizeof n.hi);
        if (b.count > 0) {
            n.offset = b.first;
            n.meta = uint32_t(b.count);
            out.push_back(n);
        } else {
            n.offset = -1;  // patched when the second child is written
            n.meta = uint32_t(b.axis) << BVH_META_AXIS_SHIFT;
            out.push_back(n);
            stack.push_back({b.left + 1, pos});  // second child: after the whole first subtree
            stack.push_back({b.left, -1});       // first child: right after this node
        }
    }
}

}  // namespace

Bvh build_bvh(const std::vector<Triangle>& triangles) {
    auto start = std::chrono::steady_clock::now();
    Bvh bvh;
    size_t n = triangles.size();
    if (n > size_t(INT32_MAX) / 2) throw Error("too many triangles for the BVH: " + std::to_string(n));
    if (n == 0) {
        // One empty leaf with an empty box: every ray misses it.
        BvhNode leaf;
        for (int k = 0; k < 3; ++k) {
            leaf.lo[k] = INFINITY;
            leaf.hi[k] = -INFINITY;
        }
        leaf.offset = 0;
        leaf.meta = 0;
        // meta count 0 would read as interior; an empty tree is traversed as a leaf by
        // giving it count 0 and a box no ray can enter (the slab test fails first).
        bvh.nodes.push_back(leaf);
        bvh.leaf_count = 1;
        bvh.build_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
        return bvh;
    }

    std::vector<PrimRef> refs(n);
    auto make_refs = [&](size_t begin, size_t end) {
        for (size_t i = begin; i < end; ++i) {
            const Triangle& t = triangles[i];
            PrimRef& r = refs[i];
            for (int k = 0; k < 3; ++k) {
                float a = t.p0.s[k], b = t.p1.s[k], c = t.p2.s[k];
                r.lo[k] = std::min(a, std::min(b, c));
                r.hi[k] = std::max(a, std::max(b, c));
            }
            r.index = uint32_t(i);
            r.pad = 0;
        }
    };
    unsigned threads = std::max(1u, std::thread::hardware_concurrency());
    if (n >= size_t(kParallelThreshold) && threads > 1) {
        std::vector<std::thread> pool;
        for (unsigned t = 0; t < threads; ++t)
            pool.emplace_back(make_refs, n * t / threads, n * (t + 1) / threads);
        for (auto& th : pool) th.join();
    } else {
        make_refs(0, n);
    }

    Builder builder(refs, int(threads));
    builder.build(0, 0, int(n), 0);

    bvh.nodes.reserve(size_t(builder.node_count()));
    flatten(builder.nodes(), 0, bvh.nodes);
    bvh.order.resize(n);
    for (size_t i = 0; i < n; ++i) bvh.order[i] = refs[i].index;
    bvh.max_depth = builder.max_depth();
    bvh.leaf_count = builder.leaf_count();
    if (bvh.max_depth >= BVH_MAX_DEPTH) throw Error("BVH deeper than BVH_MAX_DEPTH (builder bug)");
    bvh.build_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    return bvh;
}

}  // namespace clbdpt
