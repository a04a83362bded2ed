/* Lanes: PT_LANES samples side by side in one work item, one per vector lane (the wide path
 * tracer, cl/path_tracer_wide.h). PoCL runs a work group's items one after another and does not
 * vectorise a kernel with divergent loops across them (docs/throughput.md), so width on a CPU
 * has to be written out: here a floatw holds one float of each of PT_LANES samples, and a
 * float3w one point or direction of each.
 *
 * Every helper does per lane exactly the operations of its scalar counterpart (cl/geometry.h,
 * cl/sampling.h, cl/rng.h), in the same order, so a lane computes what a scalar work item
 * computes; both branches of a scalar `if` are computed and one is kept with select(). */
#ifndef CLBDPT_LANES_H
#define CLBDPT_LANES_H

#include "geometry.h"
#include "rng.h"

#ifndef PT_LANES
#define PT_LANES 8
#endif

#if PT_LANES == 4
typedef float4 floatw;
typedef int4 intw;
typedef uint4 uintw;
#define VLOADW vload4
#define VSTOREW vstore4
#define CONVERT_FLOATW convert_float4
#define CONVERT_INTW convert_int4
#elif PT_LANES == 8
typedef float8 floatw;
typedef int8 intw;
typedef uint8 uintw;
#define VLOADW vload8
#define VSTOREW vstore8
#define CONVERT_FLOATW convert_float8
#define CONVERT_INTW convert_int8
#elif PT_LANES == 16
typedef float16 floatw;
typedef int16 intw;
typedef uint16 uintw;
#define VLOADW vload16
#define VSTOREW vstore16
#define CONVERT_FLOATW convert_float16
#define CONVERT_INTW convert_int16
#else
#error "PT_LANES must be 4, 8 or 16"
#endif

/* Masks are intw with every bit set (-1) in a lane where the condition holds, as OpenCL's
 * vector comparisons give them; select(a, b, m) keeps b in those lanes and a elsewhere. */
inline int any_lane(intw m) { return any(m); }

typedef struct {
    floatw x, y, z;
} float3w;

inline float3w f3w(floatw x, floatw y, floatw z) {
    float3w v;
    v.x = x;
    v.y = y;
    v.z = z;
    return v;
}
inline float3w splat3w(float3 v) { return f3w((floatw)(v.x), (floatw)(v.y), (floatw)(v.z)); }
inline float3w add3w(float3w a, float3w b) { return f3w(a.x + b.x, a.y + b.y, a.z + b.z); }
inline float3w sub3w(float3w a, float3w b) { return f3w(a.x - b.x, a.y - b.y, a.z - b.z); }
inline float3w mul3w(float3w a, float3w b) { return f3w(a.x * b.x, a.y * b.y, a.z * b.z); }
inline float3w scale3w(float3w a, floatw s) { return f3w(a.x * s, a.y * s, a.z * s); }
inline float3w neg3w(float3w a) { return f3w(-a.x, -a.y, -a.z); }
inline float3w fabs3w(float3w a) { return f3w(fabs(a.x), fabs(a.y), fabs(a.z)); }
/* dot() of float3 sums x, y, z in that order (x*y products contracted as LLVM sees fit, the
 * same way for scalars and vectors). */
