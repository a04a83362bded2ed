/* Russian roulette (Arvo & Kirk 1990; the throughput rule of pbrt-v3's and Mitsuba 3's path
 * tracers): from a given bounce of a subpath on (bounce 0 leaves its first scattering vertex;
 * RenderParams.roulette_camera_from and roulette_light_from, RUSSIAN_ROULETTE_OFF for never),
 * a path whose throughput has fallen to a share m < 1 of what it started with goes on with
 * probability m and, if it does, its throughput is divided by m, back to where it started: the
 * same expectation, fewer rays spent on paths that can add little, and no throughput ever
 * raised above its start.
 *
 * The MIS weights leave the continuation probabilities out (as Mitsuba's and SmallVCM's
 * bidirectional integrators do): any weights that sum to 1 over the strategies that can make a
 * path keep the sum unbiased, and every strategy still can, since a path whose throughput is
 * not black goes on with a probability above 0. What changes is how well the weights fit the
 * true densities, in the deep bounces that Russian roulette thins out.
 *
 * Only at a vertex that scattered off a non-specular lobe: a path inside glass carries a
 * radiance throughput scaled by 1/eta^2 that leaving the glass restores (pbrt-v3's etaScale),
 * so a roulette inside would end paths for a loss they do not have.
 *
 * The decision's random number is the second value of the bounce's lobe draw
 * (cl/sample_dimensions.h), which the lobe choice does not use: a 2D point of a stratified
 * sampler, so the decisions are stratified over a pixel's samples with the lobe choices. */
#ifndef CLBDPT_RUSSIAN_ROULETTE_H
#define CLBDPT_RUSSIAN_ROULETTE_H

#include "geometry.h"

inline float max_channel(float3 c) { return max(max(c.x, c.y), c.z); }

/* After bounce `bounce` of a subpath whose roulette starts at bounce `from_bounce` and whose
 * first throughput's largest channel was beta_start_max: whether the path goes on (u: the
 * decision's uniform number), with *beta divided by the probability that it did. */
inline bool russian_roulette_continues(int bounce, int from_bounce, float beta_start_max, float u, float3* beta) {
    if (bounce < from_bounce) return true;
    float share = max_channel(*beta) / beta_start_max;
    if (!(share < 1.0f)) return true;
    if (u >= share) return false;
    *beta *= 1.0f / share;
    return true;
}

#endif
