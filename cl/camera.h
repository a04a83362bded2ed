/* Perspective camera with an optional thin lens: ray generation, importance We, its pdfs and
 * Sample_Wi (seed ch. 1.2; pbrt-v3 PerspectiveCamera). We is normalised so that it integrates
 * to 1 over lens area x film (measured on the z=1 plane), which is what makes a light-traced
 * splat and a camera sample estimate the same pixel value. */
#ifndef CLBDPT_CAMERA_H
#define CLBDPT_CAMERA_H

#include "shared/types.h"
#include "geometry.h"
#include "sampling.h"

inline float3 camera_to_world_dir(const Camera* c, float3 v) {
    return xyz(c->right) * v.x + xyz(c->up) * v.y + xyz(c->forward) * v.z;
}

inline float3 world_to_camera_dir(const Camera* c, float3 v) {
    return (float3)(dot(v, xyz(c->right)), dot(v, xyz(c->up)), dot(v, xyz(c->forward)));
}

/* The world-space ray through raster position `raster` (pixels, y down) and lens sample u_lens. */
inline void camera_generate_ray(const Camera* c, float2 raster, float2 u_lens, float3* origin, float3* dir) {
    float3 p_film = (float3)((2.0f * raster.x / (float)c->width - 1.0f) * c->tan_half_width,
                             (1.0f - 2.0f * raster.y / (float)c->height) * c->tan_half_height, 1.0f);
    float3 o = (float3)(0.0f, 0.0f, 0.0f);
    float3 d = p_film;
#ifdef HAS_THIN_LENS
    if (c->lens_radius > 0.0f) {
        float2 lens = c->lens_radius * sample_concentric_disk(u_lens);
        float3 p_focus = p_film * c->focus_distance; /* the film point's image on the focus plane */
        o = (float3)(lens.x, lens.y, 0.0f);
        d = p_focus - o;
    }
#endif
    *origin = xyz(c->eye) + camera_to_world_dir(c, o);
    /* d has z = 1 or the focus distance: never 0 nor near float's range ends, so none of the
     * library normalize's guards for such vectors (13 instructions a sample on PoCL) is needed.
     * (PoCL's normalize is this product otherwise: the same bits.) */
    float3 w = camera_to_world_dir(c, d);
    *dir = w * rsqrt(dot(w, w));
}

/* Raster position where a ray leaving the lens at `lens_point` (world) in direction `dir` lands
 * on the film. Returns 0 if it misses the film or points backwards. */
inline int camera_raster_of(const Camera* c, float3 lens_point, float3 dir, float2* raster) {
    float3 d = world_to_camera_dir(c, dir);
    if (d.z <= 0.0f) return 0;
    float3 o = world_to_camera_dir(c, lens_point - xyz(c->eye));
    float plane = c->lens_radius > 0.0f ? c->focus_distance : 1.0f;
    float3 p = o + d * (plane / d.z); /* on the z = plane plane */
    float fx = p.x / plane, fy = p.y / plane;
    float rx = (fx / c->tan_half_width + 1.0f) * 0.5f * (float)c->width;
    float ry = (1.0f - fy / c->tan_half_height) * 0.5f * (float)c->height;
    if (!(rx >= 0.0f && rx < (float)c->width && ry >= 0.0f && ry < (float)c->height)) return 0;
    *raster = (float2)(rx, ry);
    return 1;
}

/* Importance We for a ray leaving the lens (pbrt-v3 eq. 16.3): 1 / (A lens_area cos^4 theta)
 * inside the film, else 0. */
inline float camera_we(const Camera* c, float3 lens_point, float3 dir, float2* raster) {
    float cos_theta = dot(dir, xyz(c->forward));
    if (cos_theta <= 0.0f) return 0.0f;
    if (!camera_raster_of(c, lens_point, dir, raster)) return 0.0f;
    float cos2 = cos_theta * cos_theta;
    return 1.0f / (c->film_area * c->lens_area * cos2 * cos2);
}

/* Pdf_We: pdf_pos = 1 / lens_area (area measure), pdf_dir = 1 / (A cos^3 theta) (solid angle). */
inline void camera_pdf_we(const Camera* c, float3 lens_point, float3 dir, float* pdf_pos, float* pdf_dir) {
    float2 raster;
    float cos_theta = dot(dir, xyz(c->forward));
    if (cos_theta <= 0.0f || !camera_raster_of(c, lens_point, dir, &raster)) {
        *pdf_pos = 0.0f;
        *pdf_dir = 0.0f;
        return;
    }
    *pdf_pos = 1.0f / c->lens_area;
    *pdf_dir = 1.0f / (c->film_area * cos_theta * cos_theta * cos_theta);
}

/* Sample_Wi: picks a lens point, returns We toward `ref`, the direction wi from ref to the lens,
 * the solid-angle pdf at ref, and the raster position. */
inline float camera_sample_wi(const Camera* c, float3 ref, float2 u, float3* lens_point, float3* wi, float* pdf_w,
                              float2* raster) {
    float3 lens_cam = (float3)(0.0f, 0.0f, 0.0f);
#ifdef HAS_THIN_LENS
    float2 lens = c->lens_radius * sample_concentric_disk(u);
    lens_cam = (float3)(lens.x, lens.y, 0.0f);
#endif
    float3 p_lens = xyz(c->eye) + camera_to_world_dir(c, lens_cam);
    float3 to_lens = p_lens - ref;
    float d2 = length_squared(to_lens);
    *pdf_w = 0.0f;
    if (d2 == 0.0f) return 0.0f;
    float d = sqrt(d2);
    *wi = to_lens / d;
    *lens_point = p_lens;
    float cos_lens = fabs(dot(xyz(c->forward), *wi));
    if (cos_lens == 0.0f) return 0.0f;
    *pdf_w = d2 / (cos_lens * c->lens_area);
    return camera_we(c, p_lens, -*wi, raster);
}

#endif
