/* Ray queries against the BVH of cl/shared/types.h (built by host/bvh/bvh.cpp):
 *   intersect: the closest hit with t in (0, tmax);
 *   occluded:  whether anything is hit with t in (0, tmax).
 * Triangles are two-sided. The ray-triangle test is the watertight one of Woop, Benthin and
 * Wald, "Watertight Ray/Triangle Intersection" (JCGT 2013), as in pbrt-v3 Triangle::Intersect:
 * rays through shared edges and vertices of a closed mesh hit at least one of the triangles. */
#ifndef CLBDPT_BVH_H
#define CLBDPT_BVH_H

#include "shared/types.h"
#include "ray.h"

#ifdef cl_khr_fp64
#pragma OPENCL EXTENSION cl_khr_fp64 : enable
#endif

/* Watertightness needs each edge function to be computed the same way (up to sign) by both
 * triangles sharing the edge: a*b - c*d contracted to fma(a, b, -c*d) is not antisymmetric in
 * its operands and could make both triangles reject a ray through the edge. */
#pragma OPENCL FP_CONTRACT OFF

/* pbrt's gamma(n) = n u / (1 - n u), u = 2^-24: bound on the relative error of n rounded float
 * operations (pbrt-v3 section 3.9.1). */
#define BVH_GAMMA(n) ((float)(n) * 0x1p-24f / (1.0f - (float)(n) * 0x1p-24f))

/* Direction components smaller than this in magnitude are replaced by it (with their sign) in
 * the inverse direction of the slab test, so the inverse stays finite and (plane - o) * inv_d
 * never becomes 0 * inf = NaN. A ray moving 1e-30 per unit t along an axis moves less than any
 * box extent for every t it can reach, so the slab test's answer is that of the exact ray. */
#define BVH_MIN_DIR 1e-30f

/* Per-ray constants of the traversal and of the watertight triangle test. */
typedef struct {
    /* Slab test: origin, inverse direction and, per axis, the float offset in a BvhNode of the
     * near plane (lo[k] = k, hi[k] = 4 + k; the far plane is near ^ 4). */
    float ox, oy, oz;
    float ix, iy, iz;
    int nx, ny, nz;
    int neg_mask; /* bit k: d[k] < 0 */
    /* Triangle test (Woop et al. section 3): kz = axis of the largest |d|, kx and ky the other
     * two in cyclic order (the paper swaps them when d[kz] < 0 to keep the winding; a two-sided
     * test need not); the shear (sx, sy, sz) maps d to (0, 0, 1). */
    int kx, ky, kz;
    float okx, oky, okz; /* origin permuted to (kx, ky, kz) */
    float sx, sy, sz;
} BvhRay;

