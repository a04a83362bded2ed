/* Every struct that crosses the host/device boundary, compiled both as OpenCL C (device) and as
 * C++ (host, through compat.h). The host static_asserts sizes and offsets in
 * host/device/layout_checks.cpp, so a layout mismatch cannot compile.
 *
 * Rules: no float3 in buffers (16 bytes on the device, 12 in C), explicit padding, 16-byte
 * multiples for anything stored in arrays. */
#ifndef CLBDPT_TYPES_H
#define CLBDPT_TYPES_H

#include "shared/compat.h"

/* ---- Geometry ------------------------------------------------------------------------- */

/* One node of the BVH_WIDTH-wide BVH, flattened depth-first: a node's interior children follow
 * it in child order, each with its whole subtree. The children's boxes are stored by plane, all
 * children at a time, so the traversal tests them with one vector operation per plane:
 * bounds[2k][i] and bounds[2k + 1][i] are the lower and upper planes on axis k (x, y, z) of
 * child i. An unused child slot has an empty box (lower +inf, upper -inf) that no ray enters.
 * child[i] >= 0: the node index of an interior child; child[i] < 0: a leaf of
 * BVH_LEAF_COUNT(child[i]) triangles from BVH_LEAF_FIRST(child[i]) on, in the reordered
 * triangle arrays. The root is node 0. */
#define BVH_WIDTH 8 /* 4 works too (host and device both follow this header) */
typedef struct {
    float bounds[6][BVH_WIDTH];
    clbdpt_int child[BVH_WIDTH];
    clbdpt_int pad[BVH_WIDTH]; /* to a power of two bytes: whole cache lines per node */
} BvhNode;

#define BVH_LEAF_BITS 4 /* bits of a leaf's triangle count in its child entry */
#define BVH_LEAF(first, count) (~(((first) << BVH_LEAF_BITS) | (count)))
#define BVH_LEAF_FIRST(c) ((~(c)) >> BVH_LEAF_BITS)
#define BVH_LEAF_COUNT(c) ((~(c)) & ((1 << BVH_LEAF_BITS) - 1))

/* Entries of the traversal stack (cl/bvh.h); the builder guarantees that no traversal of its
 * tree needs more. */
#define BVH_STACK_SIZE 64

/* Triangle corners in BVH order, as the host keeps them (the device's copy is TriangleRows,
 * below). The w lanes hold the unit geometric normal, normalize((p1 - p0) x (p2 - p0))
 * computed in double on the host (p0.w, p1.w, p2.w = x, y, z; host/render/device_scene.cpp):
 * every hit and every area-light sample needs it, and the lanes are loaded with the corners
 * anyway. */
typedef struct {
    clbdpt_float4 p0, p1, p2;
} Triangle;

/* The device's copy of a Triangle, transposed at the upload (triangle_rows, host/render/
 * device_scene.cpp): row k = (p0[k], p1[k], p2[k], n[k]), the corners' coordinate k and the
 * normal's. The watertight test permutes the axes per ray (cl/bvh.h), and a row by index is
 * one vector load that holds all three corners, where corners by index took nine scalar loads. */
typedef struct {
    clbdpt_float4 row[3];
} TriangleRows;

/* Per-triangle attributes, same order as Triangle. */
typedef struct {
    clbdpt_int material;     /* index into the material array */
    clbdpt_int light;        /* index into the light array if emissive, else -1 */
    clbdpt_int normals;      /* index into the TriangleNormals array, -1 = flat shading */
    clbdpt_int source_index; /* triangle index in load order, for debugging and tests */
} TriangleInfo;

/* Per-vertex shading normals of one triangle (unit length, w unused). */
typedef struct {
    clbdpt_float4 n0, n1, n2;
} TriangleNormals;

/* Texture coordinates of one triangle's corners, same order as Triangle (only in scenes with
 * textures; (0, 0) at corners the OBJ gave none). */
typedef struct {
    float u0, v0, u1, v1, u2, v2;
    float pad0, pad1;
} TriangleUV;

/* ---- Textures ------------------------------------------------------------------------- */

