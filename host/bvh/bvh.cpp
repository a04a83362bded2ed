// BVH build: a binary tree by binned SAH (Wald 2007, "On fast Construction of SAH-based Bounding
// Volume Hierarchies"; pbrt-v3 BVHAccel::recursiveBuild, SplitMethod::SAH), collapsed to
// BVH_WIDTH-wide nodes by the least SAH cost (Ylitie, Karras & Laine 2017, "Efficient Incoherent
// Ray Traversal on GPUs Through Compressed Wide BVHs", section 3.1) and flattened depth-first into
// BvhNode (cl/shared/types.h).
//
// The build works on PrimRefs (a triangle's bounds, or a part's, and its index), partitioned in
// place, so a node's triangles are always a contiguous range [first, first + count) of the ref
// array. Binary nodes go to one array through an atomic allocator, so subtrees can be built on
// several threads.
//
// Spatial splits (Stich, Friedrich & Dietrich 2009, "Spatial Splits in Bounding Volume
// Hierarchies"; Embree's high-quality builders): where the two sides of the best object split
// overlap by more than a small fraction of the scene's area, the node also bins the parts of its
// triangles between planes (each triangle clipped, not just its box) and may split at a plane,
// giving a triangle that crosses it a reference on each side with the box of its own part.
// Large slanted triangles (arches, roofs, terrain) otherwise make boxes that overlap high in
// the tree. The extra references are bounded by a budget (BvhOptions): the ref array has that
// much slack at its end, and every split hands its free space on to its children in proportion
// to their sizes, so each subtree still owns one contiguous range. The final triangle order is
// the order in which the collapse to wide nodes writes the leaves (the ref order without the
// unused slack).
//
// Besides the centroid on each axis, the binning also sorts triangles by size (log2 of their
// box's area), so SAH can split large triangles off from small ones with the same centroid.
// Without it a few big triangles (walls, floors) whose boxes span the scene end up in nodes full
// of small ones, and every ray pays for the huge boxes of those nodes.
#include "bvh/bvh.h"

#include <algorithm>
#include <array>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstddef>
#include <cstring>
#include <limits>
#include <memory>
#include <thread>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#include "util/error.h"

namespace clbdpt {
namespace {

// ---- Build constants -------------------------------------------------------------------------

// SAH costs of the binary build: a ray visiting an interior node (a slab test, the stack work
// and, mostly, the cache miss of fetching the node) against testing one triangle. With the ratio
// 1 the traversal was as fast as with 2 or 4, and with leaves of up to 8 (traversal_bench with
// 4-wide nodes, PoCL on 2 cores): the ray rates are bound by memory latency, not by this.
constexpr float kTraversalCost = 1.0f;
constexpr float kIntersectionCost = 1.0f;

// Bins per binning key for the SAH sweep. 32 are within a percent or two of a full sweep in
// tree quality (Wald 2007); small nodes use fewer (one per triangle), where setting up and
// sweeping 32 bins would cost more than the binning itself.
constexpr int kMaxBins = 32;
constexpr int kMinBins = 4;

// Largest leaf. SAH decides below it (a leaf is made when it is cheaper than the best split);
// above it the node is always split.
constexpr int kMaxLeafSize = 4;
static_assert(kMaxLeafSize < (1 << BVH_LEAF_BITS), "leaf count does not fit a BvhNode child entry");

// The collapse's SAH costs: a wide node's visit (its BVH_WIDTH box tests and pushes) and one
// triangle test, per unit of the visited box's area. A wide node costs about three triangle
// tests on a CPU; traversal_bench on Crytek Sponza and the 1M-triangle spheres gave the same
// rays per second within noise with a triangle cost of 0.3 and 0.6.
constexpr float kCollapseNodeCost = 1.0f;
constexpr float kCollapseTriangleCost = 0.3f;

// Subtrees with fewer triangles than this are built on the calling thread; larger ones hand
// their second child to a new thread while the spawn depth allows it. Nodes with more than
// kParallelBinning triangles near the root bin on several threads.
constexpr int kParallelThreshold = 16 * 1024;
constexpr int kParallelBinning = 128 * 1024;

// Number of binning keys: centroid x, y, z (as twice the box centre) and size.
constexpr int kKeys = 4;

// Spatial splits: bins per axis, and the overlap of an object split's two sides (as a fraction
// of the root's area) above which a node tries them (Stich et al.'s alpha).
constexpr int kSpatialBins = 16;
constexpr float kSpatialSplitAlpha = 1e-5f;
// Spatial splits are tried in the top binary levels only. On Crytek Sponza, nodes at depth 8
// and below gave nothing more (closest-hit rays visit 15.6 wide nodes each with splits down to
// depth 8 or all the way, 21.7 without), while their binning took the build of 1M
// tessellated-sphere triangles from 0.68 s to 1.33 s (0.49 s without spatial splits; before
// small triangles were binned by their boxes, below).
constexpr int kSpatialSplitDepth = 8;
// A spatial split's side can hold more refs than its parent, so the depth guarantee below
// (a median split once depth + ceil(log2 count) reaches the stack limit) holds only where no
// such split happens near the limit: a node above kSpatialSplitDepth has at most 2^27 refs.
static_assert(kSpatialSplitDepth + 27 + 2 < BVH_STACK_SIZE - 1, "spatial splits could break the depth guarantee");

// ---- Four-lane vectors -----------------------------------------------------------------------

#if defined(__SSE2__)
struct V4 {
    __m128 v;
    static V4 load(const float* p) { return {_mm_load_ps(p)}; }
    static V4 splat(float x) { return {_mm_set1_ps(x)}; }
    void store(float* p) const { _mm_store_ps(p, v); }
    friend V4 operator+(V4 a, V4 b) { return {_mm_add_ps(a.v, b.v)}; }
    friend V4 operator-(V4 a, V4 b) { return {_mm_sub_ps(a.v, b.v)}; }
    friend V4 operator*(V4 a, V4 b) { return {_mm_mul_ps(a.v, b.v)}; }
    friend V4 vmin(V4 a, V4 b) { return {_mm_min_ps(a.v, b.v)}; }
    friend V4 vmax(V4 a, V4 b) { return {_mm_max_ps(a.v, b.v)}; }
    // Lanes 0..2 of a, lane 3 zero.
    friend V4 xyz(V4 a) { return {_mm_and_ps(a.v, _mm_castsi128_ps(_mm_set_epi32(0, -1, -1, -1)))}; }
};
#else
struct V4 {
    float v[4];
    static V4 load(const float* p) { return {{p[0], p[1], p[2], p[3]}}; }
    static V4 splat(float x) { return {{x, x, x, x}}; }
    void store(float* p) const { std::memcpy(p, v, sizeof v); }
    template <typename F>
    static V4 map(V4 a, V4 b, F f) { return {{f(a.v[0], b.v[0]), f(a.v[1], b.v[1]), f(a.v[2], b.v[2]), f(a.v[3], b.v[3])}}; }
    friend V4 operator+(V4 a, V4 b) { return map(a, b, [](float x, float y) { return x + y; }); }
    friend V4 operator-(V4 a, V4 b) { return map(a, b, [](float x, float y) { return x - y; }); }
    friend V4 operator*(V4 a, V4 b) { return map(a, b, [](float x, float y) { return x * y; }); }
    friend V4 vmin(V4 a, V4 b) { return map(a, b, [](float x, float y) { return x < y ? x : y; }); }
    friend V4 vmax(V4 a, V4 b) { return map(a, b, [](float x, float y) { return x > y ? x : y; }); }
    friend V4 xyz(V4 a) { return {{a.v[0], a.v[1], a.v[2], 0.0f}}; }
};
#endif

// A box (lanes 0..2; lane 3 unused) or the bounds of the binning keys (all four lanes).
struct Bounds4 {
    V4 lo = V4::splat(INFINITY);
    V4 hi = V4::splat(-INFINITY);

