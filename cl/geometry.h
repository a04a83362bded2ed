/* Small vector helpers shared by every device header. */
#ifndef CLBDPT_GEOMETRY_H
#define CLBDPT_GEOMETRY_H

#define PI_F 3.14159265358979323846f
#define INV_PI_F 0.31830988618379067154f
#define INV_4PI_F 0.07957747154594766788f

/* floor and rint of one float through the compiler's builtins on CPUs: PoCL's library builds
 * both from integer conversions, compares and blends (12-17 instructions on haswell; the
 * rint of unit_circle_turns was 2% of a path tracer's instructions under a sky map), where
 * SSE4.1 and ARMv8 have one rounding instruction. The results are the same: both are exact. */
#if defined(__x86_64__) || defined(__aarch64__)
#define scalar_floor(x) __builtin_floorf(x)
#define scalar_rint(x) __builtin_rintf(x)
#else
#define scalar_floor(x) floor(x)
#define scalar_rint(x) rint(x)
#endif

/* (cos a, sin a) for |a| <= pi/4, by the minimax polynomials of Cephes' sinf and cosf (about
 * 1 ulp there). The library's sincos runs a general argument reduction on every call (4% of a
 * path tracer's time on PoCL); every angle the renderer samples is a fraction of a turn, which
 * unit_circle_turns reduces exactly. */
inline float2 unit_circle_octant(float a) {
    float z = a * a;
    float s = a + a * z * (-1.6666654611e-1f + z * (8.3321608736e-3f + z * -1.9515295891e-4f));
    float c = 1.0f - 0.5f * z +
              z * z * (4.166664568298827e-2f + z * (-1.388731625493765e-3f + z * 2.443315711809948e-5f));
    return (float2)(c, s);
}

/* (cos 2 pi u, sin 2 pi u) for u in [0, 1]: u - q/4 for the nearest quarter turn q/4 is exact
 * in float (Sterbenz), leaving at most an eighth of a turn for the polynomials, and the
 * quarter turns are exact rotations. */
inline float2 unit_circle_turns(float u) {
    float q = scalar_rint(4.0f * u);
    float2 cs = unit_circle_octant((u - 0.25f * q) * (2.0f * PI_F));
    int quadrant = (int)q & 3;
    if (quadrant == 1) return (float2)(-cs.y, cs.x);
    if (quadrant == 2) return -cs;
    if (quadrant == 3) return (float2)(cs.y, -cs.x);
    return cs;
}

/* The angle of (x, y) from +x towards +y in turns, in [0, 1]; 0 for (0, 0). Cephes' atanf
 * polynomial on the smaller-over-larger ratio, reduced once more at tan(pi / 8) (a few ulp of
 * a turn). On PoCL the library's atan2 and acos took about a fifth of a path tracer's time
 * under a sky map (perf), for a lookup that needs a texel. */
inline float atan2_turns(float y, float x) {
    float ax = fabs(x), ay = fabs(y);
    float hi = max(ax, ay), lo = min(ax, ay);
    float a = hi > 0.0f ? lo / hi : 0.0f; /* tan of the angle to the nearer axis, in [0, 1] */
    float base = 0.0f;
    if (a > 0.41421356237309504880f) { /* tan(pi / 8) */
        base = 0.25f * PI_F;
        a = (a - 1.0f) / (a + 1.0f);
    }
    float z = a * a;
    float r = base + a +
              a * z * (-3.33329491539e-1f + z * (1.99777106478e-1f + z * (-1.38776856032e-1f + z * 8.05374449538e-2f)));
    if (ay > ax) r = 0.5f * PI_F - r;
    if (x < 0.0f) r = PI_F - r;
    float turns = r * (0.5f * INV_PI_F);
    return y < 0.0f ? 1.0f - turns : turns;
}

/* acos(c) / pi for c in [-1, 1] (clamped), in [0, 1], from Cephes' asinf polynomial (a few
 * ulp): acos(a) = pi / 2 - asin(a) for |c| = a <= 1/2, and 2 asin(sqrt((1 - a) / 2)) nearer the
 * poles. */
inline float acos_half_turns(float c) {
    float a = min(fabs(c), 1.0f);
    bool near_pole = a > 0.5f;
    float z = near_pole ? 0.5f * (1.0f - a) : a * a; /* the square of asin's argument x */
    float x = near_pole ? sqrt(z) : a;
    float p = 1.6666752422e-1f +
              z * (7.4953002686e-2f + z * (4.5470025998e-2f + z * (2.4181311049e-2f + z * 4.2163199048e-2f)));
    float asin_x = x + x * z * p;
    float half_turns = (near_pole ? 2.0f * asin_x : 0.5f * PI_F - asin_x) * INV_PI_F;
    return c < 0.0f ? 1.0f - half_turns : half_turns;
}

