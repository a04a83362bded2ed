/* Debug views that prove traversal end to end (--aov): the first hit's shading normal
 * (0.5 + 0.5 n), its material's diffuse (or, for mirrors and glass, specular) albedo, or its
 * distance from the camera. Misses are black. */
#include "bvh.h"
#include "camera.h"
#include "geometry.h"

#define AOV_NORMAL 0
#define AOV_ALBEDO 1
#define AOV_DEPTH 2

__kernel void render_aov(__global const BvhNode* nodes, __global const Triangle* triangles,
                         __global const TriangleInfo* infos, __global const Material* materials, Camera camera,
                         int first_pixel, int pixel_count, int aov, __global float4* out) {
    int gid = get_global_id(0);
    if (gid >= pixel_count) return;
    int pixel = first_pixel + gid;
    float2 raster = (float2)((float)(pixel % camera.width) + 0.5f, (float)(pixel / camera.width) + 0.5f);
    float3 o, d;
    camera_generate_ray(&camera, raster, (float2)(0.5f, 0.5f), &o, &d);
    Hit hit;
    float3 value = (float3)(0.0f);
    if (intersect(nodes, triangles, 0, o, d, INFINITY, &hit)) {
        __global const Triangle* tri = &triangles[hit.triangle];
        float3 n = normalize(cross(xyz(tri->p1) - xyz(tri->p0), xyz(tri->p2) - xyz(tri->p0)));
        __global const Material* m = &materials[infos[hit.triangle].material];
        if (aov == AOV_NORMAL) value = 0.5f + 0.5f * n;
        else if (aov == AOV_ALBEDO) value = (m->kind == MATERIAL_MIRROR || m->kind == MATERIAL_GLASS) ? xyz(m->ks) : xyz(m->kd);
        else value = (float3)(hit.t);
    }
    out[gid] = (float4)(value.x, value.y, value.z, 0.0f);
}