    void extend(V4 a, V4 b) {
        lo = vmin(lo, a);
        hi = vmax(hi, b);
    }
    void extend(V4 p) { extend(p, p); }
    void extend(const Bounds4& b) { extend(b.lo, b.hi); }
    // Half the surface area of the box in lanes 0..2; 0 if empty.
    float half_area() const {
        alignas(16) float d[4];
        (hi - lo).store(d);
        if (!(d[0] >= 0 && d[1] >= 0 && d[2] >= 0)) return 0;
        return d[0] * d[1] + d[1] * d[2] + d[2] * d[0];
    }
    // The box shared with another (empty if they do not overlap).
    Bounds4 intersection(const Bounds4& o) const {
        Bounds4 b;
        b.lo = vmax(lo, o.lo);
        b.hi = vmin(hi, o.hi);
        return b;
    }
};

// One triangle's bounds, its size key and its index; 32 bytes, 16-aligned, so a ref is two
// vector loads and partitioning moves little.
struct alignas(16) PrimRef {
    float lo[3];
    float size;  // log2 of the box's half area: the fourth binning key
    float hi[3];
    uint32_t index;

    V4 box_lo() const { return V4::load(lo); }  // lane 3: size, ignored as a box
    V4 box_hi() const { return xyz(V4::load(hi)); }
    // The binning keys: twice the box centre, and the size.
    V4 keys() const { return V4::load(lo) + xyz(V4::load(hi)); }
    float key(int k) const { return k < 3 ? lo[k] + hi[k] : size; }
    void set_box(const float* box_lo, const float* box_hi) {
        std::memcpy(lo, box_lo, sizeof lo);
        std::memcpy(hi, box_hi, sizeof hi);
        float dx = hi[0] - lo[0], dy = hi[1] - lo[1], dz = hi[2] - lo[2];
        // Zero-area boxes (axis-aligned segments, points) get the smallest normal float's log.
        size = std::log2(std::max(dx * dy + dy * dz + dz * dx, 1.17549435e-38f));
    }
};

// The bounds of the part of triangle t with lo <= x_k <= hi, within the box of ref r (which may
// already be a clipped part of t); returns false if that part is empty. Conservative: a point
// where an edge crosses a plane lies on the plane exactly on axis k, and is widened by about
// 8 ulps on the other two, so the box contains the exact part despite rounding.
bool clip_triangle(const Triangle& t, const PrimRef& r, int k, float lo, float hi, float* out_lo, float* out_hi) {
    const float* v[3] = {t.p0.s, t.p1.s, t.p2.s};
    float mn[3] = {INFINITY, INFINITY, INFINITY}, mx[3] = {-INFINITY, -INFINITY, -INFINITY};
    auto add = [&](int j, float x, float pad) {
        mn[j] = std::min(mn[j], x - pad);
        mx[j] = std::max(mx[j], x + pad);
    };
    for (int e = 0; e < 3; ++e) {
        const float* a = v[e];
        const float* b = v[e == 2 ? 0 : e + 1];
        if (a[k] >= lo && a[k] <= hi)
            for (int j = 0; j < 3; ++j) add(j, a[j], 0.0f);
        for (float plane : {lo, hi}) {
            if (!((a[k] < plane && b[k] > plane) || (a[k] > plane && b[k] < plane))) continue;
            float s = (plane - a[k]) / (b[k] - a[k]);
            for (int j = 0; j < 3; ++j) {
                if (j == k) add(j, plane, 0.0f);
                else add(j, a[j] + s * (b[j] - a[j]), 0x1p-20f * (std::fabs(a[j]) + std::fabs(b[j])));
            }
        }
    }
    mn[k] = std::max(mn[k], lo);
    mx[k] = std::min(mx[k], hi);
    for (int j = 0; j < 3; ++j) {
        out_lo[j] = std::max(mn[j], r.lo[j]);
        out_hi[j] = std::min(mx[j], r.hi[j]);
        if (!(out_lo[j] <= out_hi[j])) return false;
    }
    return true;
}

// A binary node of the build. Interior: children at `left` and `left + 1` (allocated as a
// pair). Leaf: `count` > 0 refs from `first`. Trivial, so the array is not zeroed up front.
struct BuildNode {
    float lo[3], hi[3];
    int left;
    int first;
    int count;
    int height;  // longest path to a leaf below, in binary levels (a leaf: 0)