/* ln x for a normal float x > 0 (not for 0, denormals, infinities or NaN), within 0.83 ulp
 * (measured over every float in [2^-24, 1], with and without fused multiply-adds): Cephes' logf
 * polynomial on the mantissa reduced to [sqrt(1/2), sqrt(2)). PoCL's log (SLEEF's logf_u10)
 * took 118 instructions a call on haswell, 6.5% of a path-traced sample in fog, where every
 * segment draws its optical depth with one. */
inline float log_of_normal(float x) {
    /* x = 2^e m with m in [sqrt(1/2), sqrt(2)): the exponent counted from sqrt(1/2)'s bits. */
    int e = (int)(as_uint(x) - 0x3f3504f3u) >> 23;
    float f = as_float(as_uint(x) - ((uint)e << 23)) - 1.0f;
    float z = f * f;
    float p = 7.0376836292e-2f;
    p = p * f - 1.1514610310e-1f;
    p = p * f + 1.1676998740e-1f;
    p = p * f - 1.2420140846e-1f;
    p = p * f + 1.4249322787e-1f;
    p = p * f - 1.6668057665e-1f;
    p = p * f + 2.0000714765e-1f;
    p = p * f - 2.4999993993e-1f;
    p = p * f + 3.3333331174e-1f;
    float fe = (float)e;
    /* ln 2 split in two (0.693359375 is exact in 9 bits) so that e ln 2 adds without error */
    float y = f * z * p + fe * -2.12194440e-4f - 0.5f * z;
    return (f + y) + fe * 0.693359375f;
}

/* exp(x) of each channel for x <= 0: 0 below -87.3 (where exp leaves the normal floats) and
 * at -infinity, NaN for NaN. Cephes' expf: x = n ln 2 + r with n the nearest integer to
 * x / ln 2 (adding 1.5 * 2^23 rounds it into the sum's low bits), ln 2 in two parts so that n ln 2
 * subtracts without error, |r| <= ln 2 / 2 into a degree-5 polynomial, and 2^n from its
 * exponent bits. PoCL's vector exp was 4.6% of a path tracer's instructions in fog (fog-spot),
 * whose transmittances (beer_lambert) are all it serves. */
inline float3 exp_of_nonpositive(float3 x) {
    float3 shifted = x * 1.44269504088896341f + 12582912.0f; /* n in its low mantissa bits */
    float3 n = shifted - 12582912.0f;
    float3 r = x - n * 0.693359375f - n * -2.12194440e-4f;
    float3 p = (float3)(1.9875691500e-4f);
    p = p * r + 1.3981999507e-3f;
    p = p * r + 8.3334519073e-3f;
    p = p * r + 4.1665795894e-2f;
    p = p * r + 1.6666665459e-1f;
    p = p * r + 5.0000001201e-1f;
    float3 y = p * (r * r) + r + 1.0f;
    /* shifted's bits are those of 1.5 * 2^23 plus n, whose own bits end below bit 9: shifted
     * left by 23, only n's remain. */
    float3 two_to_n = as_float3((as_int3(shifted) + 127) << 23);
    return select(y * two_to_n, (float3)(0.0f), x < -87.3f);
}

inline float3 xyz(float4 v) { return (float3)(v.x, v.y, v.z); }

inline float luminance(float3 c) { return 0.2126f * c.x + 0.7152f * c.y + 0.0722f * c.z; }

inline int is_black(float3 c) { return c.x == 0.0f && c.y == 0.0f && c.z == 0.0f; }

inline float length_squared(float3 v) { return dot(v, v); }

/* Orthonormal basis around a unit vector (Duff et al. 2017, "Building an Orthonormal Basis,
 * Revisited"): branch-free and exact for n = (0, 0, -1). */
inline void coordinate_system(float3 n, float3* s, float3* t) {
    float sign = n.z >= 0.0f ? 1.0f : -1.0f;
    float a = -1.0f / (sign + n.z);
    float b = n.x * n.y * a;
    *s = (float3)(1.0f + sign * n.x * n.x * a, sign * b, -sign * n.x);
    *t = (float3)(b, sign + n.y * n.y * a, -n.y);
}

/* A shading frame: local z is the shading normal. */
typedef struct {
    float3 s, t, n;
} Frame;

inline Frame frame_from_normal(float3 n) {
    Frame f;
    f.n = n;
    coordinate_system(n, &f.s, &f.t);
    return f;
}

inline float3 to_local(const Frame* f, float3 v) { return (float3)(dot(v, f->s), dot(v, f->t), dot(v, f->n)); }

inline float3 from_local(const Frame* f, float3 v) { return f->s * v.x + f->t * v.y + f->n * v.z; }

inline float3 face_forward(float3 n, float3 v) { return dot(n, v) < 0.0f ? -n : n; }

#endif
