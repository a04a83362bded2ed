// White furnace: a closed sphere seen from its centre, every triangle a Lambertian reflector
// of albedo a that also emits Le from its inside face. The radiance field inside is uniform, so
// a path of k bounces carries Le a^k in every direction, and with at most d scattering
// vertices every pixel is exactly
//     L = Le * sum_{k=0..d} a^k
// whatever the strategies: a check of the absolute scale of every (s, t) strategy, of MIS
// weights summing to one, and of the light tracer's splat normalisation (lt at d = 0 sees the
// emitters only through its (1,1) strategy).
#include <gtest/gtest.h>

#include <cmath>
#include <tuple>

#include "test_scenes.h"

namespace clbdpt::test {
namespace {

const Vec3 kLe{0.8f, 1.0f, 0.6f};
const Vec3 kAlbedo{0.5f, 0.7f, 0.3f};  // per channel, so a channel mix-up shows
constexpr int kFilm = 16;
constexpr int kBlocks = 4;
constexpr int kPasses = 48;

// Tolerance: 16 regions and the image mean per render, 15 renders, so about 250 comparisons.
// At 4.5 standard errors a correct renderer fails one with probability ~250 * 6.8e-6 = 1.7e-3
// under a normal model (the seeds are fixed, so a pass stays a pass). With 48 passes the
// standard error is itself estimated from 47 degrees of freedom; Student's t puts the same
// 4.5 at about 5e-5 per comparison, ~1% for the whole set, still rare. A real error of the
// scale of one strategy (a factor pi, a missing cosine) is tens to hundreds of standard errors.
// pt at d = 0 is deterministic (every camera ray hits an emitter); the 1e-5 relative floor in
// expect_matches covers float rounding there.
constexpr double kSigmas = 4.5;

Scene furnace_scene() {
    SceneBuilder b;
    int m = b.material(diffuse_material(kAlbedo, kLe), "furnace");
    b.sphere({0, 0, 0}, 1.0f, 2, /*inward=*/true, m);  // 320 triangles
    b.camera({0, 0, 0}, {0.2f, 0.1f, 1}, 90.0f);
    b.scene.width = b.scene.height = kFilm;
    return b.scene;
}

double furnace_value(int max_depth) {
    double sum = 0;
    for (int c = 0; c < 3; ++c) {
        double a = kAlbedo[c], ak = 1, s = 0;
        for (int k = 0; k <= max_depth; ++k, ak *= a) s += ak;
        sum += kLe[c] * s;
    }
    return sum / 3.0;  // render_region_stats averages the channels
}

struct FurnaceCase {
    Integrator integrator;
    SamplerKind sampler;
    int max_depth;
};

class FurnaceTest : public ::testing::TestWithParam<FurnaceCase> {};

TEST_P(FurnaceTest, EveryPixelIsTheGeometricSeries) {
    const FurnaceCase c = GetParam();
    static const DeviceScene scene = build_device_scene(furnace_scene(), kFilm, kFilm);
    RenderOptions options = make_options(c.integrator, c.max_depth, 11 + uint32_t(c.max_depth), c.sampler);
    options.spp = scaled_passes(kPasses);  // ZSobol orders this many samples per pixel
    const std::string what = options_name(options);
    // The Sobol samplers' passes are stratified, not independent: the spread of per-pass
    // values overestimates the standard error of their mean, so its comparison is conservative.
    RegionStats st = render_stats_or_fail(scene, options, scaled_passes(kPasses), kBlocks, what);
    const double expected = furnace_value(c.max_depth);
    expect_matches(st, expected, kSigmas, what + " vs analytic");
    // Sanity of the statistics themselves: the estimate is not trivially zero or wild.
    EXPECT_GT(st.image_mean, 0.5 * expected) << what;
}

std::vector<FurnaceCase> furnace_cases() {
    std::vector<FurnaceCase> cases;
    for (int d : {0, 1, 3}) {
        cases.push_back({Integrator::Bdpt, SamplerKind::Independent, d});
        cases.push_back({Integrator::Pt, SamplerKind::Independent, d});
        cases.push_back({Integrator::Lt, SamplerKind::Independent, d});
        cases.push_back({Integrator::Bdpt, SamplerKind::Sobol, d});
    }
    cases.push_back({Integrator::Bdpt, SamplerKind::ZSobol, 3});
    cases.push_back({Integrator::Pt, SamplerKind::ZSobol, 3});
    return cases;
}

INSTANTIATE_TEST_SUITE_P(Integrators, FurnaceTest, ::testing::ValuesIn(furnace_cases()),
                         [](const ::testing::TestParamInfo<FurnaceCase>& info) {
                             std::string n = integrator_name(info.param.integrator);
                             if (info.param.sampler != SamplerKind::Independent)
                                 n += std::string("_") + sampler_name(info.param.sampler);
                             return n + "_depth" + std::to_string(info.param.max_depth);
                         });

// The same furnace as a box (flat walls meeting at edges and corners, where ray offsets and
// watertightness are tested) at max depth 3 (the sphere's kernels), every integrator.
class BoxFurnaceTest : public ::testing::TestWithParam<Integrator> {};

TEST_P(BoxFurnaceTest, EveryPixelIsTheGeometricSeries) {
    SceneBuilder b;
    int m = b.material(diffuse_material(kAlbedo, kLe), "furnace");
    b.box({-1, -0.7f, -1.3f}, {1, 0.7f, 1.3f}, /*inward=*/true, m);
    b.camera({0.3f, 0.2f, -0.9f}, {-0.4f, -0.3f, 1}, 100.0f);
    static const DeviceScene scene = build_device_scene(b.scene, kFilm, kFilm);
    RenderOptions options = make_options(GetParam(), 3, 21);
    const std::string what = std::string("box ") + options_name(options);
    RegionStats st = render_stats_or_fail(scene, options, scaled_passes(kPasses), kBlocks, what);
    expect_matches(st, furnace_value(3), kSigmas, what + " vs analytic");
}

INSTANTIATE_TEST_SUITE_P(Integrators, BoxFurnaceTest, ::testing::Values(Integrator::Bdpt, Integrator::Pt, Integrator::Lt),
                         [](const ::testing::TestParamInfo<Integrator>& info) {
                             return std::string(integrator_name(info.param));
                         });

}  // namespace
}  // namespace clbdpt::test
