/* Everything a kernel reads about the scene, gathered in one private struct so device
 * functions take one argument instead of ten buffers. */
#ifndef CLBDPT_SCENE_H
#define CLBDPT_SCENE_H

#include "shared/types.h"

typedef struct {
    __global const BvhNode* nodes;
    __global const Triangle* triangles;
    __global const TriangleInfo* infos;
    __global const TriangleNormals* normals;
    __global const Material* materials;
    __global const Light* lights;
    __global const float* light_cdf;        /* light_count + 1 entries, selection by power */
    __global const float4* env_texels;      /* lat-long map, env_width * env_height, row 0 = +y */
    __global const float* env_distribution; /* see lights.h, "Environment map distribution" */
    Camera camera;
    SceneInfo info;
    uint* rays_traced; /* the work item's ray counter (closest-hit and shadow rays) */
} SceneData;

inline float scene_radius(const SceneData* scene) { return scene->info.world_center.w; }

inline float3 scene_center(const SceneData* scene) {
    return (float3)(scene->info.world_center.x, scene->info.world_center.y, scene->info.world_center.z);
}

#endif
