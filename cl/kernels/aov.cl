/* Debug views that prove traversal end to end (--aov): the first hit's shading normal
 * (0.5 + 0.5 n, after vertex normals and bump maps), its diffuse (or, for mirrors and glass,
 * specular) albedo with textures applied, or its distance from the camera. Cut-outs are holes
 * here as everywhere. Misses are black. Built with the scene's feature flags, like render.cl. */
#include "walk.h"

#define AOV_NORMAL 0
#define AOV_ALBEDO 1
#define AOV_DEPTH 2

__kernel void render_aov(SCENE_KERNEL_ARGS, int first_pixel, int pixel_count, int aov, __global float4* out) {
    int gid = get_global_id(0);
    if (gid >= pixel_count) return;
    uint rays_traced = 0;
    SceneData scene = SCENE_DATA_FROM_KERNEL_ARGS(&rays_traced);
    int pixel = first_pixel + gid;
    float2 raster = (float2)((float)(pixel % camera.width) + 0.5f, (float)(pixel / camera.width) + 0.5f);
    PathVertex eye;
    float3 d;
    camera_generate_ray(scene.camera, raster, (float2)(0.5f, 0.5f), &eye.p, &d);
    Hit hit;
    float3 value = (float3)(0.0f);
    if (intersect(scene.nodes, scene.triangles, &scene.cutouts, eye.p, d, INFINITY, &hit)) {
        PathVertex v;
        surface_vertex_from_hit(&scene, &eye, &hit, &v);
        Bsdf b = vertex_bsdf(&scene, &v);
        if (aov == AOV_NORMAL) value = 0.5f + 0.5f * v.ns;
        else if (aov == AOV_ALBEDO) value = bsdf_is_specular(&b) ? b.ks : b.kd;
        else value = (float3)(hit.t);
    }
    out[gid] = (float4)(value.x, value.y, value.z, 0.0f);
}
