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

// How light samples and light subpaths pick directions toward an environment map (cl/lights.h,
// README "Environment maps").
// - Compensated: each texel in proportion to its luminance's excess over the map's mean, texels
//   at or below the mean never (MIS compensation: Karlik, Sik, Vevoda, Skrivan & Krivanek 2019,
//   "MIS compensation: optimizing sampling techniques in multiple importance sampling"). Sampling
//   by luminance gives a direction below the mean less density than uniform sphere sampling,
//   1 / (4 pi), which a cosine lobe already exceeds over all but its grazing quarter; so those
//   directions are left to BSDF sampling, and the light samples go where the light is bright.
//   Unbiased wherever BSDF sampling can reach the environment (s = 0): bdpt and pt. A map whose
//   texels all equal their mean keeps the luminance distribution.
// - Luminance: each texel in proportion to its luminance, for the light tracer (t = 1), which
//   has no other strategy for a direction of density 0.
enum class EnvironmentSampling { Compensated = 0, Luminance = 1 };

struct DeviceScene {
    std::vector<BvhNode> nodes;
    // Per BVH reference, in BVH order: a triangle cut by spatial splits appears more than once
    // (source_triangles counts each once).
    std::vector<Triangle> triangles;
    std::vector<TriangleInfo> infos;
    std::vector<TriangleNormals> normals;
    std::vector<Material> materials;
    std::vector<Light> lights;
    std::vector<float> light_cdf;         // lights.size() + 1 entries, then their guide's (cl/sampling.h)
    std::vector<float> light_power;       // per light: luminance of its emitted power (host only)
    std::vector<cl_float4> env_texels;    // env map, row 0 = +y
    std::vector<float> env_distribution;  // see cl/lights.h
    EnvironmentSampling env_sampling = EnvironmentSampling::Compensated;
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
// The materials that some triangle uses, in index order: what the strategies must serve (an
// exporter's MTL file often defines materials no face uses). The kernel's features still come
// from every material: the MIS tests build kernels for paths whose materials no triangle has.
std::vector<Material> materials_in_use(const DeviceScene& scene);

// Whether the material is wholly specular: a mirror or glass.
bool material_is_specular(const Material& m);

// Whether some triangle is a mirror or glass.
bool has_specular_surfaces(const DeviceScene& scene);

DeviceScene build_device_scene(const Scene& scene, int width, int height,
                               EnvironmentSampling env_sampling = EnvironmentSampling::Compensated);

Camera make_camera(const CameraDesc& desc, int width, int height);

// The x, y, z of a device float4 (a triangle corner, a material's colour).
Vec3 vec3_of(const cl_float4& v);

// Writes each triangle's unit geometric normal into its corners' w lanes (cl/shared/types.h).
void store_triangle_normals(std::vector<Triangle>& triangles);

// The triangles as the device stores them (TriangleRows, cl/shared/types.h): transposed, row k
// holding the corners' coordinate k and the normal's.
std::vector<TriangleRows> triangle_rows(const std::vector<Triangle>& triangles);

// Appends to `buffer` the guide of the CDF of n intervals at buffer[cdf_offset ..], as
// find_interval_guided (cl/sampling.h) reads it: g + 1 entries, entry k the interval holding
// k / g (the last interval whose CDF value is at most k / g), ints stored as float bits.
void append_cdf_guide(std::vector<float>& buffer, size_t cdf_offset, int n, int g);

// Sampling distribution of a lat-long map (layout in cl/lights.h).
std::vector<float> environment_distribution(const EnvironmentMap& map, EnvironmentSampling how);

}  // namespace clbdpt
