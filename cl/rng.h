/* The stream of sample values a work item draws, one "dimension" per call. Every value is a
 * function of (seed, pixel, sample index, dimension) alone, so an image does not depend on how
 * work is split across work-groups, launches or devices, and any sample can be recomputed on
 * its own (STYLE.md, "Tests that prove something").
 *
 * Three samplers (the kernel is built with one):
 *   independent            a hash of (seed, pixel, sample, dimension): uniform random numbers;
 *   SAMPLER_SOBOL (default) padded Owen-scrambled Sobol (Burley 2020, "Practical Hash-based Owen
 *                          Scrambling"; pbrt-v4 PaddedSobolSampler): every 1D or 2D draw gets its
 *                          own pair of the (0,2)-sequence — the first two Sobol dimensions —
 *                          with the sample index shuffled and the values Owen-scrambled by
 *                          hashes of (pixel, draw), so each 2D decision of a path (pixel
 *                          position, lens, BSDF direction, light point) is stratified across
 *                          a pixel's samples and draws are decorrelated from each other;
 *   SAMPLER_ZSOBOL         the same points ordered over the image as blue noise (below). */
#ifndef CLBDPT_RNG_H
#define CLBDPT_RNG_H

/* The integer steps below are written once as statement macros and used on one value and on
 * four lanes (rng_draws4, which computes four draws in one SIMD pass). */

/* "lowbias32" integer hash (C. Wellons, hash-prospector): a full-avalanche 32-bit permutation. */
#define HASH_U32_STEPS(x) \
    x ^= x >> 16;         \
    x *= 0x7feb352du;     \
    x ^= x >> 15;         \
    x *= 0x846ca68bu;     \
    x ^= x >> 16
inline uint hash_u32(uint x) {
    HASH_U32_STEPS(x);
    return x;
}

/* LLVM's bitreverse where the compiler has it: a byte swap and three mask steps on x86, one
 * instruction on GPUs. */
#if defined(__has_builtin)
#if __has_builtin(__builtin_bitreverse32)
#define CLBDPT_HAS_BITREVERSE
#endif
#endif

#define REVERSE_BITS_STEPS(x)                                        \
    x = ((x >> 1) & 0x55555555u) | ((x & 0x55555555u) << 1);       \
    x = ((x >> 2) & 0x33333333u) | ((x & 0x33333333u) << 2);       \
    x = ((x >> 4) & 0x0f0f0f0fu) | ((x & 0x0f0f0f0fu) << 4);       \
    x = ((x >> 8) & 0x00ff00ffu) | ((x & 0x00ff00ffu) << 8);       \
    x = (x >> 16) | (x << 16)
inline uint reverse_bits(uint x) {
#ifdef CLBDPT_HAS_BITREVERSE
    return __builtin_bitreverse32(x);
#else
    REVERSE_BITS_STEPS(x);
    return x;
#endif
}

typedef struct {
    uint key;          /* hash of (seed, pixel); the sample index is mixed in per draw */
    uint sample_index;
#ifdef SAMPLER_SOBOL
    uint sample_index_reversed; /* its bit reversal, the input of every draw's index shuffle */
#endif
    uint dimension;    /* the next draw (cl/sample_dimensions.h) */
#ifdef SAMPLER_ZSOBOL
    ulong morton_index; /* (Morton code of the pixel << log2_spp) | sample index */
    int log2_spp;
    int base4_digits;
#endif
} Rng;

inline Rng rng_init(uint pixel, uint sample_index, uint seed) {
    Rng rng;
    rng.key = hash_u32(hash_u32(seed ^ 0x5bd1e995u) ^ pixel);
    rng.sample_index = sample_index;
    rng.dimension = 0;
#ifdef SAMPLER_SOBOL
    rng.sample_index_reversed = reverse_bits(sample_index);
#endif
    return rng;
}

/* Moves the stream to draw `draw` of the sample vector (cl/sample_dimensions.h). */
inline void rng_seek(Rng* rng, uint draw) { rng->dimension = draw; }

/* 32 random bits -> [0, 1): the top 24 bits, so 1.0f can never come out. */
inline float bits_to_unit_float(uint bits) { return (float)(bits >> 8) * (1.0f / 16777216.0f); }