inline BvhRay bvh_ray(float3 o, float3 d) {
    BvhRay r;
    r.ox = o.x;
    r.oy = o.y;
    r.oz = o.z;
    r.ix = 1.0f / (fabs(d.x) > BVH_MIN_DIR ? d.x : copysign(BVH_MIN_DIR, d.x));
    r.iy = 1.0f / (fabs(d.y) > BVH_MIN_DIR ? d.y : copysign(BVH_MIN_DIR, d.y));
    r.iz = 1.0f / (fabs(d.z) > BVH_MIN_DIR ? d.z : copysign(BVH_MIN_DIR, d.z));
    r.nx = r.ix < 0.0f ? 4 : 0;
    r.ny = r.iy < 0.0f ? 5 : 1;
    r.nz = r.iz < 0.0f ? 6 : 2;
    r.neg_mask = (r.ix < 0.0f ? 1 : 0) | (r.iy < 0.0f ? 2 : 0) | (r.iz < 0.0f ? 4 : 0);

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

/* Slab test of the node's box against [0, tmax] (pbrt-v3 Bounds3::IntersectP with the far
 * distance scaled by 1 + 2 gamma(3) so rounding cannot make a ray miss a box it touches). */
inline bool bvh_hit_box(__global const float* f, const BvhRay* r, float tmax) {
    float tx0 = (f[r->nx] - r->ox) * r->ix;
    float tx1 = (f[r->nx ^ 4] - r->ox) * r->ix;
    float ty0 = (f[r->ny] - r->oy) * r->iy;
    float ty1 = (f[r->ny ^ 4] - r->oy) * r->iy;
    float tz0 = (f[r->nz] - r->oz) * r->iz;
    float tz1 = (f[r->nz ^ 4] - r->oz) * r->iz;
    float t0 = max(max(tx0, ty0), max(tz0, 0.0f));
    float t1 = min(min(tx1, ty1), min(tz1, tmax)) * (1.0f + 2.0f * BVH_GAMMA(3));
    return t0 <= t1;
}

/* Watertight ray-triangle test (Woop et al. 2013; pbrt-v3 Triangle::Intersect). v: the
 * triangle's 12 floats (p0, p1, p2 as float4). On a hit with t in (0, tmax) returns true and
 * sets *t and the barycentrics of p1 and p2. A ray through an edge or vertex (an edge function
 * exactly 0) counts as a hit of every triangle sharing it, which is what makes it watertight. */
inline bool bvh_hit_triangle(__global const float* v, const BvhRay* r, float tmax, float* t_out,
                             float* b1_out, float* b2_out) {
    /* Translate to the ray origin, permute so the ray runs along z, shear to make it (0, 0, 1). */
    float p0z = v[r->kz] - r->okz;
    float p1z = v[4 + r->kz] - r->okz;
    float p2z = v[8 + r->kz] - r->okz;
    float p0x = v[r->kx] - r->okx + r->sx * p0z;
    float p0y = v[r->ky] - r->oky + r->sy * p0z;
    float p1x = v[4 + r->kx] - r->okx + r->sx * p1z;
    float p1y = v[4 + r->ky] - r->oky + r->sy * p1z;
    float p2x = v[8 + r->kx] - r->okx + r->sx * p2z;
    float p2y = v[8 + r->ky] - r->oky + r->sy * p2z;

    /* Edge functions: twice the signed areas of the sub-triangles opposite each vertex. */
    float e0 = p1x * p2y - p1y * p2x;
    float e1 = p2x * p0y - p2y * p0x;
    float e2 = p0x * p1y - p0y * p1x;
#ifdef cl_khr_fp64
    /* An edge function of exactly 0 may be a rounding artefact: redo it in double, where the
     * float products are exact, so the sign is the exact one (Woop et al. section 3.2). */
    if (e0 == 0.0f || e1 == 0.0f || e2 == 0.0f) {
        e0 = (float)((double)p1x * (double)p2y - (double)p1y * (double)p2x);
        e1 = (float)((double)p2x * (double)p0y - (double)p2y * (double)p0x);
        e2 = (float)((double)p0x * (double)p1y - (double)p0y * (double)p1x);
    }
#endif
    /* Inside iff no edge function has the opposite sign of another (zeros count as inside). */
    if ((e0 < 0.0f || e1 < 0.0f || e2 < 0.0f) && (e0 > 0.0f || e1 > 0.0f || e2 > 0.0f)) return false;
    float det = e0 + e1 + e2;
    if (det == 0.0f) return false;

    /* Scaled distance: t * det. Compare against the range without dividing. */
    p0z *= r->sz;
    p1z *= r->sz;
    p2z *= r->sz;
    float t_scaled = e0 * p0z + e1 * p1z + e2 * p2z;
    if (det < 0.0f ? (t_scaled >= 0.0f || t_scaled <= tmax * det) : (t_scaled <= 0.0f || t_scaled >= tmax * det))
        return false;
    float inv_det = 1.0f / det;
    float t = t_scaled * inv_det;

    /* Make sure t is conservatively greater than zero (pbrt-v3 section 3.9.6): reject hits
     * whose t could be positive only because of rounding. */
    float max_zt = max(max(fabs(p0z), fabs(p1z)), fabs(p2z));
    float delta_z = BVH_GAMMA(3) * max_zt;
    float max_xt = max(max(fabs(p0x), fabs(p1x)), fabs(p2x));
    float max_yt = max(max(fabs(p0y), fabs(p1y)), fabs(p2y));
    float delta_x = BVH_GAMMA(5) * (max_xt + max_zt);
    float delta_y = BVH_GAMMA(5) * (max_yt + max_zt);
    float delta_e = 2.0f * (BVH_GAMMA(2) * max_xt * max_yt + delta_y * max_xt + delta_x * max_yt);
    float max_e = max(max(fabs(e0), fabs(e1)), fabs(e2));
    float delta_t = 3.0f * (BVH_GAMMA(3) * max_e * max_zt + delta_e * max_zt + delta_z * max_e) * fabs(inv_det);
    if (t <= delta_t) return false;

    *t_out = t;
    *b1_out = e1 * inv_det;
    *b2_out = e2 * inv_det;
    return true;
}

/* Closest hit along o + t d with t in (0, tmax). d need not be unit length. On a miss returns
 * false and leaves hit->triangle = -1, hit->t = tmax. */
inline bool intersect(__global const BvhNode* nodes, __global const Triangle* tris, float3 o, float3 d,
                      float tmax, Hit* hit) {
    BvhRay r = bvh_ray(o, d);
    int stack[BVH_MAX_DEPTH];
    int sp = 0;
    int index = 0;
    hit->t = tmax;
    hit->b1 = 0.0f;
    hit->b2 = 0.0f;
    hit->triangle = -1;
    for (;;) {
        __global const BvhNode* node = nodes + index;
        if (bvh_hit_box((__global const float*)node, &r, hit->t)) {
            uint meta = node->meta;
            int offset = node->offset;
            uint count = meta & BVH_META_COUNT_MASK;
            if (count == 0) {
                /* Interior: visit the child on the near side of the split plane first. */
                if ((r.neg_mask >> (meta >> BVH_META_AXIS_SHIFT)) & 1) {
                    stack[sp++] = index + 1;
                    index = offset;
                } else {
                    stack[sp++] = offset;
                    index = index + 1;
                }
                continue;
            }
            for (int i = offset; i < offset + (int)count; ++i) {
                float t, b1, b2;
                if (bvh_hit_triangle((__global const float*)(tris + i), &r, hit->t, &t, &b1, &b2)) {
                    hit->t = t;
                    hit->b1 = b1;
                    hit->b2 = b2;
                    hit->triangle = i;
                }
            }
        }
        if (sp == 0) break;
        index = stack[--sp];
    }
    return hit->triangle >= 0;
}

/* Whether anything is hit along o + t d with t in (0, tmax): shadow rays, visibility tests. */
inline bool occluded(__global const BvhNode* nodes, __global const Triangle* tris, float3 o, float3 d,
                     float tmax) {
    BvhRay r = bvh_ray(o, d);
    int stack[BVH_MAX_DEPTH];
    int sp = 0;
    int index = 0;
    for (;;) {
        __global const BvhNode* node = nodes + index;
        if (bvh_hit_box((__global const float*)node, &r, tmax)) {
            uint meta = node->meta;
            int offset = node->offset;
            uint count = meta & BVH_META_COUNT_MASK;
            if (count == 0) {
                if ((r.neg_mask >> (meta >> BVH_META_AXIS_SHIFT)) & 1) {
                    stack[sp++] = index + 1;
                    index = offset;
                } else {
                    stack[sp++] = offset;
                    index = index + 1;
                }
                continue;
            }
            for (int i = offset; i < offset + (int)count; ++i) {
                float t, b1, b2;
                if (bvh_hit_triangle((__global const float*)(tris + i), &r, tmax, &t, &b1, &b2)) return true;
            }
        }
        if (sp == 0) break;
        index = stack[--sp];
    }
    return false;
}

#endif
