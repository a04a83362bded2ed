// The scene in the layout the kernels read (cl/shared/types.h): BVH-ordered triangles, one
// Light per emissive triangle plus the scene file's lights, the power-based selection CDF,
// the environment map's sampling distribution and the camera. Built once per render.
#pragma once

#include <string>
#include <vector>

#include "bvh/bvh.h"
#include "scene/scene.h"
#include "shared/types.h"

namespace clbdpt {

struct DeviceScene {
    std::vector<BvhNode> nodes;
    // Per BVH reference, in BVH order: a triangle cut by spatial splits appears more than once
    // (source_triangles counts each once).
    std::vector<Triangle> triangles;
    std::vector<TriangleInfo> infos;
    std::vector<TriangleNormals> normals;
    std::vector<Material> materials;
    std::vector<Light> lights;
    std::vector<float> light_cdf;         // lights.size() + 1 entries
    std::vector<float> light_power;       // per light: luminance of its emitted power (host only)
    std::vector<cl_float4> env_texels;    // env map, row 0 = +y
    std::vector<float> env_distribution;  // see cl/lights.h
    std::vector<TriangleUV> uvs;          // BVH order; empty without textures
    std::vector<TextureInfo> textures;
    std::vector<uint32_t> texels;
    std::vector<Medium> media;            // referenced as 1 + index by materials and lights
    std::vector<float> densities;         // grid media's voxels, one grid after another
    Camera camera{};
    SceneInfo info{};
    double bvh_build_seconds = 0;
    size_t source_triangles = 0;
    int bvh_spatial_splits = 0;
    std::vector<std::string> warnings;    // one line each (render/media_nesting.h)
};

// width/height: the film size actually rendered (scene's, or the command line's overrides).
DeviceScene build_device_scene(const Scene& scene, int width, int height);

Camera make_camera(const CameraDesc& desc, int width, int height);

// The x, y, z of a device float4 (a triangle corner, a material's colour).
Vec3 vec3_of(const cl_float4& v);

// Writes each triangle's unit geometric normal into its corners' w lanes (cl/shared/types.h).
void store_triangle_normals(std::vector<Triangle>& triangles);

// Sampling distribution of a lat-long map (layout in cl/lights.h).
std::vector<float> environment_distribution(const EnvironmentMap& map);

}  // namespace clbdpt