#if defined(SAMPLER_SOBOL) || defined(SAMPLER_ZSOBOL)

/* The hash at the heart of nested uniform (Owen) scrambling: each output bit depends only on
 * the input bits below it (Laine-Karras style; constants from pbrt-v4's FastOwenScrambler).
 * Applied to a bit-reversed value it flips each digit of the binary fraction depending only on
 * the digits before it, which is Owen scrambling. */
#define OWEN_HASH_STEPS(v, seed) \
    v ^= v * 0x3d20adeau;        \
    v += seed;                   \
    v *= (seed >> 16) | 1u;      \
    v ^= v * 0x05526c56u;        \
    v ^= v * 0x53a22864u
inline uint owen_hash(uint v, uint seed) {
    OWEN_HASH_STEPS(v, seed);
    return v;
}

/* Owen scrambling of v, given v's bit reversal. */
inline uint owen_scramble_reversed(uint v_reversed, uint seed) { return reverse_bits(owen_hash(v_reversed, seed)); }

/* Second Sobol dimension, bit-reversed, so the result can go straight into owen_hash. (The first
 * dimension is the bit reversal of the index, reversed: the index itself.) Its generator is the
 * Pascal matrix mod 2: column k has row j set iff j's bits are a subset of k's (Lucas), so
 * row j of the product is the parity of the index bits k that are supersets of j, a subset-sum
 * (zeta) transform over 5-bit positions: five shift-and-xor steps instead of a loop over the
 * index's set bits. */
#define SOBOL_DIMENSION1_REVERSED_STEPS(y) \
    y ^= (y >> 1) & 0x55555555u;           \
    y ^= (y >> 2) & 0x33333333u;           \
    y ^= (y >> 4) & 0x0f0f0f0fu;           \
    y ^= (y >> 8) & 0x00ff00ffu;           \
    y ^= (y >> 16) & 0x0000ffffu
inline uint sobol_dimension1_reversed(uint index) {
    uint y = index;
    SOBOL_DIMENSION1_REVERSED_STEPS(y);
    return y;
}
#endif

#ifdef SAMPLER_SOBOL

/* The per-draw seed and the shuffled index: shuffling the index with a nested uniform scramble
 * keeps every power-of-two prefix of a pixel's samples a (0,2)-net, whatever spp is rendered. */
inline uint sobol_draw_seed(const Rng* rng, uint draw) { return hash_u32(rng->key ^ hash_u32(draw + 0x632be5abu)); }

__attribute__((always_inline)) inline float rng_next(Rng* rng) {
    uint seed = sobol_draw_seed(rng, rng->dimension++);
    uint index = owen_scramble_reversed(rng->sample_index_reversed, seed);
    return bits_to_unit_float(reverse_bits(owen_hash(index, hash_u32(seed ^ 0xa511e9b3u))));
}

__attribute__((always_inline)) inline float2 rng_next2(Rng* rng) {
    uint seed = sobol_draw_seed(rng, rng->dimension++);
    uint index = owen_scramble_reversed(rng->sample_index_reversed, seed);
    uint x = reverse_bits(owen_hash(index, hash_u32(seed ^ 0xa511e9b3u)));
    uint y = reverse_bits(owen_hash(sobol_dimension1_reversed(index), hash_u32(seed ^ 0x63d83595u)));
    return (float2)(bits_to_unit_float(x), bits_to_unit_float(y));
}

inline uint4 reverse_bits4(uint4 x) {
#ifdef CLBDPT_HAS_BITREVERSE
    return (uint4)(__builtin_bitreverse32(x.s0), __builtin_bitreverse32(x.s1), __builtin_bitreverse32(x.s2),
                   __builtin_bitreverse32(x.s3));
#else
    REVERSE_BITS_STEPS(x);
    return x;
#endif
}

inline float4 bits_to_unit_float4(uint4 bits) { return convert_float4(bits >> 8) * (1.0f / 16777216.0f); }

/* Four draws at once: lane k of *x and *y are rng_next2's two values at draw draws[k] (and *x's
 * alone rng_next's). The same integer steps as one draw, run over four lanes: a Sobol draw is
 * mostly hashing, and SIMD does four of them for about the price of one. */