inline floatw dot3w(float3w a, float3w b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
inline float3w cross3w(float3w a, float3w b) {
    return f3w(a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x);
}
inline float3w select3w(float3w a, float3w b, intw m) {
    return f3w(select(a.x, b.x, m), select(a.y, b.y, m), select(a.z, b.z, m));
}
inline float3w normalize3w(float3w a) { return scale3w(a, rsqrt(dot3w(a, a))); }
inline intw is_black3w(float3w c) { return c.x == 0.0f && c.y == 0.0f && c.z == 0.0f; }

/* Gathers and scatters go through private arrays (OpenCL C has no variable lane index):
 * store3w puts v's components in rows first..first + 2, lane_of reads lane k of them back. */
inline void store3w(float3w v, float a[][PT_LANES], int first) {
    VSTOREW(v.x, 0, a[first]);
    VSTOREW(v.y, 0, a[first + 1]);
    VSTOREW(v.z, 0, a[first + 2]);
}
inline float3 lane_of(float a[][PT_LANES], int first, int k) { return (float3)(a[first][k], a[first + 1][k], a[first + 2][k]); }

/* ---- cl/geometry.h, cl/sampling.h per lane ------------------------------------------------ */

inline void unit_circle_octant_w(floatw a, floatw* c, floatw* s) {
    floatw z = a * a;
    *s = a + a * z * (-1.6666654611e-1f + z * (8.3321608736e-3f + z * -1.9515295891e-4f));
    *c = 1.0f - 0.5f * z +
         z * z * (4.166664568298827e-2f + z * (-1.388731625493765e-3f + z * 2.443315711809948e-5f));
}

inline void unit_circle_turns_w(floatw u, floatw* c, floatw* s) {
    floatw q = rint(4.0f * u);
    floatw co, si;
    unit_circle_octant_w((u - 0.25f * q) * (2.0f * PI_F), &co, &si);
    intw quadrant = CONVERT_INTW(q) & 3;
    /* The quarter turns: (c, s), (-s, c), (-c, -s), (s, -c). */
    *c = select(select(select(co, -si, quadrant == 1), -co, quadrant == 2), si, quadrant == 3);
    *s = select(select(select(si, co, quadrant == 1), -si, quadrant == 2), -co, quadrant == 3);
}

inline void sample_concentric_disk_w(floatw ux, floatw uy, floatw* dx, floatw* dy) {
    floatw ox = 2.0f * ux - 1.0f, oy = 2.0f * uy - 1.0f;
    intw x_wedge = fabs(ox) > fabs(oy);
    /* Each lane divides by the larger of |o.x| and |o.y| only: the other quotient may be 0/0. */
    floatw c, s;
    unit_circle_octant_w((PI_F / 4.0f) * select(ox / oy, oy / ox, x_wedge), &c, &s);
    *dx = select(oy * s, ox * c, x_wedge);
    *dy = select(oy * c, ox * s, x_wedge);
    intw centre = ox == 0.0f && oy == 0.0f;
    *dx = select(*dx, (floatw)(0.0f), centre);
    *dy = select(*dy, (floatw)(0.0f), centre);
}

inline float3w sample_cosine_hemisphere_w(floatw ux, floatw uy) {
    floatw dx, dy;
    sample_concentric_disk_w(ux, uy, &dx, &dy);
    return f3w(dx, dy, sqrt(fmax(0.0f, 1.0f - dx * dx - dy * dy)));
}

typedef struct {
    float3w s, t, n;
} Framew;

inline Framew frame_from_normal_w(float3w n) {
    Framew f;
    f.n = n;
    floatw sign = select((floatw)(-1.0f), (floatw)(1.0f), n.z >= 0.0f);
    floatw a = -1.0f / (sign + n.z);
    floatw b = n.x * n.y * a;
    f.s = f3w(1.0f + sign * n.x * n.x * a, sign * b, -sign * n.x);
    f.t = f3w(b, sign + n.y * n.y * a, -n.y);
    return f;
}

inline float3w to_local_w(const Framew* f, float3w v) { return f3w(dot3w(v, f->s), dot3w(v, f->t), dot3w(v, f->n)); }

inline float3w from_local_w(const Framew* f, float3w v) {
    return add3w(add3w(scale3w(f->s, v.x), scale3w(f->t, v.y)), scale3w(f->n, v.z));
}

/* cl/ray.h offset_ray_origin per lane. */
inline float3w offset_ray_origin_w(float3w p, float3w ng, floatw p_error, float3w w) {
    float3w magnitude = add3w(fabs3w(p), f3w(p_error, p_error, p_error));
    floatw d = p_error + FLOAT_GAMMA(1) * dot3w(fabs3w(ng), magnitude);
    return add3w(p, scale3w(ng, select(d, -d, dot3w(ng, w) < 0.0f)));
}

/* ---- cl/rng.h per lane ------------------------------------------------------------------ */

#ifdef SAMPLER_SOBOL
/* Draw `draw` of every lane's sample (rng_next2's two values, rng_next's in *x): lane k's key
 * and reversed sample index are those of its own Rng. */
__attribute__((always_inline)) inline void rng_draw_lanes(uintw key, uintw index_reversed, uint draw, floatw* x,
                                                          floatw* y) {
    uint inner = draw + 0x632be5abu;
    HASH_U32_STEPS(inner);
    uintw seed = key ^ inner;
    HASH_U32_STEPS(seed);
    uintw index = index_reversed;
    OWEN_HASH_STEPS(index, seed);
    REVERSE_BITS_STEPS(index);
    uintw seed_x = seed ^ 0xa511e9b3u, seed_y = seed ^ 0x63d83595u;
    HASH_U32_STEPS(seed_x);
    HASH_U32_STEPS(seed_y);
    uintw vx = index, vy = index;
    SOBOL_DIMENSION1_REVERSED_STEPS(vy);
    OWEN_HASH_STEPS(vx, seed_x);
    OWEN_HASH_STEPS(vy, seed_y);
    REVERSE_BITS_STEPS(vx);
    REVERSE_BITS_STEPS(vy);
    *x = CONVERT_FLOATW(vx >> 8) * (1.0f / 16777216.0f);
    *y = CONVERT_FLOATW(vy >> 8) * (1.0f / 16777216.0f);
}
#endif

#endif
