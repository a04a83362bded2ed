/* Scattering at surfaces (seed ch. 1.4; pbrt-v3 reflection.h, microfacet.h):
 *   MATERIAL_DIFFUSE  Lambertian, f = kd / pi
 *   MATERIAL_GLOSSY   kd / pi + ks * GGX microfacet reflection (Trowbridge-Reitz D, Smith G,
 *                     no Fresnel: reciprocal, and energy conserving since kd + ks <= 1 is
 *                     enforced by the loader and single-scattering GGX reflects <= 1)
 *   MATERIAL_MIRROR   perfect specular reflection with reflectance ks (delta)
 *   MATERIAL_GLASS    smooth dielectric, Fresnel-weighted choice of reflection or refraction
 *                     (delta); radiance through a refraction is scaled by (eta_i / eta_t)^2,
 *                     importance is not (the asymmetry of non-symmetric scattering, seed 1.4)
 * Reflection is two-sided. The lobes live in the shading frame; f is non-zero only where wo and
 * wi lie on the same side of both the shading normal (where bsdf_pdf is non-zero: sampling the
 * BSDF can reach every direction that f lets light through, so estimators that sample it and
 * estimators that join lights agree) and the geometric one (no light through the surface).
 * pbrt-v3 tests the geometric side only; near the terminator of a smooth-shaded coarse mesh its
 * f is then non-zero where its density is 0, and its path tracer and light tracer disagree. */
#ifndef CLBDPT_BSDF_H
#define CLBDPT_BSDF_H

#include "geometry.h"
#include "sampling.h"
#include "shared/types.h"

#define TRANSPORT_RADIANCE 0
#define TRANSPORT_IMPORTANCE 1

typedef struct {
    Frame frame; /* shading frame: frame.n is the shading normal, oriented like ng */
    float3 ng;   /* geometric normal, front face = counter-clockwise winding */
    float3 kd, ks;
    float ior;
    float alpha;
    int kind;
} Bsdf;

inline Bsdf bsdf_make(__global const Material* m, float3 ns, float3 ng) {
    Bsdf b;
    b.frame = frame_from_normal(ns);
    b.ng = ng;
    b.kd = xyz(m->kd);
    b.ks = xyz(m->ks);
    b.ior = m->ior;
    b.alpha = m->alpha;
    b.kind = m->kind;
    return b;
}

inline int bsdf_is_specular(const Bsdf* b) { return b->kind == MATERIAL_MIRROR || b->kind == MATERIAL_GLASS; }

/* ---- GGX (Trowbridge-Reitz) ------------------------------------------------------------ */

inline float ggx_d(float3 wh, float alpha) {
    float cos2 = wh.z * wh.z;
    if (cos2 == 0.0f) return 0.0f;
    float a2 = alpha * alpha;
    float tan2 = (1.0f - cos2) / cos2;
    float e = 1.0f + tan2 / a2;
    return 1.0f / (PI_F * a2 * cos2 * cos2 * e * e);
}

inline float ggx_lambda(float3 w, float alpha) {
    float cos2 = w.z * w.z;
    if (cos2 == 0.0f) return 0.0f;
    float tan2 = fmax(0.0f, 1.0f - cos2) / cos2;
    return 0.5f * (-1.0f + sqrt(1.0f + alpha * alpha * tan2));
}

inline float ggx_g(float3 wo, float3 wi, float alpha) {
    return 1.0f / (1.0f + ggx_lambda(wo, alpha) + ggx_lambda(wi, alpha));
}

/* Half vector sampled from the normals visible from wo (wo.z > 0): D_wo(wh) = G1(wo) max(0,
 * wo.wh) D(wh) / wo.z (Heitz 2018), by Dupuy & Benyoub's spherical caps (2023, "Sampling
 * Visible GGX Normals with Spherical Caps"): wo stretched to the unit-roughness configuration,
 * where the visible normals are those of a uniformly sampled cap of the sphere around it. Unlike
 * sampling D(wh) |cos theta_h|, no half vector faces away from wo and the reflected direction's
 * weight f cos / pdf is at most G2 / G1 <= 1: no spikes at grazing angles. */