    float half_area() const {
        float dx = hi[0] - lo[0], dy = hi[1] - lo[1], dz = hi[2] - lo[2];
        return dx >= 0 ? dx * dy + dy * dz + dz * dx : 0;
    }
};

int ceil_log2(uint64_t n) {
    int k = 0;
    while ((uint64_t(1) << k) < n) ++k;
    return k;
}

// How keys map to bins: bin = (key - offset) * scale, per key.
struct BinMapping {
    int count = 0;  // bins per key
    V4 offset = V4::splat(0), scale = V4::splat(0);

    BinMapping() = default;
    BinMapping(int bins, const Bounds4& keys) : count(bins), offset(keys.lo) {
        alignas(16) float lo[4], hi[4], sc[4];
        keys.lo.store(lo);
        keys.hi.store(hi);
        for (int k = 0; k < kKeys; ++k) {
            float extent = hi[k] - lo[k];
            // Slightly under bins / extent so the largest key lands in the last bin.
            sc[k] = extent > 0 ? float(bins) * (1.0f - 1e-6f) / extent : 0.0f;
        }
        scale = V4::load(sc);
    }
    float scale_of(int k) const {
        alignas(16) float s[4];
        scale.store(s);
        return s[k];
    }
    int bin_of(const PrimRef& r, int k) const {
        alignas(16) float o[4], s[4];
        offset.store(o);
        scale.store(s);
        int b = int((r.key(k) - o[k]) * s[k]);
        return std::min(std::max(b, 0), count - 1);
    }
};

// The bins of one node: for each key, the bounds and count of the refs in each bin.
struct Bins {
    BinMapping map;
    Bounds4 box[kKeys][kMaxBins];
    int n[kKeys][kMaxBins];

    void init(const BinMapping& mapping) {
        map = mapping;
        for (int k = 0; k < kKeys; ++k) {
            for (int b = 0; b < map.count; ++b) {
                box[k][b] = Bounds4();
                n[k][b] = 0;
            }
        }
    }

    void add(const PrimRef* refs, int begin, int end) {
        for (int i = begin; i < end; ++i) {
            const PrimRef& r = refs[i];
            alignas(16) float f[4];
            ((r.keys() - map.offset) * map.scale).store(f);
            V4 lo = r.box_lo(), hi = r.box_hi();
            for (int k = 0; k < kKeys; ++k) {
                int b = std::min(std::max(int(f[k]), 0), map.count - 1);
                box[k][b].extend(lo, hi);
                n[k][b]++;
            }
        }
    }

    void merge(const Bins& other) {
        for (int k = 0; k < kKeys; ++k) {
            for (int b = 0; b < map.count; ++b) {
                box[k][b].extend(other.box[k][b]);
                n[k][b] += other.n[k][b];
            }
        }
    }
};

struct Split {
    float cost = INFINITY;  // sum over both sides of half area x triangle count
    int key = -1;
    int bin = -1;  // bins [0, bin) go left
    BinMapping map;
    Bounds4 left_box, right_box;
};

Split best_split(const Bins& bins) {
    Split best;
    best.map = bins.map;
    const int count = bins.map.count;
    for (int k = 0; k < kKeys; ++k) {
        if (bins.map.scale_of(k) == 0) continue;  // all keys equal: nothing to split
        // Right-to-left sweep: bounds and cost of the right side of every boundary.
        Bounds4 right[kMaxBins];
        float right_cost[kMaxBins];
        Bounds4 acc;
        int n = 0;
        for (int b = count - 1; b > 0; --b) {
            acc.extend(bins.box[k][b]);
            n += bins.n[k][b];
            right[b] = acc;
            right_cost[b] = n ? acc.half_area() * float(n) : INFINITY;
        }
        acc = Bounds4();
        n = 0;
        for (int b = 0; b < count - 1; ++b) {
            acc.extend(bins.box[k][b]);
            n += bins.n[k][b];
            if (n == 0) continue;
            float cost = acc.half_area() * float(n) + right_cost[b + 1];
            if (cost < best.cost) {
                best.cost = cost;
                best.key = k;
                best.bin = b + 1;
                best.left_box = acc;
                best.right_box = right[b + 1];
            }
        }
    }
    return best;
}

// A split at the plane x_axis = plane, found by binning the triangles' clipped parts.
struct SpatialSplit {
    float cost = INFINITY;
    int axis = -1;
    float plane = 0;
    // The binned sides, for reference unsplitting.
    int left_count = 0, right_count = 0;
    Bounds4 left_box, right_box;
};

// The spatial bins of one node: on each axis, kSpatialBins slabs of equal width across the
// node's box, with the bounds of the triangles' parts inside each slab (each triangle clipped to
// it) and the numbers of refs that start and end in it. A ref counts on the left of every
// plane it starts before and on the right of every plane it ends after.
struct SpatialBins {
    float lo[3], hi[3], scale[3];
    Bounds4 box[3][kSpatialBins];
    int enter[3][kSpatialBins], leave[3][kSpatialBins];

    void init(const Bounds4& node_box) {
        alignas(16) float l[4], h[4];
        node_box.lo.store(l);
        node_box.hi.store(h);
        for (int k = 0; k < 3; ++k) {
            lo[k] = l[k];
            hi[k] = h[k];
            const float extent = h[k] - l[k];
            scale[k] = extent > 0 ? float(kSpatialBins) * (1.0f - 1e-6f) / extent : 0.0f;
            for (int b = 0; b < kSpatialBins; ++b) {
                box[k][b] = Bounds4();
                enter[k][b] = leave[k][b] = 0;
            }
        }
    }
    // The plane between slabs b - 1 and b.
    float plane(int k, int b) const {
        return b == kSpatialBins ? hi[k] : lo[k] + (hi[k] - lo[k]) * float(b) / float(kSpatialBins);
    }
    int bin_of(int k, float x) const { return std::min(std::max(int((x - lo[k]) * scale[k]), 0), kSpatialBins - 1); }

