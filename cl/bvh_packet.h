/* EXPERIMENT: packet traversal, 8 rays per work item in the lanes of float8 (for the throughput
 * issue's question whether width pays on a CPU when traversal is wide too). The rays share one
 * traversal: a node is entered if any ray enters it, a leaf's triangles are tested against all
 * 8 rays at once (a ray that did not enter the leaf's box cannot get a wrong hit from it: every
 * hit found is a hit on the ray). Same watertight test as bvh_hit_triangle, lane by lane. */
#ifndef CLBDPT_BVH_PACKET_H
#define CLBDPT_BVH_PACKET_H

#include "bvh.h"

typedef struct {
    float8 ox, oy, oz;
    float8 ix, iy, iz;
    int8 negx, negy, negz; /* inverse direction negative: -1 */
    int8 kx, ky, kz;
    float8 okx, oky, okz;
    float8 sx, sy, sz;
} PacketRay;

/* Per-lane pick of one of (x, y, z) by axis k (0, 1 or 2). */
__attribute__((always_inline)) inline float8 packet_pick(int8 k, float x, float y, float z) {
    return select(select((float8)(x), (float8)(y), k == 1), (float8)(z), k == 2);
}

__attribute__((always_inline)) inline float packet_hmin(float8 v) {
    float4 a = min(v.lo, v.hi);
    float2 b = min(a.lo, a.hi);
    return min(b.x, b.y);
}

__attribute__((always_inline)) inline float packet_hmax(float8 v) {
    float4 a = max(v.lo, v.hi);
    float2 b = max(a.lo, a.hi);
    return max(b.x, b.y);
}

inline PacketRay packet_ray(const float3* o, const float3* d) {
    float ox[8], oy[8], oz[8], ix[8], iy[8], iz[8], okx[8], oky[8], okz[8], sx[8], sy[8], sz[8];
    int kx[8], ky[8], kz[8];
    for (int j = 0; j < 8; ++j) {
        BvhRay r = bvh_ray(o[j], d[j]);
        ox[j] = r.ox, oy[j] = r.oy, oz[j] = r.oz;
        ix[j] = r.ix, iy[j] = r.iy, iz[j] = r.iz;
        kx[j] = r.kx, ky[j] = r.ky, kz[j] = r.kz;
        okx[j] = r.okx, oky[j] = r.oky, okz[j] = r.okz;
        sx[j] = r.sx, sy[j] = r.sy, sz[j] = r.sz;
    }
    PacketRay p;
    p.ox = vload8(0, ox), p.oy = vload8(0, oy), p.oz = vload8(0, oz);
    p.ix = vload8(0, ix), p.iy = vload8(0, iy), p.iz = vload8(0, iz);
    p.negx = p.ix < 0.0f, p.negy = p.iy < 0.0f, p.negz = p.iz < 0.0f;
    p.kx = vload8(0, kx), p.ky = vload8(0, ky), p.kz = vload8(0, kz);
    p.okx = vload8(0, okx), p.oky = vload8(0, oky), p.okz = vload8(0, okz);
    p.sx = vload8(0, sx), p.sy = vload8(0, sy), p.sz = vload8(0, sz);
    return p;
}

/* Entry distance of each ray into child c's box (t0), valid where t0 <= t1 (t1 clipped to tmax). */
__attribute__((always_inline)) inline int8 packet_hit_box(__global const BvhNode* node, int c, const PacketRay* r,
                                                          float8 tmax, float8* t_near) {
    float8 lox = (float8)(node->bounds[0][c]), hix = (float8)(node->bounds[1][c]);
    float8 loy = (float8)(node->bounds[2][c]), hiy = (float8)(node->bounds[3][c]);
    float8 loz = (float8)(node->bounds[4][c]), hiz = (float8)(node->bounds[5][c]);
    float8 tx0 = (select(lox, hix, r->negx) - r->ox) * r->ix;
    float8 tx1 = (select(hix, lox, r->negx) - r->ox) * r->ix;
    float8 ty0 = (select(loy, hiy, r->negy) - r->oy) * r->iy;
    float8 ty1 = (select(hiy, loy, r->negy) - r->oy) * r->iy;
    float8 tz0 = (select(loz, hiz, r->negz) - r->oz) * r->iz;
    float8 tz1 = (select(hiz, loz, r->negz) - r->oz) * r->iz;
    float8 t0 = max(max(tx0, ty0), max(tz0, 0.0f));
    float8 t1 = min(min(tx1, ty1), min(tz1, tmax)) * (1.0f + 2.0f * FLOAT_GAMMA(3));
    *t_near = t0;
    return t0 <= t1;
}

