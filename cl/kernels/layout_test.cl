/* Reports the layout of every struct in shared/types.h as the device compiler sees it, so
 * tests/device_layout_test.cpp can compare it with the host compiler's. The list of structs and
 * fields below is the single list both sides use: the test includes this file as C++ (where the
 * kernel itself is skipped) and expands the same list with the host's sizeof/alignof/offsetof. */
#include "shared/types.h"

/* S(T): the struct's size and alignment; F(T, f): the offset of field f. */
#define CLBDPT_LAYOUT_LIST(S, F)                                                                  \
    S(BvhNode) F(BvhNode, bounds) F(BvhNode, child) F(BvhNode, pad)                                \
    S(Triangle) F(Triangle, p0) F(Triangle, p1) F(Triangle, p2)                                   \
    S(TriangleRows) F(TriangleRows, row)                                                          \
    S(TriangleInfo) F(TriangleInfo, material) F(TriangleInfo, light) F(TriangleInfo, normals)     \
        F(TriangleInfo, source_index)                                                             \
    S(TriangleNormals) F(TriangleNormals, n0) F(TriangleNormals, n1) F(TriangleNormals, n2)       \
    S(TriangleUV) F(TriangleUV, u0) F(TriangleUV, v0) F(TriangleUV, u2) F(TriangleUV, v2)         \
    S(TextureInfo) F(TextureInfo, offset) F(TextureInfo, width) F(TextureInfo, height)            \
        F(TextureInfo, format) F(TextureInfo, scale_u) F(TextureInfo, offset_v) F(TextureInfo, clamp) \
    S(Material) F(Material, kd) F(Material, ks) F(Material, ke) F(Material, kind)                 \
        F(Material, ior) F(Material, alpha) F(Material, interior_medium) F(Material, kd_texture)             \
        F(Material, ks_texture) F(Material, ke_texture) F(Material, cutout_texture)               \
        F(Material, cutout_channel) F(Material, bump_texture) F(Material, bump_is_normal_map)     \
        F(Material, bump_scale) F(Material, exterior_medium)                                      \
    S(Medium) F(Medium, sigma_a) F(Medium, sigma_s) F(Medium, sigma_t) F(Medium, g)                \
        F(Medium, majorant) F(Medium, grid_offset) F(Medium, grid_size) F(Medium, world_to_grid)  \
    S(Light) F(Light, position) F(Light, direction) F(Light, emission) F(Light, kind)             \
        F(Light, triangle) F(Light, one_minus_cos_total) F(Light, one_minus_cos_falloff) F(Light, area)   \
        F(Light, select_pdf) F(Light, medium) F(Light, nee_weight)                                        \
    S(Camera) F(Camera, eye) F(Camera, right) F(Camera, up) F(Camera, forward)                    \
        F(Camera, tan_half_width) F(Camera, tan_half_height) F(Camera, lens_radius)               \
        F(Camera, focus_distance) F(Camera, width) F(Camera, height) F(Camera, film_area)         \
        F(Camera, lens_area)                                                                      \
    S(SceneInfo) F(SceneInfo, world_center) F(SceneInfo, light_count)                             \
        F(SceneInfo, environment_light) F(SceneInfo, env_width) F(SceneInfo, env_height)          \
        F(SceneInfo, triangle_count) F(SceneInfo, node_count) F(SceneInfo, camera_medium)         \
        F(SceneInfo, area_light_count)                                                            \
    S(RenderParams) F(RenderParams, width) F(RenderParams, height) F(RenderParams, first_pixel)   \
        F(RenderParams, pixel_count) F(RenderParams, sample_index) F(RenderParams, seed)          \
        F(RenderParams, light_subpaths)                                \
        F(RenderParams, inner_connections) F(RenderParams, pixel_stride)                          \
        F(RenderParams, position_sample_index) F(RenderParams, position_seed)                     \
        F(RenderParams, zsobol_log2_spp) F(RenderParams, zsobol_base4_digits) F(RenderParams, run_pixel) \
        F(RenderParams, run_length) F(RenderParams, light_to_lens) F(RenderParams, run_listed)           \
        F(RenderParams, roulette_camera_from) F(RenderParams, roulette_light_from)                \
        F(RenderParams, camera_image_only) F(RenderParams, subset_moments) F(RenderParams, pad)   \
    S(SplatRecord) F(SplatRecord, r) F(SplatRecord, g) F(SplatRecord, b) F(SplatRecord, pixel)     \
    S(CausticPhoton) F(CausticPhoton, p) F(CausticPhoton, ng) F(CausticPhoton, wi) F(CausticPhoton, beta) \
    S(MergeSlice) F(MergeSlice, photon_begin) F(MergeSlice, cell_begin) F(MergeSlice, cell_mask)   \
        F(MergeSlice, radius) F(MergeSlice, inv_cell) F(MergeSlice, estimate_scale) F(MergeSlice, pad)

#ifdef CLBDPT_DEVICE

/* OpenCL C 1.2 has no <stddef.h>; clang-based compilers (PoCL, most vendors) have the builtin. */
#ifdef __clang__
#define LAYOUT_OFFSETOF(T, f) ((int)__builtin_offsetof(T, f))
#else
#define LAYOUT_OFFSETOF(T, f) ((int)(size_t) & (((__private T*)0)->f))
#endif

/* A struct's alignment is the offset it gets after a single char. */
#define LAYOUT_ALIGN_PROBE(T) \
    typedef struct {          \
        char c;               \
        T t;                  \
    } LayoutAlignProbe_##T;
#define LAYOUT_NO_FIELD(T, f)
CLBDPT_LAYOUT_LIST(LAYOUT_ALIGN_PROBE, LAYOUT_NO_FIELD)

#define LAYOUT_EMIT_STRUCT(T)          \
    out[++n] = (int)sizeof(T);         \
    out[++n] = LAYOUT_OFFSETOF(LayoutAlignProbe_##T, t);
#define LAYOUT_EMIT_FIELD(T, f) out[++n] = LAYOUT_OFFSETOF(T, f);

/* Run as a single work item. out[0] = number of values that follow. */
__kernel void report_layout(__global int* out) {
    int n = 0;
    CLBDPT_LAYOUT_LIST(LAYOUT_EMIT_STRUCT, LAYOUT_EMIT_FIELD)
    out[0] = n;
}

#endif