    void add(const std::vector<Triangle>& triangles, const PrimRef* refs, int begin, int end) {
        for (int i = begin; i < end; ++i) {
            const PrimRef& r = refs[i];
            for (int k = 0; k < 3; ++k) {
                if (scale[k] == 0) continue;
                int b0 = bin_of(k, r.lo[k]), b1 = bin_of(k, r.hi[k]);
                ++enter[k][b0];
                ++leave[k][b1];
                if (b0 == b1) {
                    box[k][b0].extend(r.box_lo(), r.box_hi());
                    continue;
                }
                if (b1 == b0 + 1 && (r.hi[k] - r.lo[k]) * scale[k] < 1.0f) {
                    // A small triangle across one plane: its box cut at the plane is close
                    // enough to its parts' bounds for binning, and much cheaper (tessellated
                    // meshes have many such; the split itself clips exactly).
                    alignas(16) float l[4], h[4];
                    r.box_lo().store(l);
                    r.box_hi().store(h);
                    const float p = plane(k, b1);
                    h[k] = p;
                    box[k][b0].extend(V4::load(l), V4::load(h));
                    h[k] = r.hi[k];
                    l[k] = p;
                    box[k][b1].extend(V4::load(l), V4::load(h));
                    continue;
                }
                const Triangle& t = triangles[r.index];
                for (int b = b0; b <= b1; ++b) {
                    alignas(16) float l[4] = {0, 0, 0, 0}, h[4] = {0, 0, 0, 0};
                    float a = b == b0 ? r.lo[k] : plane(k, b), c = b == b1 ? r.hi[k] : plane(k, b + 1);
                    if (clip_triangle(t, r, k, a, c, l, h)) box[k][b].extend(V4::load(l), V4::load(h));
                }
            }
        }
    }

    void merge(const SpatialBins& other) {
        for (int k = 0; k < 3; ++k) {
            for (int b = 0; b < kSpatialBins; ++b) {
                box[k][b].extend(other.box[k][b]);
                enter[k][b] += other.enter[k][b];
                leave[k][b] += other.leave[k][b];
            }
        }
    }

    SpatialSplit best_split() const {
        SpatialSplit best;
        for (int k = 0; k < 3; ++k) {
            if (scale[k] == 0) continue;
            Bounds4 right[kSpatialBins];
            int right_n[kSpatialBins];
            Bounds4 acc;
            int n = 0;
            for (int b = kSpatialBins - 1; b > 0; --b) {
                acc.extend(box[k][b]);
                n += leave[k][b];
                right[b] = acc;
                right_n[b] = n;
            }
            acc = Bounds4();
            n = 0;
            for (int b = 1; b < kSpatialBins; ++b) {
                acc.extend(box[k][b - 1]);
                n += enter[k][b - 1];
                if (n == 0 || right_n[b] == 0) continue;
                float cost = acc.half_area() * float(n) + right[b].half_area() * float(right_n[b]);
                if (cost < best.cost) {
                    best.cost = cost;
                    best.axis = k;
                    best.plane = plane(k, b);
                    best.left_box = acc;
                    best.right_box = right[b];
                    best.left_count = n;
                    best.right_count = right_n[b];
                }
            }
        }
        return best;
    }
};

class Builder {
public:
    // refs: the triangles' refs, followed by the slack that spatial splits may fill.
    Builder(const std::vector<Triangle>& triangles, std::vector<PrimRef>& refs, int threads, float root_area)
        : triangles_(triangles),
          refs_(refs),
          nodes_(new BuildNode[std::max<size_t>(1, 2 * refs.size())]),
          threads_(threads),
          root_area_(root_area) {
        while ((1 << spawn_depth_) < threads) ++spawn_depth_;
        spawn_depth_ += 1;  // a few more tasks than cores, so uneven splits still balance
    }

    // Builds the subtree of refs [first, first + count), whose box and key bounds are given,
    // into node `index`; refs [first + count, cap_end) are free for its spatial splits. Returns
    // its height.
    int build(int index, int first, int count, int cap_end, int depth, const Bounds4& box, const Bounds4& keys) {
        BuildNode& node = nodes_[index];
        alignas(16) float lo[4], hi[4];
        box.lo.store(lo);
        box.hi.store(hi);
        std::memcpy(node.lo, lo, sizeof node.lo);
        std::memcpy(node.hi, hi, sizeof node.hi);
        node.first = first;
        node.count = count;
        node.left = -1;
        node.height = 0;
        if (count == 1) return make_leaf(depth);

        // Depth guarantee: a median split halves the count, so it finishes a subtree of n refs
        // within ceil(log2 n) more levels. Once SAH could take a leaf deeper than
        // BVH_STACK_SIZE - 1, split at the median only; the collapse to wide nodes relies on it
        // to bound the traversal stack.
        bool median_only = depth + ceil_log2(uint64_t(count)) >= BVH_STACK_SIZE - 1;

        int mid = -1;
        Bounds4 left_box, right_box, left_keys, right_keys;
        if (!median_only) {
            Split split = find_split(first, count, depth, keys);
            if (split.key >= 0) {
                const int slack = cap_end - (first + count);
                SpatialSplit spatial;
                if (slack > 0 && depth < kSpatialSplitDepth &&
                    split.left_box.intersection(split.right_box).half_area() > kSpatialSplitAlpha * root_area_) {
                    spatial = find_spatial_split(first, count, depth, box);
                }
                float best = std::min(split.cost, spatial.cost);
                float area = box.half_area();
                float split_cost = area > 0 ? kTraversalCost + kIntersectionCost * best / area
                                            : kTraversalCost + kIntersectionCost * float(count);
                if (count <= kMaxLeafSize && kIntersectionCost * float(count) <= split_cost) return make_leaf(depth);
                if (spatial.cost < split.cost) {
                    int added = 0;
                    mid = spatial_partition(first, count, slack, spatial, &added, &left_box, &right_box, &left_keys,
                                            &right_keys);
                    if (mid >= 0) {
                        count += added;
                        node.count = count;
                        if (mid == first || mid == first + count) {
                            // Nothing on one side (refs lying in the plane): split at the median.
                            Bounds4 all_keys = left_keys;
                            all_keys.extend(right_keys);
                            left_box = right_box = left_keys = right_keys = Bounds4();
                            mid = median_split(first, count, all_keys, &left_box, &right_box, &left_keys, &right_keys);
                        } else {
                            spatial_splits_.fetch_add(1, std::memory_order_relaxed);
                        }
                    }
                }
                if (mid < 0) {
                    mid = partition(first, count, split, &left_keys, &right_keys);
                    left_box = split.left_box;
                    right_box = split.right_box;
                }
            }
        }
        if (mid < 0) {
            // No split separates the keys (all triangles alike), or the depth limit: split by
            // count at the median of the widest centroid axis, or make a leaf if small enough.
            if (count <= kMaxLeafSize) return make_leaf(depth);
            mid = median_split(first, count, keys, &left_box, &right_box, &left_keys, &right_keys);
        }

        // Hand the free space on in proportion to the children's sizes: the right child's refs
        // move up by the left one's share. (Not below the levels that make spatial splits.)
        int left_count = mid - first, right_count = count - left_count;
        int right_first = mid;
        const int free = cap_end - (first + count);
        if (free > 0 && depth + 1 < kSpatialSplitDepth) {
            int left_share = int(int64_t(free) * left_count / count);
            if (left_share > 0) {
                std::memmove(&refs_[size_t(mid + left_share)], &refs_[size_t(mid)], size_t(right_count) * sizeof(PrimRef));
                right_first = mid + left_share;
            }
        }

        int left = next_.fetch_add(2, std::memory_order_relaxed);
        node.left = left;
        node.count = 0;
        int left_height = 0, right_height = 0;
        if (count >= kParallelThreshold && depth < spawn_depth_) {
            std::thread worker([&, left, right_first, right_count, cap_end, depth] {
                right_height = build(left + 1, right_first, right_count, cap_end, depth + 1, right_box, right_keys);
            });
            left_height = build(left, first, left_count, right_first, depth + 1, left_box, left_keys);
            worker.join();
        } else {
            left_height = build(left, first, left_count, right_first, depth + 1, left_box, left_keys);
            right_height = build(left + 1, right_first, right_count, cap_end, depth + 1, right_box, right_keys);
        }
        nodes_[index].height = 1 + std::max(left_height, right_height);
        return nodes_[index].height;
    }