__attribute__((always_inline)) inline void rng_draws4(const Rng* rng, uint4 draws, float4* x, float4* y) {
    uint4 inner = draws + 0x632be5abu;
    HASH_U32_STEPS(inner);
    uint4 seed = (uint4)(rng->key) ^ inner;
    HASH_U32_STEPS(seed);
    uint4 index = (uint4)(rng->sample_index_reversed);
    OWEN_HASH_STEPS(index, seed);
    index = reverse_bits4(index);
    uint4 seed_x = seed ^ 0xa511e9b3u, seed_y = seed ^ 0x63d83595u;
    HASH_U32_STEPS(seed_x);
    HASH_U32_STEPS(seed_y);
    uint4 vx = index, vy = index;
    SOBOL_DIMENSION1_REVERSED_STEPS(vy);
    OWEN_HASH_STEPS(vx, seed_x);
    OWEN_HASH_STEPS(vy, seed_y);
    *x = bits_to_unit_float4(reverse_bits4(vx));
    *y = bits_to_unit_float4(reverse_bits4(vy));
}

#elif defined(SAMPLER_ZSOBOL)

/* The 24 permutations of a base-4 digit. */
__constant uchar ZSOBOL_PERMUTATIONS[24][4] = {
    {0, 1, 2, 3}, {0, 1, 3, 2}, {0, 2, 1, 3}, {0, 2, 3, 1}, {0, 3, 2, 1}, {0, 3, 1, 2}, {1, 0, 2, 3}, {1, 0, 3, 2},
    {1, 2, 0, 3}, {1, 2, 3, 0}, {1, 3, 2, 0}, {1, 3, 0, 2}, {2, 1, 0, 3}, {2, 1, 3, 0}, {2, 0, 1, 3}, {2, 0, 3, 1},
    {2, 3, 0, 1}, {2, 3, 1, 0}, {3, 1, 2, 0}, {3, 1, 0, 2}, {3, 2, 1, 0}, {3, 2, 0, 1}, {3, 0, 2, 1}, {3, 0, 1, 2}};

inline ulong spread_bits_2d(uint x) {
    ulong v = x;
    v = (v | (v << 16)) & 0x0000ffff0000fffful;
    v = (v | (v << 8)) & 0x00ff00ff00ff00fful;
    v = (v | (v << 4)) & 0x0f0f0f0f0f0f0f0ful;
    v = (v | (v << 2)) & 0x3333333333333333ul;
    v = (v | (v << 1)) & 0x5555555555555555ul;
    return v;
}

/* ZSobol (Ahmed & Wonka 2020, "Screen-space blue-noise diffusion of Monte Carlo sampling
 * error via hierarchical ordering of pixels"; pbrt-v4 ZSobolSampler): one Sobol sequence over
 * the whole image, pixels visited in Morton order and each pixel's samples a consecutive block
 * of 2^log2_spp indices, with the base-4 digits of the index randomly permuted per draw
 * (depending on the digits above them; the permutation is picked by a 32-bit hash of those
 * digits and the draw, where pbrt-v4 uses a 64-bit one: a third of the sampler's cost). Neighbouring pixels then get complementary parts of
 * the sequence: the error is spread as blue noise. It needs the spp up front (rounded up to a
 * power of two); base4_digits = log2(resolution, rounded up to a power of two) +
 * ceil(log2_spp / 2). */
inline Rng rng_init_zsobol(uint px, uint py, uint sample_index, uint seed, int log2_spp, int base4_digits) {
    Rng rng;
    rng.key = hash_u32(seed ^ 0x5bd1e995u);
    rng.sample_index = sample_index;
    rng.dimension = 0;
    rng.morton_index = ((spread_bits_2d(px) | (spread_bits_2d(py) << 1)) << log2_spp) | (ulong)sample_index;
    rng.log2_spp = log2_spp;
    rng.base4_digits = base4_digits;
    return rng;
}

