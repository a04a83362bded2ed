/* Test kernels for cl/bsdf.h (tests/bsdf_test.cpp): bsdf_sample, bsdf_pdf and bsdf_f of one
 * material, called exactly as random_walk and mis_weight call them. Build with the HAS_* flags
 * of the lobes under test (HAS_GLOSSY, HAS_MIRROR, HAS_GLASS). */
#include "bsdf.h"
#include "rng.h"

/* One bsdf_sample per work item for the fixed outgoing direction wo (world space, unit), with
 * u from the counter-based RNG keyed by (item, seed). Per item, three float4:
 *   out[3i]     (wi, pdf)                    the sample
 *   out[3i + 1] (f, flags)                   flags = returned value + 2 * specular
 *   out[3i + 2] (bsdf_pdf(wo, wi), bsdf_f(wo, wi).x, .y, .z)   evaluated separately */
__kernel void bsdf_sample_test(__global const Material* materials, int material, float4 ns, float4 ng,
                               float4 wo, int mode, uint seed, __global float4* out) {
    int gid = get_global_id(0);
    Bsdf b = bsdf_make(&materials[material], ns.xyz, ng.xyz);
    Rng rng = rng_init((uint)gid, 0u, seed);
    float3 u = (float3)(rng_next(&rng), rng_next(&rng), rng_next(&rng));
    BsdfSample bs;
    bs.wi = (float3)(0.0f);
    bs.f = (float3)(0.0f);
    int ok = bsdf_sample(&b, wo.xyz, u, mode, &bs);
    float pdf = 0.0f;
    float3 f = (float3)(0.0f);
    if (ok) {
        pdf = bsdf_pdf(&b, wo.xyz, bs.wi);
        f = bsdf_f(&b, wo.xyz, bs.wi);
    }
    out[3 * gid] = (float4)(bs.wi, bs.pdf);
    out[3 * gid + 1] = (float4)(bs.f, (float)(ok + 2 * bs.specular));
    out[3 * gid + 2] = (float4)(pdf, f.x, f.y, f.z);
}

/* bsdf_pdf and bsdf_f at given (wo, wi) pairs: out[i] = (pdf, f). */
__kernel void bsdf_eval_test(__global const Material* materials, int material, float4 ns, float4 ng,
                             __global const float4* wo, __global const float4* wi, __global float4* out) {
    int gid = get_global_id(0);
    Bsdf b = bsdf_make(&materials[material], ns.xyz, ng.xyz);
    float3 f = bsdf_f(&b, wo[gid].xyz, wi[gid].xyz);
    out[gid] = (float4)(bsdf_pdf(&b, wo[gid].xyz, wi[gid].xyz), f.x, f.y, f.z);
}