    const std::vector<PrimRef>& refs() const { return refs_; }

    const BuildNode* nodes() const { return nodes_.get(); }
    int node_count() const { return next_.load(); }
    int max_depth() const { return max_depth_.load(); }
    int spatial_splits() const { return spatial_splits_.load(); }

private:
    int make_leaf(int depth) {
        int d = max_depth_.load(std::memory_order_relaxed);
        while (depth > d && !max_depth_.compare_exchange_weak(d, depth)) {
        }
        return 0;
    }

    // Fills `bins` (set up by init) with refs [first, first + count) through add(bins, begin,
    // end). Near the root, where few subtrees run in parallel yet, bins on several threads,
    // each into its own copy, merged at the end. Neither caller recurses, so one scratch set of
    // bins per thread will do.
    template <typename BinSet, typename Init, typename Add>
    void bin_refs(BinSet& bins, int first, int count, int depth, const Init& init, const Add& add) {
        init(bins);
        int threads = count >= kParallelBinning ? std::max(1, threads_ >> depth) : 1;
        if (threads > 1) {
            std::vector<std::unique_ptr<BinSet>> partial;
            std::vector<std::thread> pool;
            for (int t = 1; t < threads; ++t) {
                partial.push_back(std::make_unique<BinSet>());
                init(*partial.back());
                int begin = first + int(int64_t(count) * t / threads);
                int end = first + int(int64_t(count) * (t + 1) / threads);
                pool.emplace_back([&add, b = partial.back().get(), begin, end] { add(*b, begin, end); });
            }
            add(bins, first, first + count / threads);
            for (auto& th : pool) th.join();
            for (auto& p : partial) bins.merge(*p);
        } else {
            add(bins, first, first + count);
        }
    }

    Split find_split(int first, int count, int depth, const Bounds4& keys) {
        BinMapping map(std::min(kMaxBins, std::max(kMinBins, count)), keys);
        thread_local Bins bins;
        bin_refs(
            bins, first, count, depth, [&map](Bins& b) { b.init(map); },
            [this](Bins& b, int begin, int end) { b.add(refs_.data(), begin, end); });
        return best_split(bins);
    }

    // Bins the parts of the triangles between planes (SpatialBins); returns the plane of least
    // SAH cost.
    SpatialSplit find_spatial_split(int first, int count, int depth, const Bounds4& box) {
        thread_local SpatialBins bins;
        bin_refs(
            bins, first, count, depth, [&box](SpatialBins& b) { b.init(box); },
            [this](SpatialBins& b, int begin, int end) { b.add(triangles_, refs_.data(), begin, end); });
        return bins.best_split();
    }

    // Splits [first, first + count) at the plane. A ref across it is clipped to its left part
    // and a copy with its right part is added, unless keeping it whole on one side costs less
    // by SAH (Stich et al.'s reference unsplitting). Returns the first ref of the right side
    // (which then ends at first + count + *added; either side may be empty) with both sides'
    // bounds, or -1, leaving the refs as they were, if the copies would not fit in `slack`.
    int spatial_partition(int first, int count, int slack, const SpatialSplit& split, int* added, Bounds4* left_box,
                          Bounds4* right_box, Bounds4* left_keys, Bounds4* right_keys) {
        const int k = split.axis;
        const float p = split.plane;
        auto crosses = [&](const PrimRef& r) { return r.lo[k] < p && r.hi[k] > p; };
        int crossing = 0;
        for (int i = first; i < first + count; ++i) crossing += crosses(refs_[size_t(i)]);
        if (crossing > slack) return -1;

        const float area_l = split.left_box.half_area(), area_r = split.right_box.half_area();
        const float n_l = float(split.left_count), n_r = float(split.right_count);
        const float cost_split = area_l * n_l + area_r * n_r;
        // Left refs are written back in place (never ahead of the one being read), right ones
        // collected and written after them.
        thread_local std::vector<PrimRef> right_refs;
        right_refs.clear();
        int l = first;
        for (int i = first; i < first + count; ++i) {
            PrimRef r = refs_[size_t(i)];
            if (r.hi[k] <= p) {
                refs_[size_t(l++)] = r;
                continue;
            }
            if (r.lo[k] >= p) {
                right_refs.push_back(r);
                continue;
            }
            Bounds4 whole;
            whole.extend(r.box_lo(), r.box_hi());
            Bounds4 left_with = split.left_box, right_with = split.right_box;
            left_with.extend(whole);
            right_with.extend(whole);
            const float cost_left = left_with.half_area() * n_l + area_r * (n_r - 1);
            const float cost_right = area_l * (n_l - 1) + right_with.half_area() * n_r;
            if (cost_left < cost_split && cost_left <= cost_right) {
                refs_[size_t(l++)] = r;
                continue;
            }
            if (cost_right < cost_split) {
                right_refs.push_back(r);
                continue;
            }
            const Triangle& t = triangles_[r.index];
            float llo[3], lhi[3], rlo[3], rhi[3];
            bool has_left = clip_triangle(t, r, k, r.lo[k], p, llo, lhi);
            bool has_right = clip_triangle(t, r, k, p, r.hi[k], rlo, rhi);
            // The parts keep the whole triangle's size key, so the object splits below still
            // keep the parts of large triangles together, apart from small ones.
            const float size = r.size;
            if (has_right) {
                PrimRef copy = r;
                copy.set_box(rlo, rhi);
                copy.size = size;
                right_refs.push_back(copy);
            }
            if (has_left || !has_right) {
                if (has_left) r.set_box(llo, lhi);
                r.size = size;
                refs_[size_t(l++)] = r;
            }
        }
        std::copy(right_refs.begin(), right_refs.end(), refs_.begin() + l);
        const int end = l + int(right_refs.size());
        *added = end - (first + count);
        for (int i = first; i < end; ++i) {
            const PrimRef& ref = refs_[size_t(i)];
            (i < l ? left_box : right_box)->extend(ref.box_lo(), ref.box_hi());
            (i < l ? left_keys : right_keys)->extend(ref.keys());
        }
        return l;
    }

