/* Ray queries against the BVH of cl/shared/types.h (built by host/bvh/bvh.cpp):
 *   intersect: the closest hit with t in (0, tmax);
 *   occluded:  whether anything is hit with t in (0, tmax), both ends exclusive by the
 *              rounding error of t.
 * With HAS_CUTOUTS, hits that `cutouts` says are holes (cl/cutouts.h) do not count; callers
 * without cut-outs pass a null pointer.
 * Triangles are two-sided. The ray-triangle test is the watertight one of Woop, Benthin and
 * Wald, "Watertight Ray/Triangle Intersection" (JCGT 2013), as in pbrt-v3 Triangle::Intersect:
 * rays through shared edges and vertices of a closed mesh hit at least one of the triangles.
 *
 * The traversal is Embree's single-ray scheme for wide BVHs: one vector slab test for all of a
 * node's BVH_WIDTH child boxes, the children the ray enters pushed nearest on top, and a stack
 * whose entries remember their entry distance so closest-hit queries skip those beyond the
 * closest hit found since. On a CPU it is bound by the latency of fetching nodes, hence the wide
 * nodes (fewer levels) and the prefetches of pushed children. */
#ifndef CLBDPT_BVH_H
#define CLBDPT_BVH_H

#include "shared/types.h"
#include "cutouts.h"
#include "ray.h"

#ifdef cl_khr_fp64
#pragma OPENCL EXTENSION cl_khr_fp64 : enable
#endif

/* Direction components smaller than this in magnitude are replaced by it (with their sign) in
 * the inverse direction of the slab test, so the inverse stays finite and (plane - o) * inv_d
 * never becomes 0 * inf = NaN. The ray then drifts by 1e-30 t along that axis: the slab test
 * could only answer differently from the exact ray at distances above 1e23 times the ray's
 * distance to the slab, far beyond any scene. */
#define BVH_MIN_DIR 1e-30f

/* Per-ray constants of the traversal and of the watertight triangle test. */
typedef struct {
    /* Slab test: origin, negated inverse direction and, per axis, the row of BvhNode::bounds
     * holding the plane the ray meets first (the lower one if it runs towards +k); the far one
     * is near ^ 1. */
    float ox, oy, oz;
    float nix, niy, niz;
    int nx, ny, nz;
    /* Triangle test (Woop et al. section 3): kz = axis of the largest |d|, kx and ky the other
     * two in cyclic order (the paper swaps them when d[kz] < 0 to keep the winding; a two-sided
     * test need not); the shear (sx, sy, sz) maps d to (0, 0, 1). */
    int kx, ky, kz;
    float okx, oky, okz; /* origin permuted to (kx, ky, kz) */
    float sx, sy, sz;
} BvhRay;

__attribute__((always_inline)) inline BvhRay bvh_ray(float3 o, float3 d) {
    BvhRay r;
    r.ox = o.x;
    r.oy = o.y;
    r.oz = o.z;
    /* All three axes in one vector division (the same quotients as three scalar ones). */
    float3 inv = 1.0f / select(copysign((float3)(BVH_MIN_DIR), d), d, isgreater(fabs(d), (float3)(BVH_MIN_DIR)));
    r.nix = -inv.x;
    r.niy = -inv.y;
    r.niz = -inv.z;
    r.nx = inv.x < 0.0f ? 1 : 0;
    r.ny = inv.y < 0.0f ? 3 : 2;
    r.nz = inv.z < 0.0f ? 5 : 4;

    float3 a = fabs(d);
    int kz = a.x > a.y ? (a.x > a.z ? 0 : 2) : (a.y > a.z ? 1 : 2);
    int kx = kz == 2 ? 0 : kz + 1;
    int ky = kx == 2 ? 0 : kx + 1;
    float dv[3] = {d.x, d.y, d.z};
    float ov[3] = {o.x, o.y, o.z};
    r.kx = kx;
    r.ky = ky;
    r.kz = kz;
    r.okx = ov[kx];
    r.oky = ov[ky];
    r.okz = ov[kz];
    r.sz = 1.0f / dv[kz];
    r.sx = -dv[kx] * r.sz;
    r.sy = -dv[ky] * r.sz;
    return r;
}