#define TEXTURE_RGBA8_SRGB 0 /* one uint per texel: r | g << 8 | b << 16 | a << 24, sRGB-encoded rgb */
#define TEXTURE_RGBA32F 1    /* four uints per texel: the bits of linear float r, g, b, a */
#define TEXTURE_RGBA8_LINEAR 2 /* as TEXTURE_RGBA8_SRGB, values taken as they are (bump and normal maps) */

/* One use of an image by a material (the MTL's map options are per use, the texels shared):
 * texel (x, y), row 0 at the top of the image, starts at texels[offset + (y * width + x) *
 * stride] with stride 1 or 4 by format. (u, v) is first mapped to (u * scale_u + offset_u,
 * v * scale_v + offset_v) (MTL -s, -o), then wrapped (repeat), or clamped to [0, 1] with
 * MTL -clamp on; v = 0 is the bottom of the image (OBJ convention). */
typedef struct {
    clbdpt_uint offset;
    clbdpt_int width, height;
    clbdpt_int format; /* TEXTURE_* */
    float scale_u, scale_v, offset_u, offset_v;
    clbdpt_int clamp;
    clbdpt_int pad0, pad1, pad2;
} TextureInfo;

/* ---- Materials ------------------------------------------------------------------------ */

#define MATERIAL_DIFFUSE 0 /* Kd / pi */
#define MATERIAL_GLOSSY 1  /* Kd / pi + Ks * GGX microfacet reflection */
#define MATERIAL_MIRROR 2  /* perfect specular reflection, reflectance Ks */
#define MATERIAL_GLASS 3   /* smooth dielectric, index ior, Fresnel reflection + refraction */
#define MATERIAL_INTERFACE 4 /* no surface at all, only where media meet (pbrt's Material ""): rays
                                pass it unchanged and enter the medium on its other side */

typedef struct {
    clbdpt_float4 kd; /* diffuse reflectance (rgb) */
    clbdpt_float4 ks; /* specular reflectance (rgb) of the mirror or glossy lobe */
    clbdpt_float4 ke; /* emitted radiance on the front face (rgb), 0 if not emissive */
    clbdpt_int kind;  /* MATERIAL_* */
    float ior;        /* glass: index of refraction inside (front face = outside) */
    float alpha;      /* glossy: GGX roughness alpha */
    /* Participating media on either side (1 + the Medium index, 0 = vacuum): interior behind
     * the back face, exterior in front of the front face (the winding's normal side). A
     * scene-wide medium is on both sides unless the scene file says otherwise. */
    clbdpt_int interior_medium;
    /* Textures: 1 + the TextureInfo index, 0 = none (so a zero-initialised Material has none).
     * A reflectance map multiplies kd or ks (the MTL rule). */
    clbdpt_int kd_texture;    /* map_Kd */
    clbdpt_int ks_texture;    /* map_Ks */
    clbdpt_int ke_texture;    /* map_Ke: multiplies ke */
    clbdpt_int cutout_texture; /* alpha test (map_d, or map_Kd's alpha channel): below 1/2 is a hole */
    clbdpt_int cutout_channel; /* 3: alpha channel; 0: the first (grey) channel */
    clbdpt_int bump_texture;  /* bump / map_bump (a height field) or norm (a tangent-space normal map) */
    clbdpt_int bump_is_normal_map;
    float bump_scale;         /* height map: MTL -bm, multiplies BUMP_HEIGHT_IN_TEXELS (cl/bump.h) */
    clbdpt_int exterior_medium; /* see interior_medium */
    clbdpt_int pad1, pad2, pad3;
} Material;

/* ---- Participating media -------------------------------------------------------------- */

/* A participating medium (cl/medium.h): coefficients per scene unit and RGB channel, and the
 * Henyey-Greenstein asymmetry of its phase function (-1 < g < 1, 0 isotropic). A homogeneous
 * medium has them everywhere; a grid medium (grid_offset >= 0) has them times a density,
 * interpolated trilinearly between the voxels of a grid and 0 outside it. */