/* The watertight test of bvh_hit_triangle for the 8 rays against one triangle: the lanes with a
 * hit in (0, tmax) (below_tmax: certainly below tmax), their t and barycentrics. */
__attribute__((always_inline)) inline int8 packet_hit_triangle(__global const float* v, const PacketRay* r,
                                                               float8 tmax, bool below_tmax, float8* t_out,
                                                               float8* b1_out, float8* b2_out) {
#pragma OPENCL FP_CONTRACT OFF
    float8 p0z = packet_pick(r->kz, v[0], v[1], v[2]) - r->okz;
    float8 p1z = packet_pick(r->kz, v[4], v[5], v[6]) - r->okz;
    float8 p2z = packet_pick(r->kz, v[8], v[9], v[10]) - r->okz;
    float8 p0x = packet_pick(r->kx, v[0], v[1], v[2]) - r->okx + r->sx * p0z;
    float8 p0y = packet_pick(r->ky, v[0], v[1], v[2]) - r->oky + r->sy * p0z;
    float8 p1x = packet_pick(r->kx, v[4], v[5], v[6]) - r->okx + r->sx * p1z;
    float8 p1y = packet_pick(r->ky, v[4], v[5], v[6]) - r->oky + r->sy * p1z;
    float8 p2x = packet_pick(r->kx, v[8], v[9], v[10]) - r->okx + r->sx * p2z;
    float8 p2y = packet_pick(r->ky, v[8], v[9], v[10]) - r->oky + r->sy * p2z;
    float8 e0 = p1x * p2y - p1y * p2x;
    float8 e1 = p2x * p0y - p2y * p0x;
    float8 e2 = p0x * p1y - p0y * p1x;
#ifdef cl_khr_fp64
    int8 zero = (e0 == 0.0f) | (e1 == 0.0f) | (e2 == 0.0f);
    if (any(zero)) {
        long8 z = convert_long8(zero);
        e0 = select(e0, convert_float8(convert_double8(p1x) * convert_double8(p2y) - convert_double8(p1y) * convert_double8(p2x)), zero);
        e1 = select(e1, convert_float8(convert_double8(p2x) * convert_double8(p0y) - convert_double8(p2y) * convert_double8(p0x)), zero);
        e2 = select(e2, convert_float8(convert_double8(p0x) * convert_double8(p1y) - convert_double8(p0y) * convert_double8(p1x)), zero);
        (void)z;
    }
#endif
    int8 has_negative = (e0 < 0.0f) | (e1 < 0.0f) | (e2 < 0.0f);
    int8 has_positive = (e0 > 0.0f) | (e1 > 0.0f) | (e2 > 0.0f);
    float8 det = e0 + e1 + e2;
    p0z *= r->sz;
    p1z *= r->sz;
    p2z *= r->sz;
    float8 t_scaled = e0 * p0z + e1 * p1z + e2 * p2z;
    float8 t_signed = select(t_scaled, -t_scaled, det < 0.0f);
    float8 det_abs = fabs(det);
    int8 hit = ~(has_negative & has_positive) & (det != 0.0f) & (t_signed > 0.0f) & (t_signed < tmax * det_abs);
    if (!any(hit)) return hit;
    float8 inv_det = 1.0f / det;
    float8 t = t_scaled * inv_det;
    float8 max_zt = max(max(fabs(p0z), fabs(p1z)), fabs(p2z));
    float8 delta_z = FLOAT_GAMMA(3) * max_zt;
    float8 max_xt = max(max(fabs(p0x), fabs(p1x)), fabs(p2x));
    float8 max_yt = max(max(fabs(p0y), fabs(p1y)), fabs(p2y));
    float8 delta_x = FLOAT_GAMMA(5) * (max_xt + max_zt);
    float8 delta_y = FLOAT_GAMMA(5) * (max_yt + max_zt);
    float8 delta_e = 2.0f * (FLOAT_GAMMA(2) * max_xt * max_yt + delta_y * max_xt + delta_x * max_yt);
    float8 max_e = max(max(fabs(e0), fabs(e1)), fabs(e2));
    float8 delta_t = 3.0f * (FLOAT_GAMMA(3) * max_e * max_zt + delta_e * max_zt + delta_z * max_e) * fabs(inv_det);
    hit &= t > delta_t;
    if (below_tmax) hit &= t < tmax - delta_t;
    *t_out = t;
    *b1_out = e1 * inv_det;
    *b2_out = e2 * inv_det;
    return hit;
}