/* A node's child boxes as vectors of BVH_WIDTH lanes. */
#if BVH_WIDTH == 8
typedef float8 bvh_floatn;
typedef int8 bvh_intn;
#define bvh_vloadn vload8
#define bvh_vstoren vstore8
#elif BVH_WIDTH == 4
typedef float4 bvh_floatn;
typedef int4 bvh_intn;
#define bvh_vloadn vload4
#define bvh_vstoren vstore4
#else
#error "BVH_WIDTH must be 4 or 8"
#endif

/* Slab test of all of a node's child boxes against [0, tmax] (pbrt-v3 Bounds3::IntersectP, one
 * box per lane, with the far distance scaled by 1 + 2 gamma(3) so rounding cannot make a ray
 * miss a box it touches). Returns the lanes whose box the ray enters, and their entry distance.
 * Empty slots (lower +inf, upper -inf) give t0 = +inf > t1 = -inf: never entered. */
__attribute__((always_inline)) inline bvh_intn bvh_hit_boxes(__global const BvhNode* node, const BvhRay* r,
                                                           float tmax, bvh_floatn* t_near) {
    /* (o - plane) * -inv is (plane - o) * inv to the bit (negation is exact), and the plane is
     * then the subtraction's second operand, which x86 reads straight from memory. */
    bvh_floatn tx0 = (r->ox - bvh_vloadn(0, node->bounds[r->nx])) * r->nix;
    bvh_floatn tx1 = (r->ox - bvh_vloadn(0, node->bounds[r->nx ^ 1])) * r->nix;
    bvh_floatn ty0 = (r->oy - bvh_vloadn(0, node->bounds[r->ny])) * r->niy;
    bvh_floatn ty1 = (r->oy - bvh_vloadn(0, node->bounds[r->ny ^ 1])) * r->niy;
    bvh_floatn tz0 = (r->oz - bvh_vloadn(0, node->bounds[r->nz])) * r->niz;
    bvh_floatn tz1 = (r->oz - bvh_vloadn(0, node->bounds[r->nz ^ 1])) * r->niz;
    bvh_floatn t0 = max(max(tx0, ty0), max(tz0, 0.0f));
    bvh_floatn t1 = min(min(tx1, ty1), min(tz1, tmax)) * (1.0f + 2.0f * FLOAT_GAMMA(3));
    *t_near = t0;
    return t0 <= t1;
}

/* The lanes of a 4-lane mask that are set, as bits (lane k: bit k): one movmskps on x86. */
__attribute__((always_inline)) inline uint bvh_mask_bits4(int4 mask) {
#if defined(__SSE__)
    return (uint)__builtin_ia32_movmskps(as_float4(mask));
#else
    uint4 bits = as_uint4(mask) & (uint4)(1u, 2u, 4u, 8u);
    uint2 half_bits = bits.lo | bits.hi;
    return half_bits.x | half_bits.y;
#endif
}

/* The largest of lanes 0-2, and their sum in the order (x + y) + z: the triangle test's
 * reductions over a triangle's three corners (lane 3 is not one). */
__attribute__((always_inline)) inline float bvh_max3(float4 v) { return max(max(v.x, v.y), v.z); }
__attribute__((always_inline)) inline float bvh_sum3(float4 v) { return v.x + v.y + v.z; }

/* Watertight ray-triangle test (Woop et al. 2013; pbrt-v3 Triangle::Intersect, float version)
 * on a triangle stored by rows (cl/shared/types.h): the steps work on the three corners at
 * once, lane i holding corner i, with the scalar test's operations in each lane. On a hit with
 * t in (0, tmax) returns true and sets *t and the barycentrics of p1 and p2. Hits whose t
 * could be 0 or less through rounding do not count; with below_tmax set, neither do those
 * whose t could be tmax or more (visibility between two points: the far point's own surface,
 * just beyond tmax, must not block). A ray through an edge or a vertex (an edge function
 * exactly 0) hits every triangle sharing it, which is what makes the test watertight. */