typedef struct {
    clbdpt_float4 sigma_a; /* absorption (per unit density in a grid medium) */
    clbdpt_float4 sigma_s; /* scattering */
    clbdpt_float4 sigma_t; /* extinction: sigma_a + sigma_s, stored to save the sum per use */
    float g;
    float majorant;        /* grid: the largest extinction of any channel anywhere in the grid */
    clbdpt_int grid_offset; /* grid: its first voxel in the density buffer; -1: homogeneous */
    clbdpt_int pad0;
    clbdpt_int grid_size[4]; /* grid: voxels along x, y, z (x fastest in the buffer); unused w */
    /* grid: rows of the affine map from scene space to voxel coordinates, in which voxel
     * (i, j, k) is centred at (i, j, k) and the grid spans -0.5 .. size - 0.5 */
    clbdpt_float4 world_to_grid[3];
} Medium;

/* ---- Lights --------------------------------------------------------------------------- */

#define LIGHT_AREA 0
#define LIGHT_POINT 1
#define LIGHT_SPOT 2
#define LIGHT_DIRECTIONAL 3
#define LIGHT_ENVIRONMENT 4

/* The most lights a scene may have for light samples with spot cones in view (NEE_CONE_AWARE,
 * cl/lights.h: each sample weighs every light). */
#define NEE_CONE_AWARE_MAX_LIGHTS 8

typedef struct {
    clbdpt_float4 position;  /* point, spot */
    clbdpt_float4 direction; /* spot: unit axis; directional: unit direction light travels */
    clbdpt_float4 emission;  /* point/spot: intensity I; directional: radiance; area: Le;
                                environment: radiance (scale of the map if there is one) */
    clbdpt_int kind;         /* LIGHT_* */
    clbdpt_int triangle;     /* area: triangle index (BVH order) */
    /* spot: 1 - cos of the cone's half angle, and of the angle where the falloff starts (kept as
     * 1 - cos, not cos: a cone of 0.01 degrees has cos = 1 - 1.5e-8, which is 1 in float) */
    float one_minus_cos_total;
    float one_minus_cos_falloff;
    float area;              /* area: triangle area */
    float select_pdf;        /* probability that light selection picks this light, in
                                proportion to its power (DeviceScene::light_power) */
    clbdpt_int medium;       /* point, spot: the medium around the light (1 + index, 0 = vacuum) */
    float nee_weight;        /* spot: its weight for a light sample from a point inside its cone
                                (cl/lights.h, sample_light_for_point): 4 pi I over the lights'
                                total power; 0 for other lights, which use select_pdf */
} Light;

/* ---- Camera --------------------------------------------------------------------------- */

/* Perspective camera with an optional thin lens. Raster (x right, y down, in pixels) maps to
 * the z=1 plane of camera space as ((2x/W - 1) tan_half_width, (1 - 2y/H) tan_half_height). */
typedef struct {
    clbdpt_float4 eye;
    clbdpt_float4 right;   /* unit, camera-space +x in world space */
    clbdpt_float4 up;      /* unit, camera-space +y */
    clbdpt_float4 forward; /* unit, camera-space +z (viewing direction) */
    float tan_half_width;  /* half extent of the film on the z=1 plane */
    float tan_half_height;
    float lens_radius;     /* 0 = pinhole */
    float focus_distance;  /* distance along forward to the plane in focus */
    clbdpt_int width;      /* film size in pixels */
    clbdpt_int height;
    float film_area;       /* area of the film on the z=1 plane: 4 tan_half_width tan_half_height */
    float lens_area;       /* pi r^2, or 1 for a pinhole (pbrt's convention) */
} Camera;

/* ---- Scene-wide constants -------------------------------------------------------------- */

typedef struct {
    clbdpt_float4 world_center; /* bounding sphere of the scene; w = radius */
    clbdpt_int light_count;
    clbdpt_int environment_light; /* index of the environment light, -1 if none */
    clbdpt_int env_width;         /* lat-long map size, 0 if constant radiance */
    clbdpt_int env_height;
    clbdpt_int triangle_count;
    clbdpt_int node_count;
    clbdpt_int camera_medium; /* the medium around the camera (1 + index, 0 = vacuum) */
    clbdpt_int area_light_count; /* lights[0 .. area_light_count - 1] are the area lights */
} SceneInfo;

