/* Test kernels for cl/camera.h (tests/camera_test.cpp). Build with HAS_THIN_LENS for a camera
 * with a lens, without it for a pinhole, as the renderer does. */
#include "camera.h"
#include "rng.h"

/* Round trip per item: the ray through raster in[i].xy with lens sample in[i].zw, the point p on
 * it at depth `depth[i].x` along the viewing direction, then camera_sample_wi from p with lens
 * sample depth[i].yz, camera_we / camera_pdf_we of the returned lens point and direction, and
 * the ray camera_generate_ray makes for the returned raster and the same lens sample. Nine
 * float4 per item:
 *   (o, t) (d, 0) (p, We) (lens point, dist) (wi, pdf_w) (raster, We again, pdf_pos)
 *   (pdf_dir, raster of camera_we, 0) (origin of the regenerated ray, 0) (its direction, 0) */
__kernel void camera_roundtrip_test(Camera camera, __global const float4* in, __global const float4* depth,
                                    __global float4* out) {
    int gid = get_global_id(0);
    float3 o, d;
    camera_generate_ray(&camera, in[gid].xy, in[gid].zw, &o, &d);
    float3 fwd = xyz(camera.forward);
    float t = (depth[gid].x - dot(o - xyz(camera.eye), fwd)) / dot(d, fwd);
    float3 p = o + d * t;

    float3 lens = (float3)(0.0f), wi = (float3)(0.0f);
    float dist = 0.0f, pdf_w = 0.0f;
    float2 raster = (float2)(-1.0f, -1.0f);
    float2 u_wi = depth[gid].yz;
    float we = camera_sample_wi(&camera, p, u_wi, &lens, &wi, &pdf_w, &raster);
    dist = length(lens - p);

    float2 raster_we = (float2)(-1.0f, -1.0f);
    float we_eval = camera_we(&camera, lens, -wi, &raster_we);
    float pdf_pos = 0.0f, pdf_dir = 0.0f;
    camera_pdf_we(&camera, lens, -wi, &pdf_pos, &pdf_dir);
    float3 o2, d2;
    camera_generate_ray(&camera, raster, u_wi, &o2, &d2);

    __global float4* r = out + 9 * gid;
    r[0] = (float4)(o, t);
    r[1] = (float4)(d, 0.0f);
    r[2] = (float4)(p, we);
    r[3] = (float4)(lens, dist);
    r[4] = (float4)(wi, pdf_w);
    r[5] = (float4)(raster, we_eval, pdf_pos);
    r[6] = (float4)(pdf_dir, raster_we, 0.0f);
    r[7] = (float4)(o2, 0.0f);
    r[8] = (float4)(d2, 0.0f);
}

/* Monte Carlo estimate of the normalisation of We and of pdf_dir: a direction uniform in the
 * cone of half-angle acos(cos_max) about the viewing direction (covering the film) and a lens
 * point uniform on the lens (the eye for a pinhole). out[i] = (We cos(theta) lens_area / p,
 * pdf_dir / p, raster) with p the joint density of direction and lens point per lens area. */
__kernel void camera_normalisation_test(Camera camera, float cos_max, uint seed, __global float4* out) {
    int gid = get_global_id(0);
    Rng rng = rng_init((uint)gid, 0u, seed);
    float2 u_dir = rng_next2(&rng), u_lens = rng_next2(&rng);
    float3 dir = normalize(camera_to_world_dir(&camera, sample_uniform_cone(u_dir, 1.0f - cos_max)));
    float3 lens = xyz(camera.eye);
#ifdef HAS_THIN_LENS
    float2 l = camera.lens_radius * sample_concentric_disk(u_lens);
    lens += camera_to_world_dir(&camera, (float3)(l.x, l.y, 0.0f));
#endif
    float2 raster = (float2)(-1.0f, -1.0f);
    float we = camera_we(&camera, lens, dir, &raster);
    float pdf_pos, pdf_dir;
    camera_pdf_we(&camera, lens, dir, &pdf_pos, &pdf_dir);
    float inv_p = 1.0f / uniform_cone_pdf(1.0f - cos_max);
    float cos_theta = dot(dir, xyz(camera.forward));
    out[gid] = (float4)(we * cos_theta * camera.lens_area * inv_p, pdf_dir * inv_p, raster);
}
