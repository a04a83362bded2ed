// MTL material -> device Material.
//
//   illum 5                      -> MATERIAL_MIRROR, ks = Ks
//   illum 7                      -> MATERIAL_GLASS, ior = Ni (1.5 when Ni is missing or <= 1)
//   Ks != 0 (illum not 5 or 7)   -> MATERIAL_GLOSSY, kd = Kd, ks = Ks, GGX alpha from Pr or Ns
//   otherwise                    -> MATERIAL_DIFFUSE, kd = Kd
//   Ke (any kind)                -> ke, radiance of a one-sided area light (front face = CCW)
//
// Texture maps are attached by mtl_textures.cpp. Anything else the MTL says and the renderer
// cannot show (other illum models, a transmission filter, dissolve, map_Ns and other maps, the
// PBR extras) is reported back to the loader, which warns once per kind with a count.
#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include <tiny_obj_loader.h>

#include "scene/loader_internal.h"

namespace clbdpt::detail {
namespace {

// Default index of refraction for an illum 7 material without a usable Ni (crown glass).
constexpr float kDefaultGlassIor = 1.5f;
// GGX alpha range: below 1e-3 the lobe is a mirror in all but name and its pdf overflows floats;
// above 1 the Beckmann-equivalent mapping has no meaning.
constexpr float kMinAlpha = 1e-3f;
constexpr float kMaxAlpha = 1.0f;

clbdpt_float4 rgb(float r, float g, float b) {
    clbdpt_float4 v;
    v.s[0] = r;
    v.s[1] = g;
    v.s[2] = b;
    v.s[3] = 0.0f;
    return v;
}

bool any_positive(const clbdpt_float4& v) { return v.s[0] > 0 || v.s[1] > 0 || v.s[2] > 0; }

// Reads an MTL colour, replacing negative or non-finite channels by 0 (noted in `unsupported`).
clbdpt_float4 color(const tinyobj::real_t c[3], const char* key, std::vector<std::string>* unsupported) {
    clbdpt_float4 v = rgb(static_cast<float>(c[0]), static_cast<float>(c[1]), static_cast<float>(c[2]));
    bool clamped = false;
    for (int i = 0; i < 3; ++i) {
        if (!std::isfinite(v.s[i]) || v.s[i] < 0) {
            v.s[i] = 0.0f;
            clamped = true;
        }
    }
    if (clamped) unsupported->push_back(std::string("negative ") + key);
    return v;
}

// The features of `mtl` the renderer has no equivalent for, as MTL spells them.
void collect_unsupported(const tinyobj::material_t& mtl, std::vector<std::string>* unsupported) {
    // map_Kd, map_Ks, map_Ke, map_d, bump and norm are read (mtl_textures.cpp); map_Ka is ambient,
    // which a physically based renderer has no use for, and is ignored without a word.
    const std::pair<const std::string*, const char*> textures[] = {
        {&mtl.specular_highlight_texname, "map_Ns"}, {&mtl.displacement_texname, "disp"},
        {&mtl.reflection_texname, "refl"},           {&mtl.roughness_texname, "map_Pr"},
        {&mtl.metallic_texname, "map_Pm"},           {&mtl.sheen_texname, "map_Ps"},
    };
    for (const auto& [name, key] : textures) {
        if (!name->empty()) unsupported->push_back(key);
    }

    const int illum = mtl.illum;
    if (!(illum == 0 || illum == 1 || illum == 2 || illum == 5 || illum == 7)) {
        unsupported->push_back("illum " + std::to_string(illum));
    }
    // Tf 0 0 0 (tinyobj's default) and Tf 1 1 1 (what many exporters write on every material)
    // say nothing the renderer would draw differently; a coloured filter does.
    const auto* tf = mtl.transmittance;
    const bool tf_neutral = (tf[0] == 0 && tf[1] == 0 && tf[2] == 0) || (tf[0] == 1 && tf[1] == 1 && tf[2] == 1);
    if (!tf_neutral) unsupported->push_back("Tf");
    // Glass is transparent already; on anything else dissolve would be alpha blending.
    if (mtl.dissolve < 1 && illum != 7 && mtl.alpha_texname.empty()) unsupported->push_back("d (dissolve)");
    if (mtl.metallic > 0) unsupported->push_back("Pm");
    if (mtl.sheen > 0) unsupported->push_back("Ps");
    if (mtl.clearcoat_thickness > 0) unsupported->push_back("Pc");
    if (mtl.clearcoat_roughness > 0) unsupported->push_back("Pcr");
    if (mtl.anisotropy > 0) unsupported->push_back("aniso");
    if (mtl.anisotropy_rotation > 0) unsupported->push_back("anisor");
    for (const auto& [key, value] : mtl.unknown_parameter) {
        (void)value;
        unsupported->push_back(key);
    }
}

}  // namespace

Material default_material() {
    Material m{};
    m.kd = rgb(0.5f, 0.5f, 0.5f);
    m.kind = MATERIAL_DIFFUSE;
    m.ior = 1.0f;
    return m;
}

bool is_emissive(const Material& m) { return any_positive(m.ke); }

Material map_mtl_material(const tinyobj::material_t& mtl, std::vector<std::string>* unsupported, bool* rescaled) {
    collect_unsupported(mtl, unsupported);
    const clbdpt_float4 kd = color(mtl.diffuse, "Kd", unsupported);
    const clbdpt_float4 ks = color(mtl.specular, "Ks", unsupported);
    const clbdpt_float4 ke = color(mtl.emission, "Ke", unsupported);

    Material m{};
    m.ke = ke;
    m.ior = 1.0f;
    if (mtl.illum == 5) {
        m.kind = MATERIAL_MIRROR;
        m.ks = ks;
    } else if (mtl.illum == 7) {
        m.kind = MATERIAL_GLASS;
        m.ior = (std::isfinite(mtl.ior) && mtl.ior > 1.0f) ? static_cast<float>(mtl.ior) : kDefaultGlassIor;
        m.ks = rgb(1.0f, 1.0f, 1.0f);  // unused by the dielectric; neutral if read as a tint
    } else if (any_positive(ks)) {
        m.kind = MATERIAL_GLOSSY;
        m.kd = kd;
        m.ks = ks;
        float alpha;
        if (mtl.roughness > 0) {
            // PBR roughness is perceptual: alpha = roughness^2 (Burley; the glTF convention).
            alpha = static_cast<float>(mtl.roughness * mtl.roughness);
        } else {
            // Phong exponent -> Beckmann-equivalent roughness, alpha = sqrt(2 / (Ns + 2))
            // (Walter et al. 2007, eq. 30). tinyobj's Ns defaults to 1 when the MTL has none.
            const float ns = std::max(0.0f, static_cast<float>(mtl.shininess));
            alpha = std::sqrt(2.0f / (ns + 2.0f));
        }
        if (!std::isfinite(alpha)) alpha = kMaxAlpha;
        m.alpha = std::clamp(alpha, kMinAlpha, kMaxAlpha);
    } else {
        m.kind = MATERIAL_DIFFUSE;
        m.kd = kd;
    }

    // A surface cannot reflect more than it receives: where kd + ks > 1, scale both so the
    // channel sums to 1. (Glass has no kd/ks lobes to balance.)
    *rescaled = false;
    if (m.kind != MATERIAL_GLASS) {
        for (int i = 0; i < 3; ++i) {
            const float sum = m.kd.s[i] + m.ks.s[i];
            if (sum > 1.0f) {
                m.kd.s[i] /= sum;
                m.ks.s[i] /= sum;
                *rescaled = true;
            }
        }
    }
    return m;
}

}  // namespace clbdpt::detail
