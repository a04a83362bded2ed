/* Cut-outs (alpha test): leaves, fences and curtains are quads whose texture says where the
 * surface is. A hit where the material's cutout texture is below 1/2 does not count, for
 * closest-hit, shadow and connection rays alike (cl/bvh.h asks cutout_hides for every hit),
 * so every strategy sees the same holes. Compiled in only with HAS_CUTOUTS. */
#ifndef CLBDPT_CUTOUTS_H
#define CLBDPT_CUTOUTS_H

#include "shared/types.h"
#include "textures.h"

typedef struct {
    __global const TriangleInfo* infos;
    __global const Material* materials;
    __global const TriangleUV* uvs;
    Textures textures;
} Cutouts;

/* Texture coordinates at barycentrics (b1, b2) of triangle `tri` (BVH order). */
inline float2 triangle_uv(__global const TriangleUV* uvs, int tri, float b1, float b2) {
    __global const TriangleUV* t = &uvs[tri];
    float b0 = 1.0f - b1 - b2;
    return (float2)(b0 * t->u0 + b1 * t->u1 + b2 * t->u2, b0 * t->v0 + b1 * t->v1 + b2 * t->v2);
}

/* Cut-out threshold: at or above it a surface is there. Bilinear filtering makes the edge of
 * a binary mask fall at half-way between its texels. */
#define CUTOUT_THRESHOLD 0.5f

inline bool cutout_hides(const Cutouts* c, int tri, float b1, float b2) {
    __global const Material* m = &c->materials[c->infos[tri].material];
    if (m->cutout_texture == 0) return false;
    float4 v = texture_lookup(&c->textures, m->cutout_texture, triangle_uv(c->uvs, tri, b1, b2));
    return (m->cutout_channel == 3 ? v.w : v.x) < CUTOUT_THRESHOLD;
}

#endif
