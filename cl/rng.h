/* Counter-based random numbers: every value is a hash of (seed, pixel, sample index,
 * dimension), so an image does not depend on how work is split across work-groups, launches
 * or devices, and any sample can be recomputed on its own (STYLE.md, "Tests that prove
 * something"). */
#ifndef CLBDPT_RNG_H
#define CLBDPT_RNG_H

/* "lowbias32" integer hash (C. Wellons, hash-prospector): a full-avalanche 32-bit permutation. */
inline uint hash_u32(uint x) {
    x ^= x >> 16;
    x *= 0x7feb352du;
    x ^= x >> 15;
    x *= 0x846ca68bu;
    x ^= x >> 16;
    return x;
}

typedef struct {
    uint key;       /* hash of (seed, pixel, sample) */
    uint dimension; /* how many numbers this sample has drawn */
} Rng;

inline Rng rng_init(uint pixel, uint sample_index, uint seed) {
    Rng rng;
    rng.key = hash_u32(hash_u32(hash_u32(seed ^ 0x5bd1e995u) ^ pixel) ^ hash_u32(sample_index + 0x68e31da4u));
    rng.dimension = 0;
    return rng;
}

/* Uniform in [0, 1): the top 24 bits, so 1.0f can never come out. */
inline float rng_next(Rng* rng) {
    uint bits = hash_u32(rng->key ^ hash_u32(rng->dimension * 0x9e3779b9u + 0x632be5abu));
    rng->dimension++;
    return (float)(bits >> 8) * (1.0f / 16777216.0f);
}

inline float2 rng_next2(Rng* rng) {
    float a = rng_next(rng);
    float b = rng_next(rng);
    return (float2)(a, b);
}

#endif