/* ---- Per-launch parameters and outputs ------------------------------------------------- */

/* A first bounce of Russian roulette beyond any path's depth. */
#define RUSSIAN_ROULETTE_OFF 0x40000000

typedef struct {
    clbdpt_int width;        /* image size in pixels */
    clbdpt_int height;
    clbdpt_int first_pixel;  /* first pixel index (y * width + x) of this batch */
    clbdpt_int pixel_count;  /* work items in this batch, one sample each */
    clbdpt_uint sample_index; /* which sample of every pixel this launch computes */
    clbdpt_uint seed;
    /* The strategy mix (cl/strategies.h, StrategyMix): light subpaths traced per pixel sample
     * (0 .. 1; a fraction is a probability, stratified over a pixel's samples) and whether
     * subpaths are joined by connections with s >= 2 and t >= 2. */
    float light_subpaths;
    clbdpt_int inner_connections;
    /* 1: the launch's work items are pixels first_pixel ..; k > 1: items run over one pixel of
     * each k x k block (render_item_pixel), the strategy pilot's sparse passes. */
    clbdpt_int pixel_stride;
    /* The sample and seed whose pixel-position draw the launch uses: sample_index and seed,
     * except in the pilot's paired passes, which share positions to tell the variance of the
     * pixel integral from the rest. */
    clbdpt_uint position_sample_index;
    clbdpt_uint position_seed;
    /* SAMPLER_ZSOBOL only (cl/rng.h): log2 of the spp rounded up to a power of two, and the
     * base-4 digits of the image-wide sample index. */
    clbdpt_int zsobol_log2_spp;
    clbdpt_int zsobol_base4_digits;
    /* run_length > 0: the launch renders many samples of a run of pixels, run_pixel ..
     * run_pixel + run_length - 1 (adaptive sampling's extra samples, host/render/adaptive.h):
     * item i is pixel run_pixel + i % run_length at sample sample_index + i / run_length (and
     * position sample position_sample_index + i / run_length), pixel_stride unused. */
    clbdpt_int run_pixel;
    clbdpt_int run_length;
    /* Whether bdpt uses strategy (1,1) (cl/strategies.h): with a thin lens or media. (The
     * maximum depth is the kernel's MAX_DEPTH, not a parameter.) */
    clbdpt_int light_to_lens;
    /* run_listed = 1: the run's pixels are run_pixels[run_pixel + j], j < run_length (the
     * kernel's pixel list argument), scattered over the film, instead of consecutive. */
    clbdpt_int run_listed;
    /* Russian roulette (cl/russian_roulette.h): the bounce of a camera and of a light subpath
     * from which it may end the subpath; RUSSIAN_ROULETTE_OFF: never. */
    clbdpt_int roulette_camera_from;
    clbdpt_int roulette_light_from;
    /* 1: only the camera image is kept (adaptive sampling's extra samples, whose light-image
     * splats are dropped): a mix without inner connections then has no use for a light subpath
     * and traces none. Its camera image is the same bit for bit (its strategies, s <= 1, draw
     * nothing of the light subpath's and are weighed by the mix as before). */
    clbdpt_int camera_image_only;
    /* 1: the launch also writes each item's subset moments (render.cl's subset_moments
     * argument; bdpt only): the strategy pilot's passes of full bdpt. */
    clbdpt_int subset_moments;
    clbdpt_int pad[3]; /* to a multiple of 16 bytes */
} RenderParams;

/* Work items of a pass with pixel_stride `stride` over a width x height film. */
inline clbdpt_int render_item_count(clbdpt_int width, clbdpt_int height, clbdpt_int stride) {
    return ((width + stride - 1) / stride) * ((height + stride - 1) / stride);
}

