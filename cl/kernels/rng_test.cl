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
