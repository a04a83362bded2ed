// The per-scene kernel specialisation: which -D flags the render program is built with, so a
// feature the scene does not use costs no code, registers or branches (issue "Speed against
// error", section 3). The flags are part of the program cache key (host/device/opencl.cpp).
#pragma once

#include <string>
#include <vector>

#include "render/device_scene.h"

namespace clbdpt {

enum class Integrator { Bdpt = 0, Pt = 1, Lt = 2 };

const char* integrator_name(Integrator integrator);
Integrator parse_integrator(const std::string& name);  // throws Error

// The environment map's sampling an integrator renders with (render/device_scene.h): by
// luminance for the light tracer alone, which has no BSDF-sampled strategy; else compensated.
EnvironmentSampling environment_sampling_for(Integrator integrator);

// Russian roulette (cl/russian_roulette.h): the bounce of a subpath from which it may end it.
constexpr int kRouletteOff = RUSSIAN_ROULETTE_OFF;
// Camera subpaths by default: after 3 bounces, pbrt-v3's path tracer's rule. On the bundled
// scenes pt's efficiency rose 1.01-1.12x by it (README "Russian roulette"); from bounce 1 or 2 it
// fell to 0.56-0.9x on point-spot and the Cornell box, whose second and third bounces carry much
// of the light.
constexpr int kRouletteCameraFrom = 4;
// Light subpaths: the strategy pilot tries its chosen bdpt mix with roulette from this bounce
// (render/strategy_pilot.h); else light subpaths have none.
constexpr int kRouletteLightFromPilot = 2;

// "off", or the first bounce, as the summary and --stats say it.
std::string roulette_name(int from_bounce);
// --russian-roulette: auto (camera subpaths from kRouletteCameraFrom, light subpaths as the
// pilot finds), off, N (both kinds from bounce N), or C,L (camera subpaths from C, light
// subpaths from L, each a bounce or off: what a pilot's candidate with light roulette renders,
// forced, is "4,2"). Throws Error naming the text otherwise.
struct RouletteSetting {
    int camera_from = kRouletteCameraFrom;
    int light_from = kRouletteOff;
    bool light_by_pilot = true;
};
RouletteSetting parse_russian_roulette(const std::string& text);

enum class SamplerKind { Independent = 0, Sobol = 1, ZSobol = 2 };

const char* sampler_name(SamplerKind sampler);
SamplerKind parse_sampler(const std::string& name);  // throws Error

// Scenes with spot lights and at most this many lights take their light samples with spot
// cones in view (NEE_CONE_AWARE, cl/lights.h); each such sample loops over every light.
constexpr size_t kConeAwareMaxLights = NEE_CONE_AWARE_MAX_LIGHTS;

// Scenes without media with 2 to this many light groups (the area lights together, every other
// light alone) take a light sample of each group at every vertex (NEE_EVERY_LIGHT,
// cl/lights.h): one shadow ray per group.
constexpr int kEveryLightMaxGroups = 8;

// Scenes with more lights than this search the light CDF through its guide (LIGHT_CDF_GUIDE,
// find_interval_guided in cl/sampling.h); with fewer, a step or two of the plain search costs
// less than the guide's code (1% more instructions on point-spot's pt, whose area group is
// empty, and on the Cornell box's).
constexpr size_t kLightCdfGuideMinLights = 17;

// How light samples (s = 1) choose their lights (cl/lights.h): auto by the rule of
// kernel_defines, a sample of every light group (NEE_EVERY_LIGHT), or one light per sample.
enum class LightSampling { Auto = 0, Every = 1, One = 2 };

const char* light_sampling_name(LightSampling sampling);
LightSampling parse_light_sampling(const std::string& name);  // throws Error

// all_features: every HAS_* flag on (the unspecialised build, for benchmarks and tests).
std::vector<std::string> kernel_defines(const DeviceScene& scene, Integrator integrator, int max_depth,
                                        bool all_features = false, SamplerKind sampler = SamplerKind::Independent,
                                        LightSampling light_sampling = LightSampling::Auto);

}  // namespace clbdpt
