/* Test kernel for tests/sample_dimensions_test.cpp: the whole sample vector of samples 0 .. n-1
 * of one pixel, out[(i * SAMPLE_DRAW_COUNT + d) * 2 + c] = component c of draw d of sample i. */
#include "rng.h"
#include "sample_dimensions.h"

__kernel void sample_vector(uint pixel, uint seed, __global float* out) {
    uint i = get_global_id(0);
    Rng rng = rng_init(pixel, i, seed);
    for (uint d = 0; d < SAMPLE_DRAW_COUNT; ++d) {
        rng_seek(&rng, d);
        float2 v = rng_next2(&rng);
        out[(i * SAMPLE_DRAW_COUNT + d) * 2] = v.x;
        out[(i * SAMPLE_DRAW_COUNT + d) * 2 + 1] = v.y;
    }
}
