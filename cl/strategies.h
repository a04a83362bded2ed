/* Which (s, t) strategies an integrator uses: s light subpath vertices joined to t camera
 * subpath vertices. The MIS weight sums over exactly the enabled strategies, so every set
 * is unbiased on the paths it can reach.
 *   INTEGRATOR_BDPT  every strategy
 *   INTEGRATOR_PT    s <= 1, t >= 2: a path tracer with next-event estimation
 *   INTEGRATOR_LT    t == 1: a light tracer
 * The (1,1) strategy (a point sampled on a light joined straight to a sampled lens point) is
 * what lets a light tracer show emitters seen directly; pbrt-v3 leaves it out. Here it is on
 * for bdpt and lt, but only for area lights: point and spot lights are not visible to the
 * camera in any strategy set (no camera path can hit them), and for lights at infinity the
 * strategy has measure zero. */
#ifndef CLBDPT_STRATEGIES_H
#define CLBDPT_STRATEGIES_H

#define INTEGRATOR_BDPT 0
#define INTEGRATOR_PT 1
#define INTEGRATOR_LT 2

#ifndef INTEGRATOR
#define INTEGRATOR INTEGRATOR_BDPT
#endif

/* light_is_area: whether the path's emitter is an area light (only then is (1,1) possible). */
inline int strategy_enabled(int s, int t, int light_is_area) {
    if (t < 1 || s + t < 2) return 0;
    if (s == 1 && t == 1 && !light_is_area) return 0;
#if INTEGRATOR == INTEGRATOR_PT
    return s <= 1 && t >= 2;
#elif INTEGRATOR == INTEGRATOR_LT
    return t == 1;
#else
    return 1;
#endif
}

#endif