__attribute__((always_inline)) inline bool bvh_hit_triangle(__global const TriangleRows* tri, const BvhRay* r,
                                                            float tmax, bool below_tmax, float* t_out, float* b1_out,
                                                            float* b2_out) {
    /* Watertightness needs both triangles sharing an edge to compute its edge function the
     * same way up to sign: a*b - c*d contracted to fma(a, b, -c*d) is not antisymmetric in
     * its operands and could make both reject a ray through the edge. (Scoped to this
     * function: the rest of the kernel may contract.) */
#pragma OPENCL FP_CONTRACT OFF
    /* Translate to the ray origin, permute so the ray runs along z, shear to make it (0, 0, 1):
     * one row per axis (lane 3, the normal's, is carried along unread). */
    float4 pz = tri->row[r->kz] - r->okz;
    float4 px = tri->row[r->kx] - r->okx + r->sx * pz;
    float4 py = tri->row[r->ky] - r->oky + r->sy * pz;

    /* Edge functions, twice the signed areas of the sub-triangles opposite each corner:
     * e0 = p1x p2y - p1y p2x, e1 = p2x p0y - p2y p0x, e2 = p0x p1y - p0y p1x, and e2 again in
     * lane 3 so that the sign masks below see three edges. Which of them are negative,
     * positive and zero come as bits of one vector compare each: which signs a missed
     * triangle's edge functions have is data that a branch per comparison mispredicted, while
     * the one branch below, on whether the ray misses, is well predicted. */
    float4 e = px.yzxx * py.zxyy - py.yzxx * px.zxyy;
    uint negative = bvh_mask_bits4(e < 0.0f), positive = bvh_mask_bits4(e > 0.0f);
#ifdef cl_khr_fp64
    /* An edge function of exactly 0 may be a rounding artefact: redo it in double, where the
     * float products are exact, so its sign is the exact one (Woop et al. section 3.2). */
    if (bvh_mask_bits4(e == 0.0f) != 0u) {
        double4 dx = convert_double4(px), dy = convert_double4(py);
        e = convert_float4(dx.yzxx * dy.zxyy - dy.yzxx * dx.zxyy);
        negative = bvh_mask_bits4(e < 0.0f);
        positive = bvh_mask_bits4(e > 0.0f);
    }
#endif
    /* Inside iff no two edge functions have opposite signs (zeros count as inside). */
    if ((negative != 0u) & (positive != 0u)) return false;
    float det = bvh_sum3(e);
    if (det == 0.0f) return false; /* the ray lies in the triangle's plane */

    /* Scaled distance t * det, compared with the range (0, tmax) without dividing. */
    pz *= r->sz;
    float t_scaled = bvh_sum3(e * pz);
    if (det < 0.0f ? (t_scaled >= 0.0f || t_scaled <= tmax * det) : (t_scaled <= 0.0f || t_scaled >= tmax * det))
        return false;
    float inv_det = 1.0f / det;
    float t = t_scaled * inv_det;

    /* Make sure t is conservatively greater than zero (pbrt-v3 section 3.9.6): reject hits
     * whose t could be positive only through rounding. */
    float max_zt = bvh_max3(fabs(pz));
    float delta_z = FLOAT_GAMMA(3) * max_zt;
    float max_xt = bvh_max3(fabs(px));
    float max_yt = bvh_max3(fabs(py));
    float delta_x = FLOAT_GAMMA(5) * (max_xt + max_zt);
    float delta_y = FLOAT_GAMMA(5) * (max_yt + max_zt);
    float delta_e = 2.0f * (FLOAT_GAMMA(2) * max_xt * max_yt + delta_y * max_xt + delta_x * max_yt);
    float max_e = bvh_max3(fabs(e));
    float delta_t = 3.0f * (FLOAT_GAMMA(3) * max_e * max_zt + delta_e * max_zt + delta_z * max_e) * fabs(inv_det);
    if (t <= delta_t || (below_tmax && t >= tmax - delta_t)) return false;

    *t_out = t;
    *b1_out = e.y * inv_det;
    *b2_out = e.z * inv_det;
    return true;
}