inline float3 ggx_sample_visible_wh(float3 wo, float2 u, float alpha) {
    float3 wo_std = normalize((float3)(alpha * wo.x, alpha * wo.y, wo.z));
    float z = (1.0f - u.y) * (1.0f + wo_std.z) - wo_std.z;
    float sin_theta = sqrt(fmax(0.0f, 1.0f - z * z));
    float2 cs = unit_circle_turns(u.x);
    float3 wh_std = (float3)(sin_theta * cs.x, sin_theta * cs.y, z) + wo_std;
    return normalize((float3)(alpha * wh_std.x, alpha * wh_std.y, fmax(wh_std.z, 0.0f)));
}

/* Glossy lobe in the shading frame; wo and wi on the same side (either side). */
inline float3 glossy_f_local(const Bsdf* b, float3 wo, float3 wi) {
    float cos_o = fabs(wo.z), cos_i = fabs(wi.z);
    float3 wh = wi + wo;
    if (cos_o == 0.0f || cos_i == 0.0f || (wh.x == 0.0f && wh.y == 0.0f && wh.z == 0.0f)) return (float3)(0.0f);
    wh = normalize(wh);
    return b->ks * (ggx_d(wh, b->alpha) * ggx_g(wo, wi, b->alpha) / (4.0f * cos_o * cos_i));
}

inline float glossy_pdf_local(const Bsdf* b, float3 wo, float3 wi) {
    if (wo.z * wi.z <= 0.0f) return 0.0f;
    float3 wh = wi + wo;
    if (wh.x == 0.0f && wh.y == 0.0f && wh.z == 0.0f) return 0.0f;
    wh = normalize(wh);
    /* D_wo(wh) / (4 |wo.wh|), the visible normals' density carried to wi; wo.wh > 0 here. */
    return ggx_d(wh, b->alpha) / ((1.0f + ggx_lambda(wo, b->alpha)) * 4.0f * fabs(wo.z));
}

/* Probability of choosing the diffuse lobe when sampling a glossy material. */
inline float glossy_diffuse_probability(const Bsdf* b) {
    float d = luminance(b->kd), s = luminance(b->ks);
    return d + s > 0.0f ? d / (d + s) : 1.0f;
}

/* ---- Fresnel --------------------------------------------------------------------------- */

/* Unpolarised Fresnel reflectance of a dielectric interface; cos_i > 0 means wo is on the
 * front (outside, index 1) side. */
inline float fresnel_dielectric(float cos_i, float eta_outside, float eta_inside) {
    cos_i = clamp(cos_i, -1.0f, 1.0f);
    float eta_i = eta_outside, eta_t = eta_inside;
    if (cos_i < 0.0f) {
        eta_i = eta_inside;
        eta_t = eta_outside;
        cos_i = -cos_i;
    }
    float sin_i = sqrt(fmax(0.0f, 1.0f - cos_i * cos_i));
    float sin_t = eta_i / eta_t * sin_i;
    if (sin_t >= 1.0f) return 1.0f; /* total internal reflection */
    float cos_t = sqrt(fmax(0.0f, 1.0f - sin_t * sin_t));
    float r_parl = ((eta_t * cos_i) - (eta_i * cos_t)) / ((eta_t * cos_i) + (eta_i * cos_t));
    float r_perp = ((eta_i * cos_i) - (eta_t * cos_t)) / ((eta_i * cos_i) + (eta_t * cos_t));
    return 0.5f * (r_parl * r_parl + r_perp * r_perp);
}

/* ---- Evaluation ------------------------------------------------------------------------ */

/* f(wo, wi) for world-space unit directions; 0 for the delta lobes. */
inline float3 bsdf_f(const Bsdf* b, float3 wo_world, float3 wi_world) {
    if (bsdf_is_specular(b)) return (float3)(0.0f);
    float3 wo = to_local(&b->frame, wo_world), wi = to_local(&b->frame, wi_world);
#ifdef HAS_SHADING_NORMALS
    if (wo.z * wi.z <= 0.0f || dot(wi_world, b->ng) * dot(wo_world, b->ng) <= 0.0f) return (float3)(0.0f);
#else
    /* The shading frame's normal is ng itself: the geometric side test is this one, bit for bit. */
    if (wo.z * wi.z <= 0.0f) return (float3)(0.0f);
#endif
    float3 f = b->kd * INV_PI_F;
#ifdef HAS_GLOSSY
    if (b->kind == MATERIAL_GLOSSY) f += glossy_f_local(b, wo, wi);
#endif
    return f;
}