    // Partitions [first, first + count) by the split (Hoare's two-pointer scheme), collecting
    // the key bounds of each side on the way; returns the first ref of the right side.
    int partition(int first, int count, const Split& split, Bounds4* left_keys, Bounds4* right_keys) {
        PrimRef* refs = refs_.data();
        int l = first, r = first + count;
        auto goes_left = [&](const PrimRef& p) { return split.map.bin_of(p, split.key) < split.bin; };
        for (;;) {
            while (l < r && goes_left(refs[l])) left_keys->extend(refs[l++].keys());
            while (l < r && !goes_left(refs[r - 1])) right_keys->extend(refs[--r].keys());
            if (l >= r) break;
            std::swap(refs[l], refs[r - 1]);
            left_keys->extend(refs[l++].keys());
            right_keys->extend(refs[--r].keys());
        }
        return l;
    }

    int median_split(int first, int count, const Bounds4& keys, Bounds4* left_box, Bounds4* right_box,
                     Bounds4* left_keys, Bounds4* right_keys) {
        alignas(16) float lo[4], hi[4];
        keys.lo.store(lo);
        keys.hi.store(hi);
        float e[3] = {hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]};
        int axis = e[0] >= e[1] && e[0] >= e[2] ? 0 : (e[1] >= e[2] ? 1 : 2);
        int mid = first + count / 2;
        PrimRef* refs = refs_.data();
        std::nth_element(refs + first, refs + mid, refs + first + count,
                         [axis](const PrimRef& a, const PrimRef& b) { return a.key(axis) < b.key(axis); });
        for (int i = first; i < first + count; ++i) {
            Bounds4& b = i < mid ? *left_box : *right_box;
            Bounds4& k = i < mid ? *left_keys : *right_keys;
            b.extend(refs[i].box_lo(), refs[i].box_hi());
            k.extend(refs[i].keys());
        }
        return mid;
    }

    const std::vector<Triangle>& triangles_;
    std::vector<PrimRef>& refs_;
    std::unique_ptr<BuildNode[]> nodes_;
    int threads_;
    float root_area_;
    int spawn_depth_ = 0;
    std::atomic<int> next_{1};  // node 0 is the root
    std::atomic<int> max_depth_{0};
    std::atomic<int> spatial_splits_{0};
};

// Collapses the binary tree into BVH_WIDTH-wide nodes and writes them depth-first.
//
// Which binary nodes become wide nodes, which become leaves and which are opened (their children
// taking their place) is chosen for the least SAH cost over the whole tree (Ylitie et al. 2017):
// cost(n, i), the least cost of binary subtree n spread over at most i child slots of a wide
// node, is computed bottom-up, where a slot holds a binary leaf, a subtree of at most
// kMaxLeafSize references merged into one leaf, or a wide node. Against the greedy collapse
// that opens the child of largest area until a node has BVH_WIDTH children (Embree's wide
// builders), which filled nodes with about 4 children on average, this made nodes fuller (22 194
// wide nodes instead of 45 146 on Crytek Sponza, 68 126 instead of 151 338 on the 1M-triangle
// spheres: 24-25% fewer bytes per triangle) and every kind of ray 1.0-1.16x as fast
// (docs/throughput.md, "Wide nodes by the least SAH cost").
//
// Stack bound: a traversal holds, on reaching a wide node, the entries its ancestors pushed
// (`used`), and pushes up to k more for the node's k children. A node's children are allowed
// only if every child x keeps used + (k - 1) + height(x) <= BVH_STACK_SIZE - 1, where height(x)
// is x's binary height (0 for a leaf): a subtree that is never opened again pushes at most one
// entry per binary level, so the bound holds all the way down. Where the least-cost children
// break it, the node takes the greedy collapse's, which opens a child only while it holds. At
// the root used = 0 and the binary build keeps height <= BVH_STACK_SIZE - 1, so the traversal
// stack never overflows.
class Collapser {
public:
    // Writes the wide nodes to `out` and, as it writes each leaf, its triangles to `order`.
    Collapser(const BuildNode* nodes, const std::vector<PrimRef>& refs, std::vector<BvhNode>& out,
              std::vector<uint32_t>& order)
        : nodes_(nodes), refs_(refs), out_(out), order_(order) {}

    // node_count: the binary nodes (indices below it).
    void run(int triangle_count, int node_count) {
        int children[BVH_WIDTH];
        int k = 0;
        if (triangle_count > 0) {
            if (nodes_[0].count > 0) {
                children[k++] = 0;  // a single leaf: the root node holds it as its only child
            } else {
                choice_.resize(size_t(node_count));
                least_cost(0);
                k = open(0, 0, children);
            }
        }
        emit(children, k, 0, 0);
    }