/* Prefetching the children a traversal pushes overlaps their cache misses with the work on the
 * nearer child (10-30% more closest-hit rays per second on PoCL with traversal_bench's
 * 1M-triangle scene). OpenCL's prefetch() is a no-op on PoCL, so this uses the compiler's
 * builtin, on CPUs only: GPU back ends need not support it. BVH_PREFETCH_CHILD(p) fetches a
 * node's cache lines from p (4, or 2 at BVH_WIDTH 4; the nodes buffer and so every node start
 * on a line), written out: a loop over lines stayed a loop, 4 instructions a line. A leaf's
 * triangles get the same span, which at BVH_WIDTH 8 covers a leaf's 4 x 48 bytes from anywhere
 * in a line. */
#if defined(__x86_64__) || defined(__aarch64__)
#define BVH_PREFETCH_CHILD(p)                                                                     \
    do {                                                                                          \
        __global const char* p_ = (__global const char*)(p);                                      \
        __builtin_prefetch(p_);                                                                   \
        __builtin_prefetch(p_ + 64);                                                              \
        if (sizeof(BvhNode) > 128) { /* BVH_WIDTH 8 */                                            \
            __builtin_prefetch(p_ + 128);                                                         \
            __builtin_prefetch(p_ + 192);                                                         \
        }                                                                                         \
    } while (0)
#else
#define BVH_PREFETCH_CHILD(p)
#endif

/* Pushes entry c_ at distance d_ onto the stack, keeping the entries pushed for the current
 * node (from `base` on) sorted by distance, nearest on top; stack_t[j] is entry j's distance. */
#define BVH_PUSH_SORTED(c_, d_)                                                                   \
    do {                                                                                          \
        int j_ = sp++;                                                                            \
        while (j_ > base && stack_t[j_ - 1] < (d_)) {                                             \
            stack_t[j_] = stack_t[j_ - 1];                                                        \
            stack_node[j_] = stack_node[j_ - 1];                                                  \
            --j_;                                                                                 \
        }                                                                                         \
        stack_t[j_] = (d_);                                                                       \
        stack_node[j_] = (c_);                                                                    \
    } while (0)

/* intersect: pushes child `lane` (one whose box the ray enters) and prefetches what it points to. */
#define BVH_CLOSEST_LANE(lane)                                                                    \
    {                                                                                             \
        int c_ = node->child[lane];                                                               \
        BVH_PUSH_SORTED(c_, t_nears[lane]);                                                       \
        /* A node's lines, or as many of a leaf's triangles (up to 4 x 48 bytes from anywhere in \
         * a line): chosen without a branch, which whether a child is a leaf would mispredict. */ \
        BVH_PREFETCH_CHILD(c_ >= 0 ? (__global const char*)(nodes + c_)                          \
                                   : (__global const char*)(tris + BVH_LEAF_FIRST(c_)));          \
    }

/* occluded: child `lane` (one whose box the ray enters): a leaf is tested at once, an interior
 * child pushed (unsorted: see occluded). */
#define BVH_ANY_LANE(lane)                                                                        \
    {                                                                                             \
        int c_ = node->child[lane];                                                               \
        if (c_ < 0) {                                                                             \
            if (bvh_leaf_occluded(tris, cutouts, c_, &r, tmax)) return true;                      \
        } else {                                                                                  \
            stack_node[sp++] = c_;                                                                \
            BVH_PREFETCH_CHILD(nodes + c_);                                                       \
        }                                                                                         \
    }

/* The lanes of hit_mask that are set, as bits (lane k: bit k). Where the compiler targets x86
 * with AVX (PoCL on such a CPU), one vmovmskps of the lanes' sign bits; elsewhere the lanes are
 * folded in halves, 7 more instructions a node visit that LLVM does not turn into it. */
