/* Rays and hits in private memory, and spawning rays off surfaces without self-intersection. */
#ifndef CLBDPT_RAY_H
#define CLBDPT_RAY_H

/* The closest hit of a ray (cl/bvh.h intersect): distance along the ray direction (in units of
 * |d|), barycentrics of the hit point (p = (1 - b1 - b2) p0 + b1 p1 + b2 p2 of the triangle
 * in BVH order) and the triangle's index in BVH order, -1 if the ray hit nothing. */
typedef struct {
    float t;
    float b1;
    float b2;
    int triangle;
} Hit;

/* Self-intersection avoidance after Wächter and Binder, "A Fast and Robust Method for Avoiding
 * Self-Intersection" (Ray Tracing Gems, ch. 6, 2019): the new origin is p moved along the
 * geometric normal to the side that w leaves towards, by a fixed number of ULPs of each
 * coordinate, so the offset scales with the magnitude of p (the floating-point error of a hit
 * point computed from barycentrics grows with it). Coordinates near zero, where an ULP is
 * tiny, are moved by a fixed distance instead.
 *
 * RAY_OFFSET_INT_SCALE: ULPs per unit of normal component (up to 256 ULPs, about 3e-5 relative).
 * RAY_OFFSET_FLOAT_SCALE: absolute offset per unit of normal component for |p| < ORIGIN.
 * RAY_OFFSET_ORIGIN: below this magnitude a coordinate is offset absolutely (at 1/32, 256 ULPs
 * are about 1e-6, below the absolute offset 1.5e-5, so the switch only grows the offset).
 * Values as in the paper, for scenes of roughly unit to thousand-unit scale. */
#define RAY_OFFSET_ORIGIN (1.0f / 32.0f)
#define RAY_OFFSET_FLOAT_SCALE (1.0f / 65536.0f)
#define RAY_OFFSET_INT_SCALE 256.0f

/* p: a point on a surface; ng: the surface's unit geometric normal (either orientation); w: the
 * direction the new ray will leave in. Returns the origin to use for a ray from p along w (or
 * for a shadow ray from p towards a point in direction w). p should be interpolated from the
 * triangle's corners with the hit's barycentrics, not computed as o + t d: the error of the
 * latter scales with |o| and t, not with |p|, and can exceed the offset (a hit on a wall at
 * x = 0 seen from x = 278 lands up to ~1e-4 off the wall). */
inline float3 offset_ray_origin(float3 p, float3 ng, float3 w) {
    float3 n = dot(ng, w) < 0.0f ? -ng : ng;
    int3 of_i = convert_int3(RAY_OFFSET_INT_SCALE * n);
    /* Moving the integer representation changes the magnitude; for negative coordinates an
     * increase of the bits moves towards -infinity, hence the sign flip. */
    float3 p_i = as_float3(as_int3(p) + select(of_i, -of_i, p < 0.0f));
    return select(p_i, p + RAY_OFFSET_FLOAT_SCALE * n, fabs(p) < RAY_OFFSET_ORIGIN);
}

#endif