inline ulong zsobol_index(const Rng* rng, uint draw) {
    ulong m = rng->morton_index;
    int odd = rng->log2_spp & 1;
    ulong index = 0;
    for (int i = rng->base4_digits - 1; i >= odd; --i) {
        int shift = 2 * i - odd;
        uint digit = (uint)(m >> shift) & 3u;
        ulong higher = m >> (shift + 2);
        uint p = (hash_u32((uint)higher ^ (uint)(higher >> 32) * 0x9e3779b9u ^ draw * 0x55555555u) >> 8) % 24u;
        index |= (ulong)ZSOBOL_PERMUTATIONS[p][digit] << shift;
    }
    if (odd) {
        ulong higher = m >> 1;
        index |= (m & 1ul) ^ (ulong)(hash_u32((uint)higher ^ (uint)(higher >> 32) * 0x9e3779b9u ^ draw * 0x55555555u) & 1u);
    }
    return index;
}

/* The second Sobol dimension of a 64-bit index, bit-reversed: the Pascal matrix's column k has
 * row j set iff (j & k) == j (Lucas), which for the 32 rows kept depends on k's low 5 bits only:
 * column k + 32 is column k. */
inline uint sobol_dimension1_reversed64(ulong index) {
    return sobol_dimension1_reversed((uint)index) ^ sobol_dimension1_reversed((uint)(index >> 32));
}

inline uint zsobol_draw_seed(const Rng* rng, uint draw) { return hash_u32(rng->key ^ hash_u32(draw + 0x632be5abu)); }

inline float rng_next(Rng* rng) {
    uint draw = rng->dimension++;
    ulong index = zsobol_index(rng, draw);
    uint seed = zsobol_draw_seed(rng, draw);
    return bits_to_unit_float(reverse_bits(owen_hash((uint)index, hash_u32(seed ^ 0xa511e9b3u))));
}

inline float2 rng_next2(Rng* rng) {
    uint draw = rng->dimension++;
    ulong index = zsobol_index(rng, draw);
    uint seed = zsobol_draw_seed(rng, draw);
    uint x = reverse_bits(owen_hash((uint)index, hash_u32(seed ^ 0xa511e9b3u)));
    uint y = reverse_bits(owen_hash(sobol_dimension1_reversed64(index), hash_u32(seed ^ 0x63d83595u)));
    return (float2)(bits_to_unit_float(x), bits_to_unit_float(y));
}

#else

/* Component c of draw d: a hash of (seed, pixel, sample, d, c). A 2D draw is one draw, as in
 * the Sobol sampler, so both samplers follow the same table of draws. */
inline float independent_value(const Rng* rng, uint draw, uint component) {
    uint sample_key = hash_u32(rng->key ^ hash_u32(rng->sample_index + 0x68e31da4u));
    return bits_to_unit_float(hash_u32(sample_key ^ hash_u32((2u * draw + component) * 0x9e3779b9u + 0x632be5abu)));
}

inline float rng_next(Rng* rng) { return independent_value(rng, rng->dimension++, 0u); }

inline float2 rng_next2(Rng* rng) {
    uint draw = rng->dimension++;
    return (float2)(independent_value(rng, draw, 0u), independent_value(rng, draw, 1u));
}

#endif

#ifndef SAMPLER_SOBOL
/* rng_draws4 (above) draw by draw. */
inline void rng_draws4(const Rng* rng, uint4 draws, float4* x, float4* y) {
    Rng r = *rng;
    uint d[4] = {draws.s0, draws.s1, draws.s2, draws.s3};
    float v[2][4];
    for (int k = 0; k < 4; ++k) {
        r.dimension = d[k];
        float2 u = rng_next2(&r);
        v[0][k] = u.x;
        v[1][k] = u.y;
    }
    *x = (float4)(v[0][0], v[0][1], v[0][2], v[0][3]);
    *y = (float4)(v[1][0], v[1][1], v[1][2], v[1][3]);
}
#endif

/* Values beyond the sample vector, for decisions whose number has no bound (a ray through a
 * grid medium meets any number of tentative collisions, cl/medium.h): value k of stream
 * `stream`, a hash of (seed, pixel, sample, stream, k) whatever the sampler, so still a
 * function of the sample alone. Stream numbers must not repeat within a sample. */
inline float rng_stream_value(const Rng* rng, uint stream, uint k) {
    uint h = hash_u32(rng->key ^ hash_u32(rng->sample_index * 0x9e3779b9u ^ hash_u32(stream + 0x3c6ef372u)));
    return bits_to_unit_float(hash_u32(h + k * 0x85ebca6bu));
}

#endif