__attribute__((always_inline)) inline uint bvh_lane_bits(bvh_intn hit_mask) {
#if BVH_WIDTH == 4
    return bvh_mask_bits4(hit_mask);
#elif defined(__AVX__)
    return (uint)__builtin_ia32_movmskps256(as_float8(hit_mask));
#else
    uint8 bits = as_uint8(hit_mask) & (uint8)(1u, 2u, 4u, 8u, 16u, 32u, 64u, 128u);
    uint4 folded = bits.lo | bits.hi;
    uint2 quarter = folded.lo | folded.hi;
    return quarter.x | quarter.y;
#endif
}

/* The index of the lowest set bit of bits (not 0): on CPUs one tzcnt through the compiler's
 * builtin (OpenCL C 1.2 has no ctz, and LLVM kept 31 - clz(bits & -bits) as 5 instructions). */
__attribute__((always_inline)) inline int bvh_lowest_lane(uint bits) {
#if defined(__x86_64__) || defined(__aarch64__)
    return __builtin_ctz(bits);
#else
    return 31 - (int)clz(bits & (0u - bits));
#endif
}

/* M(lane) for each lane the ray enters, in lane order, as a test of every lane would: a node's
 * ray enters 1-3 of its children's boxes, and a branch per lane cost more than the loop. */
#define BVH_ALL_LANES(M)                                                                          \
    for (uint bits_ = bvh_lane_bits(hit_mask); bits_ != 0u; bits_ &= bits_ - 1u) {                \
        int lane_ = bvh_lowest_lane(bits_);                                                       \
        M(lane_)                                                                                  \
    }

/* Closest hit along o + t d with t in (0, tmax). d need not be unit length; t is in units of
 * |d|. On a miss returns false with hit->triangle = -1 and hit->t = tmax. With exclude_end,
 * hits within the rounding error of t of tmax do not count either (as in occluded): the
 * closest hit strictly inside a segment whose far end lies on a surface.
 * BVH_COUNT_VISITS (a diagnostic build, traversal_bench --count-visits) returns the numbers of
 * nodes visited and triangles tested in hit->b1 and hit->b2 instead of the barycentrics. */
__attribute__((always_inline)) inline bool intersect_closest(__global const BvhNode* nodes,
                                                             __global const TriangleRows* tris, const Cutouts* cutouts,
                                                             float3 o, float3 d, float tmax, bool exclude_end,
                                                             Hit* hit) {
    BvhRay r = bvh_ray(o, d);
    /* Entries still to visit (node index, or leaf entry) and the distance at which the ray
     * enters their boxes. The builder bounds the depth of the stack (host/bvh/bvh.cpp). */
    int stack_node[BVH_STACK_SIZE];
    float stack_t[BVH_STACK_SIZE];
    int sp = 0;
    int current = 0; /* the root, always an interior node */
#ifdef BVH_COUNT_VISITS
    int nodes_visited = 0, triangles_tested = 0;
#define BVH_COUNT(counter) ++counter
#else
#define BVH_COUNT(counter)
#endif
    hit->t = tmax;
    hit->b1 = 0.0f;
    hit->b2 = 0.0f;
    hit->triangle = -1;
    for (;;) {
        if (current >= 0) {
            BVH_COUNT(nodes_visited);
            __global const BvhNode* node = nodes + current;
            bvh_floatn t_near;
            bvh_intn hit_mask = bvh_hit_boxes(node, &r, hit->t, &t_near);
            float t_nears[BVH_WIDTH];
            bvh_vstoren(t_near, 0, t_nears);
            int base = sp;
            BVH_ALL_LANES(BVH_CLOSEST_LANE)
            if (sp > base) {
                current = stack_node[--sp]; /* the nearest child */
                continue;
            }
        } else {
            int first = BVH_LEAF_FIRST(current), end = first + BVH_LEAF_COUNT(current);
            for (int i = first; i < end; ++i) {
                float t, b1, b2;
                BVH_COUNT(triangles_tested);
                if (bvh_hit_triangle(tris + i, &r, hit->t, false, &t, &b1, &b2)) {
#ifdef HAS_CUTOUTS
                    if (cutouts && cutout_hides(cutouts, i, b1, b2)) continue;
#endif
                    if (exclude_end && !bvh_hit_triangle(tris + i, &r, tmax, true, &t, &b1, &b2))
                        continue;
                    hit->t = t;
                    hit->b1 = b1;
                    hit->b2 = b2;
                    hit->triangle = i;
                }
            }
        }
        /* Pop the next entry the ray enters before its closest hit so far. */
        for (;;) {
            if (sp == 0) {
#ifdef BVH_COUNT_VISITS
                hit->b1 = (float)nodes_visited;
                hit->b2 = (float)triangles_tested;
#endif
                return hit->triangle >= 0;
            }
            --sp;
            if (stack_t[sp] <= hit->t) break;
        }
        current = stack_node[sp];
    }
}