/* The pixel (y * width + x) of work item `item` in a launch with pixel_stride `stride`: for
 * k > 1, one pixel of the item's k x k block, at a position hashed from the block's number. A
 * fixed corner lines the sparse grid up with a scene's axis-aligned edges, where a path tracer's
 * error sits (on the Cornell box, 95% of a 1-spp pt image's squared error is in 0.5% of its
 * pixels, at the light's outline): the mean of a 1-spp pt image's squared error over ten
 * stride-5 grids of fixed corners (rows offset by 0-4, columns by 0 or 2) ranged 0.0032-0.14,
 * against 0.053 over all pixels. The pilot chose by where its grid fell. The hash is fixed, so every pass of a stride sees the
 * same pixels. */
inline clbdpt_int render_item_pixel(clbdpt_int item, clbdpt_int width, clbdpt_int height,
                                    clbdpt_int stride) {
    if (stride == 1) return item; /* a whole pass: its items are its pixels, in order */
    clbdpt_int columns = (width + stride - 1) / stride;
    clbdpt_int x = (item % columns) * stride, y = (item / columns) * stride;
    if (stride > 1) {
        clbdpt_uint h = (clbdpt_uint)item * 0x9e3779b9u; /* lowbias32 of the block's number */
        h ^= h >> 16;
        h *= 0x7feb352du;
        h ^= h >> 15;
        h *= 0x846ca68bu;
        h ^= h >> 16;
        clbdpt_int block_width = width - x < stride ? width - x : stride;
        clbdpt_int block_height = height - y < stride ? height - y : stride;
        x += (clbdpt_int)((h & 0xffffu) % (clbdpt_uint)block_width);
        y += (clbdpt_int)((h >> 16) % (clbdpt_uint)block_height);
    }
    return y * width + x;
}

/* The pixel of work item `item` of a launch: with run_length > 0 (RenderParams) the run's pixel
 * run_pixel + item % run_length (its sample is item / run_length further on), else the pass's
 * render_item_pixel. The kernel and the host's collection of its outputs both map items so. */
inline clbdpt_int launch_item_pixel(clbdpt_int item, clbdpt_int width, clbdpt_int height, clbdpt_int stride,
                                    clbdpt_int run_pixel, clbdpt_int run_length) {
    return run_length > 0 ? run_pixel + item % run_length : render_item_pixel(item, width, height, stride);
}

/* A contribution that lands at another pixel than the work item's own (t = 1 strategies).
 * Each work item owns max_depth + 1 slots; pixel < 0 marks an empty slot. The host adds the
 * records in slot order, so the light image does not depend on the order work items ran. */
typedef struct {
    float r, g, b;
    clbdpt_int pixel;
} SplatRecord;

/* ---- Caustic merging (cl/caustic_merging.h) --------------------------------------------- */

/* A light subpath's first vertex on a non-specular surface that it reached through one or more
 * specular vertices (mirror, glass) from an area light. */
typedef struct {
    clbdpt_float4 p;    /* xyz: position; w: the vertex's index on its light subpath (>= 2), as a float */
    clbdpt_float4 ng;   /* xyz: geometric normal */
    clbdpt_float4 wi;   /* xyz: unit direction toward the previous (specular) vertex */
    clbdpt_float4 beta; /* xyz: the light subpath's throughput arriving there (power per path) */
} CausticPhoton;

/* One pass's caustic photons: photons[photon_begin + i] for i in [cells[cell_begin + h],
 * cells[cell_begin + h + 1]) lie in the grid cells whose hash & cell_mask is h. Cells are
 * 2 radius wide, so a disk of the radius around a point overlaps at most 2 x 2 x 2 of them. */
typedef struct {
    clbdpt_uint photon_begin;
    clbdpt_uint cell_begin;
    clbdpt_uint cell_mask;
    float radius;
    float inv_cell;    /* 1 / (2 radius) */
    float estimate_scale; /* 1 / (light subpaths traced for the pass x pi radius^2) */
    clbdpt_int pad[2];
} MergeSlice;

/* The hash of grid cell (x, y, z) (Teschner et al. 2003); host and device bin by the same one. */
inline clbdpt_uint merge_cell_hash(clbdpt_int x, clbdpt_int y, clbdpt_int z) {
    return ((clbdpt_uint)x * 73856093u) ^ ((clbdpt_uint)y * 19349663u) ^ ((clbdpt_uint)z * 83492791u);
}

#endif