/* Closest hits of 8 rays (tmax per lane); triangle -1 and t = tmax where a ray misses. */
inline void packet_intersect(__global const BvhNode* nodes, __global const Triangle* tris, const PacketRay* r,
                             float8 tmax, float8* hit_t, float8* hit_b1, float8* hit_b2, int8* hit_tri) {
    int stack_node[BVH_STACK_SIZE * BVH_WIDTH];
    float stack_t[BVH_STACK_SIZE * BVH_WIDTH];
    int sp = 0;
    int current = 0;
    float8 t_best = tmax, b1_best = 0.0f, b2_best = 0.0f;
    int8 tri_best = -1;
    for (;;) {
        if (current >= 0) {
            __global const BvhNode* node = nodes + current;
            int base = sp;
            for (int c = 0; c < BVH_WIDTH; ++c) {
                float8 t_near;
                int8 entered = packet_hit_box(node, c, r, t_best, &t_near);
                if (!any(entered)) continue;
                float d = packet_hmin(select((float8)(INFINITY), t_near, entered));
                int child = node->child[c];
                int j = sp++;
                while (j > base && stack_t[j - 1] < d) {
                    stack_t[j] = stack_t[j - 1];
                    stack_node[j] = stack_node[j - 1];
                    --j;
                }
                stack_t[j] = d;
                stack_node[j] = child;
            }
            if (sp > base) {
                current = stack_node[--sp];
                continue;
            }
        } else {
            int first = BVH_LEAF_FIRST(current), end = first + BVH_LEAF_COUNT(current);
            for (int i = first; i < end; ++i) {
                float8 t, b1, b2;
                int8 hit = packet_hit_triangle((__global const float*)(tris + i), r, t_best, false, &t, &b1, &b2);
                t_best = select(t_best, t, hit);
                b1_best = select(b1_best, b1, hit);
                b2_best = select(b2_best, b2, hit);
                tri_best = select(tri_best, (int8)(i), hit);
            }
        }
        float farthest = packet_hmax(t_best);
        for (;;) {
            if (sp == 0) {
                *hit_t = t_best;
                *hit_b1 = b1_best;
                *hit_b2 = b2_best;
                *hit_tri = tri_best;
                return;
            }
            --sp;
            if (stack_t[sp] <= farthest) break;
        }
        current = stack_node[sp];
    }
}

/* Whether each of 8 rays is occluded in (0, tmax) (-1 lanes). */
inline int8 packet_occluded(__global const BvhNode* nodes, __global const Triangle* tris, const PacketRay* r,
                            float8 tmax) {
    int stack_node[BVH_STACK_SIZE * BVH_WIDTH];
    int sp = 0;
    int current = 0;
    int8 done = 0;
    /* A finished ray's tmax becomes -inf: it enters no more boxes. */
    float8 live_tmax = tmax;
    for (;;) {
        __global const BvhNode* node = nodes + current;
        for (int c = 0; c < BVH_WIDTH; ++c) {
            float8 t_near;
            int8 entered = packet_hit_box(node, c, r, live_tmax, &t_near);
            if (!any(entered)) continue;
            int child = node->child[c];
            if (child < 0) {
                int first = BVH_LEAF_FIRST(child), end = first + BVH_LEAF_COUNT(child);
                for (int i = first; i < end; ++i) {
                    float8 t, b1, b2;
                    int8 hit = packet_hit_triangle((__global const float*)(tris + i), r, tmax, true, &t, &b1, &b2);
                    done |= hit;
                }
                if (all(done)) return done;
                live_tmax = select(tmax, (float8)(-INFINITY), done);
            } else {
                stack_node[sp++] = child;
            }
        }
        if (sp == 0) return done;
        current = stack_node[--sp];
    }
}

#endif