inline bool intersect(__global const BvhNode* nodes, __global const TriangleRows* tris, const Cutouts* cutouts,
                      float3 o, float3 d, float tmax, Hit* hit) {
    return intersect_closest(nodes, tris, cutouts, o, d, tmax, false, hit);
}

/* The closest hit on the open segment from o to o + d, its ends' surfaces excluded as in
 * occluded (t in units of |d|, so tmax = 1). */
inline bool intersect_segment(__global const BvhNode* nodes, __global const TriangleRows* tris, const Cutouts* cutouts,
                              float3 o, float3 d, Hit* hit) {
    return intersect_closest(nodes, tris, cutouts, o, d, 1.0f, true, hit);
}

__attribute__((always_inline)) inline bool bvh_leaf_occluded(__global const TriangleRows* tris, const Cutouts* cutouts,
                                                             int leaf, const BvhRay* r, float tmax) {
    int first = BVH_LEAF_FIRST(leaf), end = first + BVH_LEAF_COUNT(leaf);
    for (int i = first; i < end; ++i) {
        float t, b1, b2;
        if (bvh_hit_triangle(tris + i, r, tmax, true, &t, &b1, &b2)) {
#ifdef HAS_CUTOUTS
            if (cutouts && cutout_hides(cutouts, i, b1, b2)) continue;
#endif
            return true;
        }
    }
    return false;
}

/* Whether anything is hit along o + t d with t certainly in (0, tmax) (hits within rounding of
 * either end do not count): shadow rays, visibility tests.
 * Leaf children are tested as soon as the ray is found to enter their box, before any interior
 * child: leaves high in the tree hold large triangles (walls, floors), the likeliest occluders
 * (about 3x faster than visiting them in distance order on traversal_bench's random any-hit
 * rays in a room).
 * Interior children are then visited in the order they were pushed, not sorted by distance:
 * for a query that any occluder ends, sorting cost more than it saved (traversal_bench,
 * 300k triangles, CPU time relative to Embree in the same run: shadow rays to a light 0.83-0.88
 * sorted, 0.97-1.00 unsorted; connections 0.60-0.65 and 0.63-0.71; random any-hit 1.09-1.17 and
 * 1.16-1.18). */
inline bool occluded(__global const BvhNode* nodes, __global const TriangleRows* tris, const Cutouts* cutouts,
                     float3 o, float3 d, float tmax) {
    BvhRay r = bvh_ray(o, d);
    int stack_node[BVH_STACK_SIZE];
    int sp = 0;
    int current = 0;
    for (;;) {
        __global const BvhNode* node = nodes + current;
        bvh_floatn t_near;
        bvh_intn hit_mask = bvh_hit_boxes(node, &r, tmax, &t_near);
        BVH_ALL_LANES(BVH_ANY_LANE)
        if (sp == 0) return false;
        current = stack_node[--sp];
    }
}

#undef BVH_COUNT
#undef BVH_PUSH_SORTED
#undef BVH_CLOSEST_LANE
#undef BVH_ANY_LANE
#undef BVH_ALL_LANES
#undef BVH_PREFETCH_CHILD

#endif