    int max_depth = 0;
    int leaf_count = 0;
    int max_stack = 0;

private:
    static constexpr int kStackLimit = BVH_STACK_SIZE - 1;

    int height(int b) const { return nodes_[b].count > 0 ? 0 : nodes_[b].height; }

    // A child slot holding binary interior node n as one merged leaf is n | kMergedLeaf (binary
    // node indices stay below 2^30: at most two per reference).
    static constexpr int kMergedLeaf = 1 << 30;
    static_assert((size_t(2) << (31 - BVH_LEAF_BITS)) <= size_t(kMergedLeaf), "node indices reach kMergedLeaf");

    bool is_leaf_slot(int slot) const { return (slot & kMergedLeaf) != 0 || nodes_[slot].count > 0; }

    // The choices behind cost(n, i) for binary interior node n: choice_[n][0], how many of a
    // wide node's BVH_WIDTH slots go to n's left child when n is one; choice_[n][1], whether
    // with one slot n is a merged leaf (-1) or a wide node (-2); choice_[n][i] for i >= 2, 0 if
    // n takes at most i - 1 slots, else how many of its i go to the left child.
    std::vector<std::array<int8_t, BVH_WIDTH + 1>> choice_;

    struct SubtreeCost {
        float cost[BVH_WIDTH + 1];  // cost[i], i = 1 .. BVH_WIDTH
        int refs;
    };

    // cost(n, i) for i = 1 .. BVH_WIDTH, filling choice_ below n. Recursion depth: n's binary
    // height, below BVH_STACK_SIZE.
    SubtreeCost least_cost(int n) {
        const BuildNode& b = nodes_[n];
        const float area = b.half_area();
        SubtreeCost out;
        if (b.count > 0) {
            out.refs = b.count;
            for (int i = 1; i <= BVH_WIDTH; ++i) out.cost[i] = area * kCollapseTriangleCost * float(b.count);
            return out;
        }
        const SubtreeCost left = least_cost(b.left), right = least_cost(b.left + 1);
        std::array<int8_t, BVH_WIDTH + 1>& choice = choice_[size_t(n)];
        out.refs = left.refs + right.refs;
        // n opened: its i slots shared between its children.
        float shared[BVH_WIDTH + 1];
        int8_t to_left[BVH_WIDTH + 1] = {};
        for (int i = 2; i <= BVH_WIDTH; ++i) {
            shared[i] = std::numeric_limits<float>::infinity();
            for (int k = 1; k < i; ++k) {
                const float c = left.cost[k] + right.cost[i - k];
                if (c < shared[i]) shared[i] = c, to_left[i] = int8_t(k);
            }
        }
        choice[0] = to_left[BVH_WIDTH];
        const float as_node = area * kCollapseNodeCost + shared[BVH_WIDTH];
        const float as_leaf = out.refs <= kMaxLeafSize ? area * kCollapseTriangleCost * float(out.refs)
                                                       : std::numeric_limits<float>::infinity();
        out.cost[1] = std::min(as_node, as_leaf);
        choice[1] = as_leaf <= as_node ? -1 : -2;
        for (int i = 2; i <= BVH_WIDTH; ++i) {
            const bool opened = shared[i] < out.cost[i - 1];
            out.cost[i] = opened ? shared[i] : out.cost[i - 1];
            choice[size_t(i)] = opened ? to_left[i] : 0;
        }
        return out;
    }

    // Appends the slots that subtree n takes with at most i of them.
    void expand(int n, int i, int* slots, int* k) const {
        const BuildNode& b = nodes_[n];
        if (b.count > 0) {
            slots[(*k)++] = n;
            return;
        }
        const int c = choice_[size_t(n)][size_t(i)];
        if (i == 1) slots[(*k)++] = c == -1 ? (n | kMergedLeaf) : n;
        else if (c == 0) expand(n, i - 1, slots, k);
        else {
            expand(b.left, c, slots, k);
            expand(b.left + 1, i - c, slots, k);
        }
    }

    // Children of the wide node made from binary interior node b, for a traversal holding
    // `used` entries on arrival: those of the least cost, where the stack bound allows them,
    // else those of the greedy collapse.
    int open(int b, int used, int* children) const {
        const int to_left = choice_[size_t(b)][0];
        int k = 0;
        expand(nodes_[b].left, to_left, children, &k);
        expand(nodes_[b].left + 1, BVH_WIDTH - to_left, children, &k);
        bool fits = used + k <= kStackLimit;
        for (int i = 0; i < k && fits; ++i)
            if (!is_leaf_slot(children[i]) && used + k - 1 + height(children[i]) > kStackLimit) fits = false;
        return fits ? k : open_greedy(b, used, children);
    }

    // The greedy collapse's children for b: its two children, then repeatedly the interior
    // child of largest area opened, as far as the stack bound allows.
    int open_greedy(int b, int used, int* children) const {
        int k = 2;
        children[0] = nodes_[b].left;
        children[1] = nodes_[b].left + 1;
        while (k < BVH_WIDTH) {
            // Open the interior child of largest area among those the stack bound allows.
            int best = -1;
            float best_area = -1;
            for (int i = 0; i < k; ++i) {
                const BuildNode& c = nodes_[children[i]];
                if (c.count > 0) continue;
                float area = c.half_area();
                if (area <= best_area) continue;
                // After opening: k + 1 children, the opened one replaced by its two.
                bool fits = used + k + height(c.left) <= kStackLimit && used + k + height(c.left + 1) <= kStackLimit;
                for (int j = 0; j < k && fits; ++j)
                    if (j != i && used + k + height(children[j]) > kStackLimit) fits = false;
                if (!fits) continue;
                best = i;
                best_area = area;
            }
            if (best < 0) break;
            int opened = children[best];
            for (int j = k; j > best + 1; --j) children[j] = children[j - 1];
            children[best] = nodes_[opened].left;
            children[best + 1] = nodes_[opened].left + 1;
            ++k;
        }
        return k;
    }

