/* Bump and normal maps (MTL bump / map_bump, norm): the shading normal of a hit is perturbed in
 * the tangent frame of the triangle's texture parameterisation (t along dp/du, b toward dp/dv,
 * n the interpolated shading normal). Everything downstream reads v->ns, so the BSDF, its
 * densities and the adjoint shading-normal correction on light subpaths (cl/vertex.h) all see
 * the same perturbed normal, and bdpt, pt and lt stay consistent. Compiled in only with
 * HAS_BUMP_MAPS (which brings HAS_SHADING_NORMALS). */
#ifndef CLBDPT_BUMP_H
#define CLBDPT_BUMP_H

#include "geometry.h"
#include "scene.h"
#include "textures.h"

/* Height maps hold values in [0, 1] without a unit. They are read as heights measured in
 * texels, a value range of 1 spanning this many texels of height (times MTL -bm), so that a
 * map looks equally bumpy on any model size or texture scale. */
#define BUMP_HEIGHT_IN_TEXELS 4.0f

inline float3 bumped_normal(const SceneData* scene, __global const TriangleRows* tri, int triangle,
                            __global const Material* m, float2 uv, float3 ns) {
    __global const TriangleUV* t_uv = &scene->uvs[triangle];
    float2 duv02 = (float2)(t_uv->u0 - t_uv->u2, t_uv->v0 - t_uv->v2);
    float2 duv12 = (float2)(t_uv->u1 - t_uv->u2, t_uv->v1 - t_uv->v2);
    float det = duv02.x * duv12.y - duv02.y * duv12.x;
    if (!(fabs(det) > 0.0f)) return ns; /* no usable parameterisation (e.g. no texture coordinates) */
    float3 p0, p1, p2;
    triangle_corners(tri, &p0, &p1, &p2);
    float3 dp02 = p0 - p2, dp12 = p1 - p2;
    float3 dpdu = (duv12.y * dp02 - duv02.y * dp12) / det;
    float3 dpdv = (duv02.x * dp12 - duv12.x * dp02) / det;

    float3 tangent = dpdu - ns * dot(ns, dpdu);
    float tangent2 = length_squared(tangent);
    if (!(tangent2 > 0.0f) || !isfinite(tangent2)) return ns;
    tangent *= rsqrt(tangent2);
    float3 bitangent = cross(ns, tangent);
    if (dot(bitangent, dpdv) < 0.0f) bitangent = -bitangent;

    float3 n_tangent;
    if (m->bump_is_normal_map) {
        /* rgb = (n + 1) / 2 in the tangent frame (green toward +v, OpenGL's convention). */
        n_tangent = texture_lookup(&scene->textures, m->bump_texture, uv).xyz * 2.0f - 1.0f;
    } else {
        /* Forward differences one texel apart in u and in v. */
        __global const TextureInfo* info = &scene->textures.infos[m->bump_texture - 1];
        float du = 1.0f / ((float)info->width * fmax(fabs(info->scale_u), 1e-6f));
        float dv = 1.0f / ((float)info->height * fmax(fabs(info->scale_v), 1e-6f));
        float h = texture_lookup(&scene->textures, m->bump_texture, uv).x;
        float hu = texture_lookup(&scene->textures, m->bump_texture, uv + (float2)(du, 0.0f)).x;
        float hv = texture_lookup(&scene->textures, m->bump_texture, uv + (float2)(0.0f, dv)).x;
        float k = m->bump_scale * BUMP_HEIGHT_IN_TEXELS;
        n_tangent = (float3)(-(hu - h) * k, -(hv - h) * k, 1.0f);
    }
    if (!(n_tangent.z > 0.0f)) return ns; /* a normal below the surface: the map is broken there */
    float3 n = n_tangent.x * tangent + n_tangent.y * bitangent + n_tangent.z * ns;
    float n2 = length_squared(n);
    if (!(n2 > 0.0f) || !isfinite(n2)) return ns;
    return n * rsqrt(n2);
}

#endif
