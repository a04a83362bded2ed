// Compile-time checks that the host's view of every struct in cl/shared/types.h matches the
// layout OpenCL C gives it on the device: float4 is 16 bytes and 16-aligned, int/uint/float are
// 4, and a struct is padded to a multiple of its largest member's alignment. The numbers are
// written out by hand from those rules, so a change to types.h that moves a field fails here
// instead of corrupting buffers. tests/device_layout_test.cpp checks the same layout as the
// device compiler actually computes it.
#include "shared/types.h"

#include <cstddef>
#include <type_traits>

namespace clbdpt {
namespace {

#define CLBDPT_CHECK_STRUCT(T, size, align)                                            \
    static_assert(std::is_standard_layout_v<T>, #T " must be standard layout");          \
    static_assert(std::is_trivially_copyable_v<T>, #T " must be trivially copyable");   \
    static_assert(sizeof(T) == (size), "sizeof(" #T ") must be " #size);                 \
    static_assert(alignof(T) == (align), "alignof(" #T ") must be " #align);            \
    static_assert(sizeof(T) % 16 == 0, #T " is stored in arrays: size must be a multiple of 16")
#define CLBDPT_CHECK_FIELD(T, f, offset) \
    static_assert(offsetof(T, f) == (offset), "offsetof(" #T ", " #f ") must be " #offset)

// The building blocks: the host vector type must match float4 on the device.
static_assert(sizeof(clbdpt_float4) == 16 && alignof(clbdpt_float4) == 16, "cl_float4 must be 16 bytes, 16-aligned");
static_assert(sizeof(clbdpt_int) == 4 && sizeof(clbdpt_uint) == 4 && sizeof(float) == 4, "32-bit scalars");

CLBDPT_CHECK_STRUCT(BvhNode, 32 * BVH_WIDTH, 4);
CLBDPT_CHECK_FIELD(BvhNode, bounds, 0);
CLBDPT_CHECK_FIELD(BvhNode, child, 24 * BVH_WIDTH);
CLBDPT_CHECK_FIELD(BvhNode, pad, 28 * BVH_WIDTH);

CLBDPT_CHECK_STRUCT(Triangle, 48, 16);
CLBDPT_CHECK_FIELD(Triangle, p0, 0);
CLBDPT_CHECK_FIELD(Triangle, p1, 16);
CLBDPT_CHECK_FIELD(Triangle, p2, 32);

CLBDPT_CHECK_STRUCT(TriangleRows, 48, 16);
CLBDPT_CHECK_FIELD(TriangleRows, row, 0);

CLBDPT_CHECK_STRUCT(TriangleInfo, 16, 4);
CLBDPT_CHECK_FIELD(TriangleInfo, material, 0);
CLBDPT_CHECK_FIELD(TriangleInfo, light, 4);
CLBDPT_CHECK_FIELD(TriangleInfo, normals, 8);
CLBDPT_CHECK_FIELD(TriangleInfo, source_index, 12);

CLBDPT_CHECK_STRUCT(TriangleNormals, 48, 16);
CLBDPT_CHECK_FIELD(TriangleNormals, n0, 0);
CLBDPT_CHECK_FIELD(TriangleNormals, n1, 16);
CLBDPT_CHECK_FIELD(TriangleNormals, n2, 32);

CLBDPT_CHECK_STRUCT(TriangleUV, 32, 4);
CLBDPT_CHECK_FIELD(TriangleUV, u0, 0);
CLBDPT_CHECK_FIELD(TriangleUV, v2, 20);

CLBDPT_CHECK_STRUCT(TextureInfo, 48, 4);
CLBDPT_CHECK_FIELD(TextureInfo, offset, 0);
CLBDPT_CHECK_FIELD(TextureInfo, format, 12);
CLBDPT_CHECK_FIELD(TextureInfo, scale_u, 16);
CLBDPT_CHECK_FIELD(TextureInfo, offset_v, 28);
CLBDPT_CHECK_FIELD(TextureInfo, clamp, 32);

CLBDPT_CHECK_STRUCT(Material, 112, 16);
CLBDPT_CHECK_FIELD(Material, kd, 0);
CLBDPT_CHECK_FIELD(Material, ks, 16);
CLBDPT_CHECK_FIELD(Material, ke, 32);
CLBDPT_CHECK_FIELD(Material, kind, 48);
CLBDPT_CHECK_FIELD(Material, ior, 52);
CLBDPT_CHECK_FIELD(Material, alpha, 56);
CLBDPT_CHECK_FIELD(Material, interior_medium, 60);
CLBDPT_CHECK_FIELD(Material, kd_texture, 64);
CLBDPT_CHECK_FIELD(Material, ke_texture, 72);
CLBDPT_CHECK_FIELD(Material, cutout_texture, 76);
CLBDPT_CHECK_FIELD(Material, bump_texture, 84);
CLBDPT_CHECK_FIELD(Material, bump_scale, 92);
CLBDPT_CHECK_FIELD(Material, exterior_medium, 96);

CLBDPT_CHECK_STRUCT(Medium, 128, 16);
CLBDPT_CHECK_FIELD(Medium, sigma_a, 0);
CLBDPT_CHECK_FIELD(Medium, sigma_s, 16);
CLBDPT_CHECK_FIELD(Medium, sigma_t, 32);
CLBDPT_CHECK_FIELD(Medium, g, 48);
CLBDPT_CHECK_FIELD(Medium, majorant, 52);
CLBDPT_CHECK_FIELD(Medium, grid_offset, 56);
CLBDPT_CHECK_FIELD(Medium, grid_size, 64);
CLBDPT_CHECK_FIELD(Medium, world_to_grid, 80);

CLBDPT_CHECK_STRUCT(Light, 80, 16);
CLBDPT_CHECK_FIELD(Light, position, 0);
CLBDPT_CHECK_FIELD(Light, direction, 16);
CLBDPT_CHECK_FIELD(Light, emission, 32);
CLBDPT_CHECK_FIELD(Light, kind, 48);
CLBDPT_CHECK_FIELD(Light, triangle, 52);
CLBDPT_CHECK_FIELD(Light, one_minus_cos_total, 56);
CLBDPT_CHECK_FIELD(Light, one_minus_cos_falloff, 60);
CLBDPT_CHECK_FIELD(Light, area, 64);
CLBDPT_CHECK_FIELD(Light, select_pdf, 68);
CLBDPT_CHECK_FIELD(Light, medium, 72);
CLBDPT_CHECK_FIELD(Light, nee_weight, 76);

CLBDPT_CHECK_STRUCT(Camera, 96, 16);
CLBDPT_CHECK_FIELD(Camera, eye, 0);
CLBDPT_CHECK_FIELD(Camera, right, 16);
CLBDPT_CHECK_FIELD(Camera, up, 32);
CLBDPT_CHECK_FIELD(Camera, forward, 48);
CLBDPT_CHECK_FIELD(Camera, tan_half_width, 64);
CLBDPT_CHECK_FIELD(Camera, tan_half_height, 68);
CLBDPT_CHECK_FIELD(Camera, lens_radius, 72);
CLBDPT_CHECK_FIELD(Camera, focus_distance, 76);
CLBDPT_CHECK_FIELD(Camera, width, 80);
CLBDPT_CHECK_FIELD(Camera, height, 84);
CLBDPT_CHECK_FIELD(Camera, film_area, 88);
CLBDPT_CHECK_FIELD(Camera, lens_area, 92);

CLBDPT_CHECK_STRUCT(SceneInfo, 48, 16);
CLBDPT_CHECK_FIELD(SceneInfo, world_center, 0);
CLBDPT_CHECK_FIELD(SceneInfo, light_count, 16);
CLBDPT_CHECK_FIELD(SceneInfo, environment_light, 20);
CLBDPT_CHECK_FIELD(SceneInfo, env_width, 24);
CLBDPT_CHECK_FIELD(SceneInfo, env_height, 28);
CLBDPT_CHECK_FIELD(SceneInfo, triangle_count, 32);
CLBDPT_CHECK_FIELD(SceneInfo, node_count, 36);
CLBDPT_CHECK_FIELD(SceneInfo, camera_medium, 40);
CLBDPT_CHECK_FIELD(SceneInfo, area_light_count, 44);

CLBDPT_CHECK_STRUCT(RenderParams, 96, 4);
CLBDPT_CHECK_FIELD(RenderParams, width, 0);
CLBDPT_CHECK_FIELD(RenderParams, height, 4);
CLBDPT_CHECK_FIELD(RenderParams, first_pixel, 8);
CLBDPT_CHECK_FIELD(RenderParams, pixel_count, 12);
CLBDPT_CHECK_FIELD(RenderParams, sample_index, 16);
CLBDPT_CHECK_FIELD(RenderParams, seed, 20);
CLBDPT_CHECK_FIELD(RenderParams, light_subpaths, 24);
CLBDPT_CHECK_FIELD(RenderParams, inner_connections, 28);
CLBDPT_CHECK_FIELD(RenderParams, pixel_stride, 32);
CLBDPT_CHECK_FIELD(RenderParams, position_sample_index, 36);
CLBDPT_CHECK_FIELD(RenderParams, position_seed, 40);
CLBDPT_CHECK_FIELD(RenderParams, zsobol_log2_spp, 44);
CLBDPT_CHECK_FIELD(RenderParams, zsobol_base4_digits, 48);
CLBDPT_CHECK_FIELD(RenderParams, run_pixel, 52);
CLBDPT_CHECK_FIELD(RenderParams, run_length, 56);
CLBDPT_CHECK_FIELD(RenderParams, light_to_lens, 60);
CLBDPT_CHECK_FIELD(RenderParams, run_listed, 64);
CLBDPT_CHECK_FIELD(RenderParams, roulette_camera_from, 68);
CLBDPT_CHECK_FIELD(RenderParams, roulette_light_from, 72);
CLBDPT_CHECK_FIELD(RenderParams, camera_image_only, 76);
CLBDPT_CHECK_FIELD(RenderParams, subset_moments, 80);
CLBDPT_CHECK_FIELD(RenderParams, pad, 84);

CLBDPT_CHECK_STRUCT(SplatRecord, 16, 4);
CLBDPT_CHECK_FIELD(SplatRecord, r, 0);
CLBDPT_CHECK_FIELD(SplatRecord, g, 4);
CLBDPT_CHECK_FIELD(SplatRecord, b, 8);
CLBDPT_CHECK_FIELD(SplatRecord, pixel, 12);

CLBDPT_CHECK_STRUCT(CausticPhoton, 64, 16);
CLBDPT_CHECK_FIELD(CausticPhoton, p, 0);
CLBDPT_CHECK_FIELD(CausticPhoton, ng, 16);
CLBDPT_CHECK_FIELD(CausticPhoton, wi, 32);
CLBDPT_CHECK_FIELD(CausticPhoton, beta, 48);

CLBDPT_CHECK_STRUCT(MergeSlice, 32, 4);
CLBDPT_CHECK_FIELD(MergeSlice, photon_begin, 0);
CLBDPT_CHECK_FIELD(MergeSlice, cell_begin, 4);
CLBDPT_CHECK_FIELD(MergeSlice, cell_mask, 8);
CLBDPT_CHECK_FIELD(MergeSlice, radius, 12);
CLBDPT_CHECK_FIELD(MergeSlice, inv_cell, 16);
CLBDPT_CHECK_FIELD(MergeSlice, estimate_scale, 20);
CLBDPT_CHECK_FIELD(MergeSlice, pad, 24);

#undef CLBDPT_CHECK_STRUCT
#undef CLBDPT_CHECK_FIELD

}  // namespace
}  // namespace clbdpt