    // Writes the wide node with the given binary children (k of them) and, after it, their
    // subtrees; returns its index.
    int emit(const int* children, int k, int used, int depth) {
        int index = int(out_.size());
        out_.emplace_back();
        BvhNode node;
        std::memset(&node, 0, sizeof node);
        for (int i = 0; i < BVH_WIDTH; ++i) {
            for (int axis = 0; axis < 3; ++axis) {
                node.bounds[2 * axis][i] = INFINITY;  // empty: no ray enters
                node.bounds[2 * axis + 1][i] = -INFINITY;
            }
            node.child[i] = BVH_LEAF(0, 0);
        }
        max_stack = std::max(max_stack, used + k);
        for (int i = 0; i < k; ++i) {
            const BuildNode& c = nodes_[children[i] & ~kMergedLeaf];
            for (int axis = 0; axis < 3; ++axis) {
                node.bounds[2 * axis][i] = c.lo[axis];
                node.bounds[2 * axis + 1][i] = c.hi[axis];
            }
            if (children[i] & kMergedLeaf) {
                const size_t first = order_.size();
                append_merged(children[i] & ~kMergedLeaf, first);
                node.child[i] = BVH_LEAF(int(first), int(order_.size() - first));
                ++leaf_count;
                max_depth = std::max(max_depth, depth + 1);
            } else if (c.count > 0) {
                // The leaves' triangles are laid out in the order the leaves are written.
                node.child[i] = BVH_LEAF(int(order_.size()), c.count);
                for (int r = c.first; r < c.first + c.count; ++r) order_.push_back(refs_[size_t(r)].index);
                ++leaf_count;
                max_depth = std::max(max_depth, depth + 1);
            } else {
                int grandchildren[BVH_WIDTH];
                int child_used = used + k - 1;
                int kc = open(children[i], child_used, grandchildren);
                node.child[i] = emit(grandchildren, kc, child_used, depth + 1);
            }
        }
        out_[size_t(index)] = node;
        return index;
    }

    // Appends the triangles of binary subtree n's leaves to the order, each once: the parts of a
    // triangle that a spatial split cut apart meet again in a merged leaf (whose box, n's, holds
    // them all). `first`: where the merged leaf starts.
    void append_merged(int n, size_t first) {
        const BuildNode& b = nodes_[n];
        if (b.count == 0) {
            append_merged(b.left, first);
            append_merged(b.left + 1, first);
            return;
        }
        for (int r = b.first; r < b.first + b.count; ++r) {
            const uint32_t t = refs_[size_t(r)].index;
            if (std::find(order_.begin() + std::ptrdiff_t(first), order_.end(), t) == order_.end()) order_.push_back(t);
        }
    }

    const BuildNode* nodes_;
    const std::vector<PrimRef>& refs_;
    std::vector<BvhNode>& out_;
    std::vector<uint32_t>& order_;
};

// Fills refs [begin, end) from the triangles; returns their box and key bounds.
std::pair<Bounds4, Bounds4> make_refs(const std::vector<Triangle>& triangles, std::vector<PrimRef>& refs, size_t begin,
                                      size_t end) {
    Bounds4 box, keys;
    for (size_t i = begin; i < end; ++i) {
        const Triangle& t = triangles[i];
        PrimRef& r = refs[i];
        float lo[3], hi[3];
        for (int k = 0; k < 3; ++k) {
            float a = t.p0.s[k], b = t.p1.s[k], c = t.p2.s[k];
            lo[k] = std::min(a, std::min(b, c));
            hi[k] = std::max(a, std::max(b, c));
        }
        r.set_box(lo, hi);
        r.index = uint32_t(i);
        box.extend(r.box_lo(), r.box_hi());
        keys.extend(r.keys());
    }
    return {box, keys};
}

double seconds_since(std::chrono::steady_clock::time_point start) {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

}  // namespace

Bvh build_bvh(const std::vector<Triangle>& triangles, const BvhOptions& options) {
    auto start = std::chrono::steady_clock::now();
    Bvh bvh;
    size_t n = triangles.size();
    // Leaf entries hold the first triangle in the bits above the count.
    const size_t max_refs = (size_t(1) << (31 - BVH_LEAF_BITS)) - 1;
    if (n > max_refs) throw Error("too many triangles for the BVH: " + std::to_string(n));
    if (n == 0) {
        // A root whose slots are all empty: every ray misses it.
        Collapser collapser(nullptr, {}, bvh.nodes, bvh.order);
        collapser.run(0, 0);
        bvh.build_seconds = seconds_since(start);
        return bvh;
    }

    const double budget = std::max(0.0, double(options.spatial_split_budget));
    const size_t capacity = std::min(max_refs, n + size_t(double(n) * budget));
    std::vector<PrimRef> refs(capacity);
    int threads = int(std::max(1u, std::thread::hardware_concurrency()));
    if (n < size_t(kParallelThreshold)) threads = 1;
    std::vector<std::pair<Bounds4, Bounds4>> bounds(static_cast<size_t>(threads));
    {
        std::vector<std::thread> pool;
        for (int t = 1; t < threads; ++t) {
            pool.emplace_back([&, t] {
                bounds[size_t(t)] = make_refs(triangles, refs, n * size_t(t) / size_t(threads),
                                              n * size_t(t + 1) / size_t(threads));
            });
        }
        bounds[0] = make_refs(triangles, refs, 0, n / size_t(threads));
        for (auto& th : pool) th.join();
    }
    Bounds4 box, keys;
    for (const auto& b : bounds) {
        box.extend(b.first);
        keys.extend(b.second);
    }

    Builder builder(triangles, refs, threads, box.half_area());
    builder.build(0, 0, int(n), int(capacity), 0, box, keys);
    bvh.spatial_splits = builder.spatial_splits();

    bvh.nodes.reserve(size_t(builder.node_count()) / 2 + 1);
    Collapser collapser(builder.nodes(), builder.refs(), bvh.nodes, bvh.order);
    collapser.run(int(n), builder.node_count());
    bvh.max_depth = collapser.max_depth;
    bvh.leaf_count = collapser.leaf_count;
    bvh.max_stack = collapser.max_stack;
    if (builder.max_depth() >= BVH_STACK_SIZE || bvh.max_stack > BVH_STACK_SIZE)
        throw Error("BVH traversal stack bound exceeded (builder bug)");
    bvh.build_seconds = seconds_since(start);
    return bvh;
}

}  // namespace clbdpt
