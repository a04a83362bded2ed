/* Test kernels: the 2D values of draw `draw` for samples 0 .. n-1 of one pixel; with
 * SAMPLER_ZSOBOL, of the pixels of a 2x2 quad (item i: pixel (x0 + (q & 1), y0 + (q >> 1)) with
 * q = i >> log2_spp, sample i & (spp - 1)). */
#include "rng.h"

#ifdef SAMPLER_ZSOBOL
__kernel void zsobol_values(uint x0, uint y0, int log2_spp, int base4_digits, uint seed, uint draw,
                            __global float2* out) {
    uint i = get_global_id(0);
    uint q = i >> log2_spp;
    Rng rng = rng_init_zsobol(x0 + (q & 1u), y0 + (q >> 1), i & ((1u << log2_spp) - 1u), seed, log2_spp, base4_digits);
    rng.dimension = draw;
    out[i] = rng_next2(&rng);
}
#else
__kernel void sample_values(uint pixel, uint seed, uint draw, __global float2* out) {
    uint i = get_global_id(0);
    Rng rng = rng_init(pixel, i, seed);
    rng.dimension = draw;
    out[i] = rng_next2(&rng);
}
#endif

/* Item i, sample i of one pixel: rng_draws4 at draws first .. first + 3 against four rng_next2
 * and four rng_next calls. out[8i + k] is rng_next2 at draw first + k and out[8i + 4 + k] lane k
 * of rng_draws4 (x, y); next1[4i + k] is rng_next at draw first + k. ZSobol: pixel (pixel % 64,
 * pixel / 64) of a 64 x 64 image at 256 spp. */
__kernel void draws4_values(uint pixel, uint seed, uint first, __global float2* out, __global float* next1) {
    uint i = get_global_id(0);
#ifdef SAMPLER_ZSOBOL
    Rng rng = rng_init_zsobol(pixel & 63u, pixel >> 6, i, seed, 8, 10);
#else
    Rng rng = rng_init(pixel, i, seed);
#endif
    for (uint k = 0; k < 4u; ++k) {
        rng_seek(&rng, first + k);
        out[8 * i + k] = rng_next2(&rng);
        rng_seek(&rng, first + k);
        next1[4 * i + k] = rng_next(&rng);
    }
    float4 x, y;
    rng_draws4(&rng, (uint4)(first) + (uint4)(0u, 1u, 2u, 3u), &x, &y);
    out[8 * i + 4] = (float2)(x.s0, y.s0);
    out[8 * i + 5] = (float2)(x.s1, y.s1);
    out[8 * i + 6] = (float2)(x.s2, y.s2);
    out[8 * i + 7] = (float2)(x.s3, y.s3);
}
