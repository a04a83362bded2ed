/* Everything a kernel reads about the scene, gathered in one private struct so device
 * functions take one argument instead of ten buffers. */
#ifndef CLBDPT_SCENE_H
#define CLBDPT_SCENE_H

#include "shared/types.h"
#include "cutouts.h"
#include "textures.h"

typedef struct {
    __global const BvhNode* nodes;
    __global const TriangleRows* triangles;
    __global const TriangleInfo* infos;
    __global const TriangleNormals* normals;
    __global const Material* materials;
    __global const Light* lights;
    __global const float* light_cdf;        /* light_count + 1 entries, selection by power, then
                                               their guide's light_count + 1 (find_interval_guided) */
    __global const float4* env_texels;      /* lat-long map, env_width * env_height, row 0 = +y */
    __global const float* env_distribution; /* see lights.h, "Environment map distribution" */
    __global const TriangleUV* uvs;         /* per triangle, in scenes with textures */
    __global const Medium* media;           /* Material and Light medium indices are 1 + index */
    __global const float* densities;        /* grid media's voxels (Medium.grid_offset) */
    Textures textures;
    Cutouts cutouts; /* what the ray queries need to see holes (cl/cutouts.h) */
    /* The kernel's own by-value arguments, pointed to: a copy in every work item's SceneData
     * measured 2-3% of a path tracer's time on PoCL (the copies and a stalled 16-byte reload). */
    const Camera* camera;
    const SceneInfo* info;
    uint* rays_traced; /* the work item's ray counter (closest-hit and shadow rays) */
    /* Russian roulette's first bounce in camera and light subpaths (cl/russian_roulette.h):
     * RenderParams' in the render kernel, RUSSIAN_ROULETTE_OFF in every other. */
    int roulette_camera_from;
    int roulette_light_from;
#ifdef HAS_CAUSTIC_MERGING
    /* Set by the caustic photon kernel alone: a walk ends at its first non-specular vertex
     * (cl/walk.h), which is all that kernel keeps. The kernels of scenes without merging have
     * neither the field nor the test. */
    int walk_ends_at_scattering;
#endif
} SceneData;

/* The kernel arguments every light-transport kernel takes, in this order (the host sets them
 * in host/render/renderer.cpp). */
#define SCENE_KERNEL_ARGS                                                                              \
    __global const BvhNode *nodes, __global const TriangleRows *triangles, __global const TriangleInfo *infos, \
        __global const TriangleNormals *normals, __global const Material *materials,                    \
        __global const Light *lights, __global const float *light_cdf, __global const float4 *env_texels, \
        __global const float *env_distribution, __global const TriangleUV *uvs,                         \
        __global const TextureInfo *texture_infos, __global const uint *texels, __global const Medium *media, \
        __global const float *densities, Camera camera, SceneInfo info

#define SCENE_DATA_FROM_KERNEL_ARGS(rays)                                                               \
    scene_data(nodes, triangles, infos, normals, materials, lights, light_cdf, env_texels, env_distribution, \
               uvs, texture_infos, texels, media, densities, &camera, &info, rays)

inline SceneData scene_data(__global const BvhNode* nodes, __global const TriangleRows* triangles,
                            __global const TriangleInfo* infos, __global const TriangleNormals* normals,
                            __global const Material* materials, __global const Light* lights,
                            __global const float* light_cdf, __global const float4* env_texels,
                            __global const float* env_distribution, __global const TriangleUV* uvs,
                            __global const TextureInfo* texture_infos, __global const uint* texels,
                            __global const Medium* media, __global const float* densities, const Camera* camera,
                            const SceneInfo* info, uint* rays) {
    SceneData s;
    s.nodes = nodes;
    s.triangles = triangles;
    s.infos = infos;
    s.normals = normals;
    s.materials = materials;
    s.lights = lights;
    s.light_cdf = light_cdf;
    s.env_texels = env_texels;
    s.env_distribution = env_distribution;
    s.uvs = uvs;
    s.media = media;
    s.densities = densities;
    s.textures.infos = texture_infos;
    s.textures.texels = texels;
    s.cutouts.infos = infos;
    s.cutouts.materials = materials;
    s.cutouts.uvs = uvs;
    s.cutouts.textures = s.textures;
    s.camera = camera;
    s.info = info;
    s.rays_traced = rays;
    s.roulette_camera_from = RUSSIAN_ROULETTE_OFF;
    s.roulette_light_from = RUSSIAN_ROULETTE_OFF;
#ifdef HAS_CAUSTIC_MERGING
    s.walk_ends_at_scattering = 0;
#endif
    return s;
}

inline float scene_radius(const SceneData* scene) { return scene->info->world_center.w; }

inline float3 scene_center(const SceneData* scene) {
    return (float3)(scene->info->world_center.x, scene->info->world_center.y, scene->info->world_center.z);
}

#endif
