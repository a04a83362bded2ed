/* The Henyey-Greenstein phase function (pbrt-v3 section 11.3.1): the angular distribution of
 * light scattered in a medium, normalised over the sphere, so it is its own sampling density
 * (a medium vertex's f and pdf are the same number).
 *
 * Directions follow the path vertices' convention: wo points back toward the previous vertex,
 * wi toward the next, so light going straight on has wi = -wo. g > 0 scatters forward. */
#ifndef CLBDPT_PHASE_H
#define CLBDPT_PHASE_H

#include "geometry.h"

/* Density per steradian of scattering by angle theta from straight on (cos_theta = 1: on). */
inline float henyey_greenstein(float cos_theta, float g) {
    float denom = 1.0f + g * g - 2.0f * g * cos_theta;
    return INV_4PI_F * (1.0f - g * g) / (denom * sqrt(fmax(denom, 0.0f)));
}

inline float phase_hg(float3 wo, float3 wi, float g) { return henyey_greenstein(-dot(wo, wi), g); }

/* Samples wi with density phase_hg(wo, wi, g) by inverting the distribution's CDF in cos_theta
 * (exact; for |g| < 1e-3 the inversion loses precision and the distribution is uniform within
 * 2e-3 relative, so cos_theta is drawn uniformly and the density returned is the uniform one's
 * value: sampling and density agree to the float either way). Returns the density. */
inline float sample_phase_hg(float3 wo, float g, float2 u, float3* wi) {
    float cos_theta;
    float pdf;
    if (fabs(g) < 1e-3f) {
        cos_theta = 1.0f - 2.0f * u.x;
        pdf = INV_4PI_F;
    } else {
        float sqr_term = (1.0f - g * g) / (1.0f - g + 2.0f * g * u.x);
        cos_theta = clamp((1.0f + g * g - sqr_term * sqr_term) / (2.0f * g), -1.0f, 1.0f);
        pdf = henyey_greenstein(cos_theta, g);
    }
    float sin_theta = sqrt(fmax(0.0f, 1.0f - cos_theta * cos_theta));
    float3 s, t;
    float3 on = -wo;
    coordinate_system(on, &s, &t);
    float2 cs = unit_circle_turns(u.y);
    *wi = s * (sin_theta * cs.x) + t * (sin_theta * cs.y) + on * cos_theta;
    return pdf;
}

#endif
