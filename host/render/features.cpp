#include "render/features.h"

#include <optional>

#include "util/error.h"

namespace clbdpt {

const char* integrator_name(Integrator integrator) {
    switch (integrator) {
    case Integrator::Pt: return "pt";
    case Integrator::Lt: return "lt";
    default: return "bdpt";
    }
}

std::string roulette_name(int from_bounce) {
    return from_bounce >= kRouletteOff ? "off" : "from bounce " + std::to_string(from_bounce);
}

namespace {

// A first bounce (0 .. 1024) or "off", as text; nullopt for anything else.
std::optional<int> parse_bounce_or_off(const std::string& text) {
    if (text == "off") return kRouletteOff;
    size_t used = 0;
    int bounce = -1;
    try {
        bounce = std::stoi(text, &used);
    } catch (const std::exception&) {
        return std::nullopt;
    }
    if (used != text.size() || bounce < 0 || bounce > 1024) return std::nullopt;
    return bounce;
}

}  // namespace

RouletteSetting parse_russian_roulette(const std::string& text) {
    RouletteSetting s;
    if (text == "auto") return s;
    s.light_by_pilot = false;
    auto bounce_or_off = [&](const std::string& part) {
        const std::optional<int> bounce = parse_bounce_or_off(part);
        if (!bounce)
            throw Error("expected auto, off, a bounce from 0 to 1024 or two of them (camera,light; each a "
                        "bounce or off), not '" + text + "'");
        return *bounce;
    };
    const size_t comma = text.find(',');
    if (comma == std::string::npos) {
        s.camera_from = s.light_from = bounce_or_off(text);
    } else {
        s.camera_from = bounce_or_off(text.substr(0, comma));
        s.light_from = bounce_or_off(text.substr(comma + 1));
    }
    return s;
}

EnvironmentSampling environment_sampling_for(Integrator integrator) {
    return integrator == Integrator::Lt ? EnvironmentSampling::Luminance : EnvironmentSampling::Compensated;
}

Integrator parse_integrator(const std::string& name) {
    if (name == "bdpt") return Integrator::Bdpt;
    if (name == "pt") return Integrator::Pt;
    if (name == "lt") return Integrator::Lt;
    throw Error("unknown integrator '" + name + "' (expected bdpt, pt or lt)");
}

const char* sampler_name(SamplerKind sampler) {
    switch (sampler) {
    case SamplerKind::Sobol: return "sobol";
    case SamplerKind::ZSobol: return "zsobol";
    default: return "independent";
    }
}

SamplerKind parse_sampler(const std::string& name) {
    if (name == "independent") return SamplerKind::Independent;
    if (name == "sobol") return SamplerKind::Sobol;
    if (name == "zsobol") return SamplerKind::ZSobol;
    throw Error("unknown sampler '" + name + "' (expected sobol, zsobol or independent)");
}

const char* light_sampling_name(LightSampling sampling) {
    switch (sampling) {
    case LightSampling::Every: return "every";
    case LightSampling::One: return "one";
    default: return "auto";
    }
}

LightSampling parse_light_sampling(const std::string& name) {
    if (name == "auto") return LightSampling::Auto;
    if (name == "every") return LightSampling::Every;
    if (name == "one") return LightSampling::One;
    throw Error("unknown light sampling '" + name + "' (expected auto, every or one)");
}

namespace {

// The light groups of NEE_EVERY_LIGHT: 1 for all the area lights, 1 for each other light.
int light_group_count(const DeviceScene& scene) {
    const int area = scene.info.area_light_count;
    return int(scene.lights.size()) - area + (area > 0 ? 1 : 0);
}

}  // namespace

std::vector<std::string> kernel_defines(const DeviceScene& scene, Integrator integrator, int max_depth,
                                        bool all_features, SamplerKind sampler, LightSampling light_sampling) {
    bool area = false, point = false, spot = false, directional = false, environment = false;
    for (const Light& l : scene.lights) {
        area |= l.kind == LIGHT_AREA;
        point |= l.kind == LIGHT_POINT;
        spot |= l.kind == LIGHT_SPOT;
        directional |= l.kind == LIGHT_DIRECTIONAL;
        environment |= l.kind == LIGHT_ENVIRONMENT;
    }
    bool glossy = false, mirror = false, glass = false, interfaces = false;
    bool media = !scene.media.empty();
    for (const Material& m : scene.materials) {
        glossy |= m.kind == MATERIAL_GLOSSY;
        mirror |= m.kind == MATERIAL_MIRROR;
        glass |= m.kind == MATERIAL_GLASS;
        interfaces |= m.kind == MATERIAL_INTERFACE;
    }
    media |= interfaces;
    bool textures = !scene.textures.empty();
    bool cutouts = false, bump_maps = false, emission_textures = false;
    for (const Material& m : scene.materials) {
        cutouts |= textures && m.cutout_texture != 0;
        bump_maps |= textures && m.bump_texture != 0;
        emission_textures |= textures && m.ke_texture != 0;
    }
    bool shading_normals = !scene.normals.empty() || bump_maps;
    bool thin_lens = scene.camera.lens_radius > 0;
    bool env_map = scene.info.env_width > 0;

    std::vector<std::string> d;
    d.push_back("MAX_DEPTH=" + std::to_string(max_depth));
    d.push_back("INTEGRATOR=" + std::to_string(int(integrator)));
    if (sampler == SamplerKind::Sobol) d.push_back("SAMPLER_SOBOL");
    if (sampler == SamplerKind::ZSobol) d.push_back("SAMPLER_ZSOBOL");
    auto flag = [&](bool on, const char* name) {
        if (on || all_features) d.push_back(name);
    };
    flag(area, "HAS_AREA_LIGHTS");
    flag(point, "HAS_POINT_LIGHTS");
    flag(spot, "HAS_SPOT_LIGHTS");
    flag(directional, "HAS_DIRECTIONAL_LIGHTS");
    flag(environment, "HAS_ENVIRONMENT");
    // How light samples choose their lights (cl/lights.h): from the scene alone, so an
    // all-features build renders the scene's own image. With a few light groups, a sample of
    // each (pt's efficiency at 64 spp, medians of 3: 2.3x on point-spot, 1.55x with a point light
    // in the Cornell box, 10x with 8 lights); but not in media, where the medium's own noise
    // dominates and every medium vertex takes the samples (fog-spot 0.93x; with 4 lights,
    // 0.95-1.10x). Else, with a few lights among them spots, one sample that skips the spots
    // whose cone does not reach the point (a loop over the lights per sample).
    const int groups = light_group_count(scene);
    const bool every_light = light_sampling == LightSampling::Auto
                                 ? !media && groups >= 2 && groups <= kEveryLightMaxGroups
                                 : light_sampling == LightSampling::Every && groups >= 1;
    if (every_light) d.push_back("NEE_EVERY_LIGHT");
    else if (spot && scene.lights.size() <= kConeAwareMaxLights) d.push_back("NEE_CONE_AWARE");
    if (scene.lights.size() >= kLightCdfGuideMinLights) d.push_back("LIGHT_CDF_GUIDE");
    // The map's code reads buffers that exist only with a map; "all features" keeps it off
    // unless the scene has one.
    if (env_map) d.push_back("HAS_ENVIRONMENT_MAP");
    flag(glossy, "HAS_GLOSSY");
    flag(mirror, "HAS_MIRROR");
    flag(glass, "HAS_GLASS");
    flag(shading_normals, "HAS_SHADING_NORMALS");
    // Texture code reads buffers that exist only with textures: like the environment map, it
    // stays off in "all features" builds of scenes without them.
    if (textures) d.push_back("HAS_TEXTURES");
    if (cutouts) d.push_back("HAS_CUTOUTS");
    if (bump_maps) d.push_back("HAS_BUMP_MAPS");
    if (emission_textures) d.push_back("HAS_EMISSION_TEXTURES");
    flag(thin_lens, "HAS_THIN_LENS");
    // Media change the sample draws' table (cl/sample_dimensions.h): off in "all features"
    // builds too, so their images stay those of the scene's own build.
    if (media) d.push_back("HAS_MEDIA");
    bool grids = false;
    for (const Medium& m : scene.media) grids |= m.grid_offset >= 0;
    if (grids) d.push_back("HAS_MEDIUM_GRIDS");
    // Without index-matched boundaries, any surface between a connection's ends blocks it: an
    // any-hit query answers that, where a boundary needs the closest hit to be crossed.
    if (interfaces) d.push_back("HAS_MEDIUM_INTERFACES");
    return d;
}

}  // namespace clbdpt
