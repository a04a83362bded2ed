/* Warps from the unit square to the domains the renderer samples, each with its density. */
#ifndef CLBDPT_SAMPLING_H
#define CLBDPT_SAMPLING_H

#include "geometry.h"

/* Shirley-Chiu concentric map: the unit square onto the unit disk, area-preserving. */
inline float2 sample_concentric_disk(float2 u) {
    float2 o = 2.0f * u - (float2)(1.0f, 1.0f);
    if (o.x == 0.0f && o.y == 0.0f) return (float2)(0.0f, 0.0f);
    /* The polar angle is pi/4 * (y/x) in the wedges about the x axis and pi/2 - pi/4 * (x/y) in
     * those about the y axis, whose cosine and sine are the sine and cosine of pi/4 * (x/y): the
     * angles stay within an octant (geometry.h). */
    if (fabs(o.x) > fabs(o.y)) return o.x * unit_circle_octant((PI_F / 4.0f) * (o.y / o.x));
    float2 cs = unit_circle_octant((PI_F / 4.0f) * (o.x / o.y));
    return o.y * (float2)(cs.y, cs.x);
}

/* A draw of the exponential distribution of rate 1: -ln(1 - u) for u in [0, 1). 1 - u is at
 * least 2^-24 for the renderer's draws (24 bits), a normal float, and 1 for u = 0 (depth 0). */
inline float sample_unit_exponential(float u) { return -log_of_normal(1.0f - u); }

/* Cosine-weighted direction about +z; density cos(theta) / pi. */
inline float3 sample_cosine_hemisphere(float2 u) {
    float2 d = sample_concentric_disk(u);
    float z = sqrt(fmax(0.0f, 1.0f - d.x * d.x - d.y * d.y));
    return (float3)(d.x, d.y, z);
}

inline float cosine_hemisphere_pdf(float cos_theta) { return fmax(cos_theta, 0.0f) * INV_PI_F; }

inline float3 sample_uniform_sphere(float2 u) {
    float z = 1.0f - 2.0f * u.x;
    float r = sqrt(fmax(0.0f, 1.0f - z * z));
    float2 cs = unit_circle_turns(u.y);
    return (float3)(r * cs.x, r * cs.y, z);
}

/* Uniform direction inside a cone about +z whose half angle has 1 - cos = one_minus_cos_max (in
 * (0, 2]). Drawn as 1 - cos, and sin from it as sqrt(v (2 - v)): for a cone of a hundredth of a
 * degree cos rounds to 1 in float, but sin, and so the direction, stay accurate. */
inline float3 sample_uniform_cone(float2 u, float one_minus_cos_max) {
    float v = u.x * one_minus_cos_max;
    float sin_theta = sqrt(fmax(0.0f, v * (2.0f - v)));
    float2 cs = unit_circle_turns(u.y);
    return (float3)(cs.x * sin_theta, cs.y * sin_theta, 1.0f - v);
}

inline float uniform_cone_pdf(float one_minus_cos_max) { return 1.0f / (2.0f * PI_F * one_minus_cos_max); }

/* 1 - cos of the angle between unit vectors w and axis, accurate for small angles as well
 * (|w x axis|^2 / (1 + cos) there, rather than 1 - cos, which cancels to 0 below ~3e-4 rad). */
inline float one_minus_cos_between(float3 w, float3 axis) {
    float c = dot(w, axis);
    return c > 0.5f ? length_squared(cross(w, axis)) / (1.0f + c) : 1.0f - c;
}

/* Uniform point on a triangle as barycentrics (b0, b1); b2 = 1 - b0 - b1. Heitz's
 * low-distortion map (2019, "A Low-Distortion Map Between Triangle and Square"; pbrt-v4's
 * SampleUniformTriangle): the square's halves either side of its diagonal are sheared onto the
 * triangle, so strata of u stay compact on it (the square-root map squeezes those near u.x = 0
 * into slivers at one corner), and it takes no square root. */
inline float2 sample_uniform_triangle(float2 u) {
    float b0, b1;
    if (u.x < u.y) {
        b0 = 0.5f * u.x;
        b1 = u.y - b0;
    } else {
        b1 = 0.5f * u.y;
        b0 = u.x - b1;
    }
    return (float2)(b0, b1);
}

/* The binary search of find_interval within [lo, hi), given cdf[lo] <= u and either
 * u < cdf[hi] or hi = n. */
inline int find_interval_between(__global const float* cdf, int lo, int hi, float u) {
    while (hi - lo > 1) {
        int mid = (lo + hi) >> 1;
        if (cdf[mid] <= u) lo = mid; else hi = mid;
    }
    return lo;
}

/* Index i with cdf[i] <= u < cdf[i + 1] in a normalised CDF of n + 1 entries (cdf[0] = 0,
 * cdf[n] = 1); entries of zero width are never returned for u in [0, 1). */
inline int find_interval(__global const float* cdf, int n, float u) { return find_interval_between(cdf, 0, n, u); }

/* find_interval(cdf, n, u) by a guide table (Chen's indexed search, 1974): guide[k], for
 * k = 0 .. g, is the interval holding k / g, so the interval holding u lies from guide[k] to
 * guide[k + 1] for k = floor(u g), a range of about n / g intervals, where the plain search
 * halves [0, n) log2(n) times (veach-mis's 5 472 triangle lights: 13 steps, 5% of a path-traced
 * sample). The range's ends are checked against u, so a guide entry off by the rounding of
 * u g costs steps, never a different answer. The guide's ints are stored as float bits: it
 * follows its CDF in one buffer. */
inline int find_interval_guided(__global const float* cdf, int n, __global const float* guide, int g, float u) {
    int k = clamp((int)(u * (float)g), 0, g - 1);
    int lo = as_int(guide[k]), hi = min(as_int(guide[k + 1]) + 1, n);
    if (cdf[lo] > u) lo = 0;
    if (hi < n && cdf[hi] <= u) hi = n;
    return find_interval_between(cdf, lo, hi, u);
}

/* Where u lies within [lo, hi), itself uniform on [0, 1) when u is uniform and falls there: a
 * discrete choice made with u (one light of several, one triangle of an emitter) hands its rest
 * to the chosen item's own sampling, so the points of a stratified 2D draw stay stratified over
 * all the items together instead of each item getting a random subset of them (pbrt-v4's
 * SampleDiscrete, Mitsuba's mesh emitters). Its resolution is u's float spacing over hi - lo. */
inline float rest_of_choice(float u, float lo, float hi) {
    return hi > lo ? fmin((u - lo) / (hi - lo), 0x1.fffffep-1f) : 0.0f;
}

#endif