/* Solid-angle density with which bsdf_sample picks wi given wo; 0 for the delta lobes. */
inline float bsdf_pdf(const Bsdf* b, float3 wo_world, float3 wi_world) {
    if (bsdf_is_specular(b)) return 0.0f;
    float3 wo = to_local(&b->frame, wo_world), wi = to_local(&b->frame, wi_world);
    if (wo.z == 0.0f || wo.z * wi.z <= 0.0f) return 0.0f;
    float pdf_diffuse = fabs(wi.z) * INV_PI_F;
#ifdef HAS_GLOSSY
    if (b->kind == MATERIAL_GLOSSY) {
        float pd = glossy_diffuse_probability(b);
        return pd * pdf_diffuse + (1.0f - pd) * glossy_pdf_local(b, wo, wi);
    }
#endif
    return pdf_diffuse;
}

typedef struct {
    float3 wi;   /* world space, unit */
    float3 f;    /* value of the BSDF (for delta lobes: the lobe weight / |cos|, pbrt style) */
    float pdf;   /* solid angle; for delta lobes the discrete probability of the lobe */
    int specular;
} BsdfSample;

/* Samples wi given wo. u.x picks a lobe, u.yz the direction. Returns 0 if nothing was sampled. */
inline int bsdf_sample(const Bsdf* b, float3 wo_world, float3 u, int mode, BsdfSample* out) {
    float3 wo = to_local(&b->frame, wo_world);
    out->specular = 0;
    out->pdf = 0.0f;
    if (wo.z == 0.0f) return 0;
    switch (b->kind) {
#ifdef HAS_MIRROR
    case MATERIAL_MIRROR: {
        float3 wi = (float3)(-wo.x, -wo.y, wo.z);
        out->wi = from_local(&b->frame, wi);
        out->f = b->ks / fabs(wi.z);
        out->pdf = 1.0f;
        out->specular = 1;
        return 1;
    }
#endif
#ifdef HAS_GLASS
    case MATERIAL_GLASS: {
        float F = fresnel_dielectric(wo.z, 1.0f, b->ior);
        out->specular = 1;
        if (u.x < F) {
            float3 wi = (float3)(-wo.x, -wo.y, wo.z);
            out->wi = from_local(&b->frame, wi);
            out->f = (float3)(F / fabs(wi.z));
            out->pdf = F;
            return 1;
        }
        int entering = wo.z > 0.0f;
        float eta_i = entering ? 1.0f : b->ior, eta_t = entering ? b->ior : 1.0f;
        float eta = eta_i / eta_t;
        float3 n = (float3)(0.0f, 0.0f, entering ? 1.0f : -1.0f);
        float cos_i = dot(n, wo);
        float sin2_i = fmax(0.0f, 1.0f - cos_i * cos_i);
        float sin2_t = eta * eta * sin2_i;
        if (sin2_t >= 1.0f) return 0; /* cannot happen: F = 1 then */
        float cos_t = sqrt(1.0f - sin2_t);
        float3 wi = -eta * wo + (eta * cos_i - cos_t) * n;
        float3 ft = (float3)(1.0f - F);
        if (mode == TRANSPORT_RADIANCE) ft *= eta * eta;
        out->wi = from_local(&b->frame, wi);
        out->f = ft / fabs(wi.z);
        out->pdf = 1.0f - F;
        return 1;
    }
#endif
    default:
        break;
    }
    /* Diffuse, or diffuse + glossy. */
    float3 wi;
#ifdef HAS_GLOSSY
    if (b->kind == MATERIAL_GLOSSY && u.x >= glossy_diffuse_probability(b)) {
        float3 wo_up = wo.z < 0.0f ? -wo : wo;
        float3 wh = ggx_sample_visible_wh(wo_up, (float2)(u.y, u.z), b->alpha);
        if (wo.z < 0.0f) wh = -wh;
        wi = -wo + 2.0f * dot(wo, wh) * wh;
    } else
#endif
    {
        wi = sample_cosine_hemisphere((float2)(u.y, u.z));
        if (wo.z < 0.0f) wi.z = -wi.z;
    }
    if (wo.z * wi.z <= 0.0f) return 0;
    out->wi = from_local(&b->frame, wi);
    out->pdf = bsdf_pdf(b, wo_world, out->wi);
    out->f = bsdf_f(b, wo_world, out->wi);
    return out->pdf > 0.0f;
}

#endif
