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

/* One node of the flattened (depth-first) BVH. An interior node's first child is the next
 * node in the array and its second child is at `offset`; a leaf holds `count` triangles from
 * `offset` on, in the reordered triangle arrays. */
typedef struct {
    float lo[3];
    clbdpt_int offset;
    float hi[3];
    clbdpt_uint meta; /* bits 0..15: triangle count (0 = interior); bits 16..17: split axis */
} BvhNode;

#define BVH_META_COUNT_MASK 0xffffu
#define BVH_META_AXIS_SHIFT 16

/* Size of the traversal stack (cl/bvh.h); the builder keeps every leaf shallower than this. */
#define BVH_MAX_DEPTH 64

/* Triangle corners in BVH order; w is unused (kept 0). */
typedef struct {
    clbdpt_float4 p0, p1, p2;
} Triangle;

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

/* ---- Materials ------------------------------------------------------------------------ */

#define MATERIAL_DIFFUSE 0 /* Kd / pi */
#define MATERIAL_GLOSSY 1  /* Kd / pi + Ks * GGX microfacet reflection */
#define MATERIAL_MIRROR 2  /* perfect specular reflection, reflectance Ks */
#define MATERIAL_GLASS 3   /* smooth dielectric, index ior, Fresnel reflection + refraction */

typedef struct {
    clbdpt_float4 kd; /* diffuse reflectance (rgb) */
    clbdpt_float4 ks; /* specular reflectance (rgb) of the mirror or glossy lobe */
    clbdpt_float4 ke; /* emitted radiance on the front face (rgb), 0 if not emissive */
    clbdpt_int kind;  /* MATERIAL_* */
    float ior;        /* glass: index of refraction inside (front face = outside) */
    float alpha;      /* glossy: GGX roughness alpha */
    clbdpt_int pad0;
} Material;

/* ---- Lights --------------------------------------------------------------------------- */

#define LIGHT_AREA 0
#define LIGHT_POINT 1
#define LIGHT_SPOT 2
#define LIGHT_DIRECTIONAL 3
#define LIGHT_ENVIRONMENT 4

typedef struct {
    clbdpt_float4 position;  /* point, spot */
    clbdpt_float4 direction; /* spot: unit axis; directional: unit direction light travels */
    clbdpt_float4 emission;  /* point/spot: intensity I; directional: radiance; area: Le;
                                environment: radiance (scale of the map if there is one) */
    clbdpt_int kind;         /* LIGHT_* */
    clbdpt_int triangle;     /* area: triangle index (BVH order) */
    float cos_total_width;   /* spot: cosine of the cone's half angle */
    float cos_falloff_start; /* spot: cosine where the falloff starts */
    float area;              /* area: triangle area */
    float select_pdf;        /* probability that light selection picks this light */
    float power;             /* luminance of emitted power, the selection weight */
    clbdpt_int pad0;
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
    clbdpt_int pad0, pad1;
} SceneInfo;

/* ---- Per-launch parameters and outputs ------------------------------------------------- */

typedef struct {
    clbdpt_int width;        /* image size in pixels */
    clbdpt_int height;
    clbdpt_int first_pixel;  /* first pixel index (y * width + x) of this batch */
    clbdpt_int pixel_count;  /* work items in this batch, one sample each */
    clbdpt_uint sample_index; /* which sample of every pixel this launch computes */
    clbdpt_uint seed;
    clbdpt_int max_depth;    /* maximum number of scattering vertices on a path */
    clbdpt_int pad0;
} RenderParams;

/* A contribution that lands at another pixel than the work item's own (t = 1 strategies).
 * Each work item owns max_depth + 1 slots; pixel < 0 marks an empty slot. The host adds the
 * records in slot order, so the light image does not depend on the order work items ran. */
typedef struct {
    float r, g, b;
    clbdpt_int pixel;
} SplatRecord;

#endif
