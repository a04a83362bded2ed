/* Test kernel: the 2D values of draw `draw` for samples 0 .. n-1 of one pixel. */
#include "rng.h"

__kernel void sample_values(uint pixel, uint seed, uint draw, __global float2* out) {
    uint i = get_global_id(0);
    Rng rng = rng_init(pixel, i, seed);
    rng.dimension = draw;
    out[i] = rng_next2(&rng);
}
