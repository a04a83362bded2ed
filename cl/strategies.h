/* Which (s, t) strategies an integrator uses: s light subpath vertices joined to t camera
 * subpath vertices. The MIS weight sums over exactly the enabled strategies, so every set
 * is unbiased on the paths it can reach.
 *   INTEGRATOR_BDPT  every strategy the strategy mix allows (below)
 *   INTEGRATOR_PT    s <= 1, t >= 2: a path tracer with next-event estimation
 *   INTEGRATOR_LT    t == 1: a light tracer
 * The (1,1) strategy (a point sampled on a light joined straight to a sampled lens point) is
 * what lets a light tracer show emitters seen directly; pbrt-v3 leaves it out. It is only for
 * area lights: point and spot lights are not visible to the camera in any strategy set (no
 * camera path can hit them), and for lights at infinity the strategy has measure zero. lt
 * always uses it; bdpt only with a thin lens or in a scene with media (mix.light_to_lens). In
 * vacuum through a pinhole, s = 0 sees an emitter with no noise but the pixel's coverage of its
 * outline, while (1,1)'s splats land on random pixels of it: with (1,1), 80% of full bdpt's
 * squared error on the Cornell box (64 spp) and 45% of that of bdpt without inner connections
 * on cornell-specular sat on the visible light, where pt had almost none. Through a thin lens
 * (1,1) renders a small light's out-of-focus disk, which s = 0 finds only by chance; in fog, a
 * camera ray reaches the light only where distance sampling lets it through, while (1,1) joins
 * the two with the segment's transmittance (on cornell-fog bdpt's pilot variance was 13x
 * higher without it).
 *
 * The strategy mix (efficiency-aware BDPT; Grittmann, Yazici, Georgiev & Slusallek 2022): a
 * pixel sample traces one camera subpath and, with probability light_subpaths, one light
 * subpath. Strategies that use the light subpath (s >= 2, and t = 1) then have
 * light_subpaths samples per pixel sample where the camera-only ones (s <= 1, t >= 2) have
 * one, and the balance heuristic weighs each strategy by its density times its sample count
 * (Veach 9.2.2: w_i = n_i p_i / sum_k n_k p_k). light_subpaths = 0 is path tracing;
 * inner_connections = 0 drops the s >= 2, t >= 2 connections (path tracing plus light
 * tracing). The light-subpath strategies' contributions are divided by light_subpaths
 * (they are made with that probability). */
#ifndef CLBDPT_STRATEGIES_H
#define CLBDPT_STRATEGIES_H

#include "shared/types.h"

#define INTEGRATOR_BDPT 0
#define INTEGRATOR_PT 1
#define INTEGRATOR_LT 2

#ifndef INTEGRATOR
#define INTEGRATOR INTEGRATOR_BDPT
#endif

/* Strategy (s, t) is numbered s * STRATEGY_STRIDE + t where a kernel reports one (the first with
 * a value that is not finite; --strategy-images' record slots): t <= MAX_DEPTH + 2. */
#define STRATEGY_STRIDE (MAX_DEPTH + 3)

typedef struct {
    float light_subpaths;  /* light subpaths per pixel sample, 0 .. 1 */
    int inner_connections; /* whether s >= 2, t >= 2 strategies are used */
    int light_to_lens;     /* whether bdpt uses (1,1) (above) */
} StrategyMix;

/* The mix a launch's parameters name. */
inline StrategyMix strategy_mix_of(const RenderParams* params) {
    StrategyMix mix;
    mix.light_subpaths = params->light_subpaths;
    mix.inner_connections = params->inner_connections;
    mix.light_to_lens = params->light_to_lens;
    return mix;
}

/* Whether strategy (s, t) joins a vertex of the light subpath (rather than only the camera
 * subpath and, for s = 1, a freshly sampled light point). */
inline int strategy_uses_light_subpath(int s, int t) { return s >= 2 || t == 1; }

/* Samples of strategy (s, t) per pixel sample. */
inline float strategy_sample_count(const StrategyMix* mix, int s, int t) {
#if INTEGRATOR == INTEGRATOR_BDPT
    return strategy_uses_light_subpath(s, t) ? mix->light_subpaths : 1.0f;
#else
    return 1.0f; /* pt and lt each use one kind of strategy only: counts cancel */
#endif
}

/* Bounds on the enabled strategies' vertex counts that the integrator fixes when the kernel is
 * built: a path tracer's strategies have at most one light vertex, a light tracer's exactly one
 * camera vertex. The MIS ratio recursion (cl/mis.h) stops where they end instead of walking
 * the rest of the path for terms that are all disabled. */
#if INTEGRATOR == INTEGRATOR_PT
#define STRATEGY_MAX_LIGHT_VERTICES 1
#else
#define STRATEGY_MAX_LIGHT_VERTICES 0x7fffffff
#endif
#if INTEGRATOR == INTEGRATOR_LT
#define STRATEGY_MAX_CAMERA_VERTICES 1
#else
#define STRATEGY_MAX_CAMERA_VERTICES 0x7fffffff
#endif

/* Whether the MIS weights read the reverse densities (pdf_rev) that the random walks store in
 * subpath vertices. With the bounds above a path tracer's and a light tracer's weights need only
 * the connection's own reverse densities, so their walks skip the second BSDF evaluation per
 * bounce that a subpath's reverse densities cost. */
#if INTEGRATOR == INTEGRATOR_BDPT
#define STRATEGIES_READ_SUBPATH_PDF_REV 1
#else
#define STRATEGIES_READ_SUBPATH_PDF_REV 0
#endif

/* light_is_area: whether the path's emitter is an area light (only then is (1,1) possible). */
inline int strategy_enabled(const StrategyMix* mix, int s, int t, int light_is_area) {
    if (t < 1 || s + t < 2) return 0;
    if (s == 1 && t == 1 && !light_is_area) return 0;
#if INTEGRATOR == INTEGRATOR_PT
    return s <= 1 && t >= 2;
#elif INTEGRATOR == INTEGRATOR_LT
    return t == 1;
#else
    if (s == 1 && t == 1 && !mix->light_to_lens) return 0;
    if (s >= 2 && t >= 2 && !mix->inner_connections) return 0;
    return !strategy_uses_light_subpath(s, t) || mix->light_subpaths > 0.0f;
#endif
}

#endif
