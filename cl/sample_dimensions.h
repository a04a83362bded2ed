/* Which draw of a pixel sample's vector each decision of a BDPT sample uses: one table, so no
 * two decisions share a random number and the same decision of every sample of a pixel uses
 * the same draw whatever the subpaths did before it (what keeps a stratified sampler
 * stratified: sample i of decision d is point i of draw d's sequence).
 *
 * A draw is one 1D or 2D value (rng_next / rng_next2 at rng->dimension = draw). The whole
 * sample, camera and light subpath alike, comes from the pixel's own vector (pbrt-v3 hands
 * BDPT one per-pixel sampler for both subpaths).
 *
 *   draw                                   what                                   count
 *   SAMPLE_DRAW_PIXEL                      position in the pixel (2D)             1
 *   SAMPLE_DRAW_LENS                       camera ray's lens point (2D)           1
 *   SAMPLE_DRAW_TRACE_LIGHT_SUBPATH        whether a light subpath is traced (1D) 1
 *   SAMPLE_DRAW_LIGHT_POSITION             which light emits and where (2D)       1
 *   SAMPLE_DRAW_LIGHT_DIRECTION            emitted direction (2D)                 1
 *   sample_draw_camera_bounce(k)           lobe and Russian roulette (2D), then   2 per bounce, MAX_DEPTH bounces
 *                                          direction (2D)
 *                                          HAS_MEDIA: then the distance (2D)      3 per bounce, MAX_DEPTH + 1
 *   sample_draw_light_bounce(k)            as the camera's                        as the camera's
 *   sample_draw_lens_connection(s)         t = 1: lens point (2D)                 1 per s = 1 .. MAX_DEPTH + 1
 *   sample_draw_light_connection(t)        s = 1: light and point on it (2D)      1 per t = 2 .. MAX_DEPTH + 1
 *
 * A light's draw is 2D: its first value picks the light (and the triangle of an emitter) and
 * what is left of it after the pick (rest_of_choice, cl/sampling.h) is the point's first
 * coordinate, so a pixel's light points stay stratified over every emitter together.
 *
 * A camera subpath has at most MAX_DEPTH + 1 scattering vertices and samples a direction at
 * all but the last; a light subpath has at most MAX_DEPTH and samples at all but the last
 * (MAX_DEPTH - 1 bounces; one spare slot keeps the formulas alike). With media, bounce k's third
 * draw samples the distance along the segment that arrives at the subpath's k-th scattering
 * vertex (channel and optical depth, cl/medium.h); a camera subpath has MAX_DEPTH + 1 such
 * segments, so the slots are one more. Without media the table is as it was, and so are the
 * images. Plain C so a host test can
 * include it with any MAX_DEPTH (tests/sample_dimensions_test.cpp checks the ranges are
 * disjoint and the values they give uncorrelated). */
#ifndef CLBDPT_SAMPLE_DIMENSIONS_H
#define CLBDPT_SAMPLE_DIMENSIONS_H

#ifndef MAX_DEPTH
#define MAX_DEPTH 5
#endif

#define SAMPLE_DRAW_PIXEL 0u
#define SAMPLE_DRAW_LENS 1u
#define SAMPLE_DRAW_TRACE_LIGHT_SUBPATH 2u
#define SAMPLE_DRAW_LIGHT_POSITION 3u
#define SAMPLE_DRAW_LIGHT_DIRECTION 4u
#ifdef HAS_MEDIA
#define SAMPLE_DRAWS_PER_BOUNCE 3u
#define SAMPLE_DRAW_BOUNCE_DISTANCE 2u /* within a bounce's draws */
#define SAMPLE_BOUNCE_SLOTS ((MAX_DEPTH) + 1u)
#else
#define SAMPLE_DRAWS_PER_BOUNCE 2u
#define SAMPLE_BOUNCE_SLOTS (MAX_DEPTH)
#endif
#define SAMPLE_DRAW_CAMERA_BOUNCES 5u
#define SAMPLE_DRAW_LIGHT_BOUNCES (SAMPLE_DRAW_CAMERA_BOUNCES + SAMPLE_DRAWS_PER_BOUNCE * SAMPLE_BOUNCE_SLOTS)
#define SAMPLE_DRAW_LENS_CONNECTIONS (SAMPLE_DRAW_LIGHT_BOUNCES + SAMPLE_DRAWS_PER_BOUNCE * SAMPLE_BOUNCE_SLOTS)
#define SAMPLE_DRAW_LIGHT_CONNECTIONS (SAMPLE_DRAW_LENS_CONNECTIONS + (MAX_DEPTH) + 1u)
#define SAMPLE_DRAWS_PER_LIGHT_CONNECTION 1u
#define SAMPLE_DRAW_COUNT (SAMPLE_DRAW_LIGHT_CONNECTIONS + SAMPLE_DRAWS_PER_LIGHT_CONNECTION * (MAX_DEPTH))

/* The first of the draws of a subpath's bounce k (k = 0 at its first scattering vertex). */
inline unsigned int sample_draw_camera_bounce(int k) { return SAMPLE_DRAW_CAMERA_BOUNCES + SAMPLE_DRAWS_PER_BOUNCE * (unsigned int)k; }
inline unsigned int sample_draw_light_bounce(int k) { return SAMPLE_DRAW_LIGHT_BOUNCES + SAMPLE_DRAWS_PER_BOUNCE * (unsigned int)k; }
/* t = 1: the lens point joined to light vertex s (s >= 1). */
inline unsigned int sample_draw_lens_connection(int s) { return SAMPLE_DRAW_LENS_CONNECTIONS + (unsigned int)(s - 1); }
/* s = 1: the light point joined to camera vertex t (t >= 2). */
inline unsigned int sample_draw_light_connection(int t) {
    return SAMPLE_DRAW_LIGHT_CONNECTIONS + SAMPLE_DRAWS_PER_LIGHT_CONNECTION * (unsigned int)(t - 2);
}

#endif
