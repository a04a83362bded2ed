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

/* pbrt's gamma(n) = n u / (1 - n u), u = 2^-24: a bound on the relative error of n rounded
 * float operations (pbrt-v3 section 3.9.1). */
#define FLOAT_GAMMA(n) ((float)(n) * 0x1p-24f / (1.0f - (float)(n) * 0x1p-24f))

/* Ray origins off surfaces, after pbrt-v3 section 3.9.5: a point computed on a triangle carries
 * a bound `p_error` on its distance from the triangle's plane (measured along the normal, from
 * the rounding of the computation that produced it: triangle_point_error, a few ULPs of its
 * coordinates); a ray leaving it starts that far off the plane on the side it leaves toward. The true surface is then behind the origin, so the
 * conservative hit test of cl/bvh.h (which rejects t that is positive only through rounding)
 * cannot find it again, and nothing else is skipped: the offset is as small as the point's own
 * error, at any distance from the scene's origin (a fixed number of ULPs of |p|, as before,
 * is 0.12 units at 5560 and turned a 0.56-unit box 3% darker there).
 *
 * p: a point on a surface; ng: the surface's unit geometric normal (either orientation, 0 off
 * surfaces: no offset); p_error: p's error bound along ng; w: the direction the new ray leaves
 * in (or toward the point a shadow ray goes to). */
inline float3 offset_ray_origin(float3 p, float3 ng, float p_error, float3 w) {
    /* Plus a bound on the rounding of the sum below (half an ULP of each coordinate), so the
     * rounding cannot take back part of the offset. */
    float d = p_error + FLOAT_GAMMA(1) * dot(fabs(ng), fabs(p) + p_error);
    return p + (dot(ng, w) < 0.0f ? -d : d) * ng;
}

#endif
