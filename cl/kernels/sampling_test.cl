/* Test kernels for cl/sampling.h (tests/sampling_test.cpp): every warp on counter-based random
 * numbers, and find_interval on a given CDF. */
#include "phase.h"
#include "rng.h"
#include "sampling.h"

#define WARP_CONCENTRIC_DISK 0
#define WARP_COSINE_HEMISPHERE 1
#define WARP_UNIFORM_SPHERE 2
#define WARP_UNIFORM_CONE 3
#define WARP_UNIFORM_TRIANGLE 4
#define WARP_HENYEY_GREENSTEIN 5 /* cos_max is g; wo = (0, 0, -1), so straight on is +z */

/* out[i] = (the warped point, its density where sampling.h has one, else 0). Disk and
 * triangle: (x, y, 0, 0) and (b0, b1, 0, 0). Henyey-Greenstein: (wi, the density sampling
 * returned) and, in place of nothing, phase_hg's value is checked through out[i].w as well:
 * w = the returned density when it equals phase_hg, else -1. */
__kernel void warp_test(int warp, float cos_max, uint seed, __global float4* out) {
    int gid = get_global_id(0);
    Rng rng = rng_init((uint)gid, 0u, seed);
    float2 u = rng_next2(&rng);
    float4 r = (float4)(0.0f);
    switch (warp) {
    case WARP_CONCENTRIC_DISK: r.xy = sample_concentric_disk(u); break;
    case WARP_COSINE_HEMISPHERE: {
        float3 w = sample_cosine_hemisphere(u);
        r = (float4)(w, cosine_hemisphere_pdf(w.z));
        break;
    }
    case WARP_UNIFORM_SPHERE: r = (float4)(sample_uniform_sphere(u), INV_4PI_F); break;
    case WARP_UNIFORM_CONE: r = (float4)(sample_uniform_cone(u, 1.0f - cos_max), uniform_cone_pdf(1.0f - cos_max)); break;
    case WARP_UNIFORM_TRIANGLE: r.xy = sample_uniform_triangle(u); break;
    case WARP_HENYEY_GREENSTEIN: {
        float3 wo = (float3)(0.0f, 0.0f, -1.0f), wi;
        float pdf = sample_phase_hg(wo, cos_max, u, &wi);
        float f = phase_hg(wo, wi, cos_max);
        r = (float4)(wi, fabs(f - pdf) <= 1e-4f * pdf || fabs(cos_max) < 1e-3f ? pdf : -1.0f);
        break;
    }
    }
    out[gid] = r;
}

/* out[i] = find_interval(cdf, n, u[i]). */
__kernel void find_interval_test(__global const float* cdf, int n, __global const float* u, __global int* out) {
    int gid = get_global_id(0);
    out[gid] = find_interval(cdf, n, u[gid]);
}

/* out[i] = (unit_circle_turns(u[i]), unit_circle_octant(a[i])): (cos, sin, cos, sin). */
__kernel void unit_circle_test(__global const float* u, __global const float* a, __global float4* out) {
    int gid = get_global_id(0);
    out[gid] = (float4)(unit_circle_turns(u[gid]), unit_circle_octant(a[gid]));
}

/* out[i] = (atan2_turns(y, x), acos_half_turns(c)) for in[i] = (x, y, c, unused). */
__kernel void inverse_trig_test(__global const float4* in, __global float2* out) {
    int gid = get_global_id(0);
    float4 v = in[gid];
    out[gid] = (float2)(atan2_turns(v.y, v.x), acos_half_turns(v.z));
}

/* out[i] = (log_of_normal(x[i]), sample_unit_exponential(u[i])). */
__kernel void log_test(__global const float* x, __global const float* u, __global float2* out) {
    int gid = get_global_id(0);
    out[gid] = (float2)(log_of_normal(x[gid]), sample_unit_exponential(u[gid]));
}

/* out[i] = exp_of_nonpositive(x[i]) (its three channels: x[i], x[i] / 2 and x[i] / 4). */
__kernel void exp_test(__global const float* x, __global float4* out) {
    int gid = get_global_id(0);
    float3 e = exp_of_nonpositive((float3)(x[gid], 0.5f * x[gid], 0.25f * x[gid]));
    out[gid] = (float4)(e.x, e.y, e.z, 0.0f);
}

/* out[i] = (find_interval(cdf, n, u[i]), find_interval_guided(cdf, n, guide, g, u[i])). */
__kernel void find_interval_guided_test(__global const float* cdf, int n, __global const float* guide, int g,
                                        __global const float* u, __global int2* out) {
    int gid = get_global_id(0);
    out[gid] = (int2)(find_interval(cdf, n, u[gid]), find_interval_guided(cdf, n, guide, g, u[gid]));
}
