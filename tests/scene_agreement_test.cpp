// bdpt, pt and lt estimate the same image of every bundled scene, region by region, within
// stated standard errors. Each integrator's MIS runs over exactly its own strategies, so each is
// unbiased on the paths it can reach; they are compared only where their reach is the same:
//   - lt (t = 1 only) cannot reach paths whose camera side starts with a specular vertex
//     (mirror, glass) nor an environment seen directly: no lt on cornell-specular and sky;
//   - point and spot lights are invisible to every strategy set, so lt is fine on point-spot;
//   - veach-mis: lt reaches every path in principle, but the reflections of its small lights
//     in the sharpest plates (GGX alpha 0.0016) are found by a light subpath only when it lands
//     where the camera sees the mirror image, so lt's per-pass values there are extremely
//     heavy-tailed: measured on a 40x40 film, one region is 0.011 +- 0.0003 (64 passes),
//     0.14 +- 0.12 (1024), 0.030 +- 0.006 (8192) against bdpt's 0.055 +- 0.002. Its standard
//     error is not a usable tolerance at any affordable count, so lt is not compared there.
#include <gtest/gtest.h>

#include <filesystem>

#include "render/strategy_pilot.h"
#include "test_scenes.h"

namespace clbdpt::test {
namespace {

// Tolerance: 16 regions + the image mean, up to 5 pairs, 5 scenes: about 420 comparisons. At
// 4.5 standard errors a correct renderer fails one with probability ~420 * 6.8e-6 = 3e-3 under
// a normal model; the seeds are fixed, so a pass stays a pass. The standard errors come from
// the spread of independent one-sample-per-pixel passes over 12x12-pixel regions, so each
// per-pass region value is itself a mean of 144 samples and close to normal.
constexpr double kSigmas = 4.5;
constexpr int kFilm = 40;
constexpr int kPairedFilm = 96;
constexpr int kBlocks = 4;
// One depth for every scene, so scenes with the same features share compiled kernels (and
// cornell-box-like scenes share them with integrators_test).
constexpr int kMaxDepth = 5;

struct AgreementCase {
    const char* scene;
    bool lt;     // whether lt reaches every path bdpt and pt do
    int passes;  // per integrator at CLBDPT_TEST_SCALE = 1
};

class SceneAgreementTest : public ::testing::TestWithParam<AgreementCase> {};

TEST_P(SceneAgreementTest, IntegratorsAgree) {
    const AgreementCase c = GetParam();
    const std::string path = scene_path(c.scene);
    if (!std::filesystem::exists(path)) GTEST_SKIP() << path << " does not exist";
    Scene loaded = load_scene(path);
    DeviceScene scene = build_device_scene(loaded, kFilm, kFilm);
    const int passes = scaled_passes(c.passes);

    RegionStats bdpt = render_stats_or_fail(scene, make_options(Integrator::Bdpt, kMaxDepth, 101), passes, kBlocks, "bdpt");
    RegionStats pt = render_stats_or_fail(scene, make_options(Integrator::Pt, kMaxDepth, 202), passes, kBlocks, "pt");
    ASSERT_GT(bdpt.image_mean, 0.0) << c.scene << " renders black";
    expect_agree(bdpt, pt, kSigmas, "bdpt vs pt");
    // Efficiency-aware mixes (cl/strategies.h): fewer light subpaths, counted in the MIS, and
    // no inner connections are unbiased too.
    const std::pair<float, bool> mixes[] = {{0.25f, true}, {0.5f, false}};
    for (size_t m = 0; m < 2; ++m) {
        RenderOptions o = make_options(Integrator::Bdpt, kMaxDepth, 404 + uint32_t(m));
        o.light_subpaths = mixes[m].first;
        o.inner_connections = mixes[m].second;
        const std::string name = describe_strategy_mix(Integrator::Bdpt, o.light_subpaths, o.inner_connections);
        RegionStats mixed = render_stats_or_fail(scene, o, passes, kBlocks, name);
        expect_agree(mixed, pt, kSigmas, name + " vs pt");
    }
    if (c.lt) {
        RegionStats lt = render_stats_or_fail(scene, make_options(Integrator::Lt, kMaxDepth, 303), passes, kBlocks, "lt");
        expect_agree(bdpt, lt, kSigmas, "bdpt vs lt");
        expect_agree(pt, lt, kSigmas, "pt vs lt");
    }
}

// bdpt and pt sample an environment map by each texel's excess over the map's mean, never the
// texels at or below it (render/device_scene.h): unbiased only if every strategy that cannot
// sample such a direction gives way to BSDF sampling in the MIS weights. Checked against pt
// with the map sampled by luminance, where every direction has a light sample's density (an
// estimator of the same image that shares no light density with them), on sky, whose sun
// highlight and caustics are the heavy tails this is for; same regions and tolerance as above.
// A light tracer is refused such a map (it takes the one by luminance).
TEST(SceneAgreement, EnvironmentSampledByExcessAgreesWithLuminance) {
    const std::string path = scene_path("sky");
    if (!std::filesystem::exists(path)) GTEST_SKIP() << path << " does not exist";
    const Scene loaded = load_scene(path);
    const DeviceScene by_excess = build_device_scene(loaded, kFilm, kFilm, EnvironmentSampling::Compensated);
    const DeviceScene by_luminance = build_device_scene(loaded, kFilm, kFilm, EnvironmentSampling::Luminance);
    ASSERT_NE(by_excess.env_distribution, by_luminance.env_distribution);
    const int passes = scaled_passes(64);
    RegionStats reference =
        render_stats_or_fail(by_luminance, make_options(Integrator::Pt, kMaxDepth, 505), passes, kBlocks, "pt, luminance");
    RegionStats pt = render_stats_or_fail(by_excess, make_options(Integrator::Pt, kMaxDepth, 506), passes, kBlocks, "pt");
    RegionStats bdpt =
        render_stats_or_fail(by_excess, make_options(Integrator::Bdpt, kMaxDepth, 507), passes, kBlocks, "bdpt");
    expect_agree(pt, reference, kSigmas, "pt vs pt with the map sampled by luminance");
    expect_agree(bdpt, reference, kSigmas, "bdpt vs pt with the map sampled by luminance");
    // The light tracer has no strategy for the directions left to BSDF sampling: refused.
    EXPECT_THROW(Renderer(test_device(), by_excess, make_options(Integrator::Lt, kMaxDepth, 508)), Error);
}

// Russian roulette (cl/russian_roulette.h) keeps every integrator's expectation: with roulette
// from the first bounce of both subpaths, as often as it can fire, pt, bdpt (full and without
// inner connections) and lt agree with pt without roulette, on cornell-specular (glass, whose
// 1/eta^2 inside must not count as a throughput's loss, and depth 8) and lamp-ceiling (light
// that arrives by way of the ceiling). Same regions and tolerance as above. A roulette that did
// not divide the throughput by the probability of going on would make their regions
// 16-36% dark (measured with the division taken out).
TEST(SceneAgreement, RussianRouletteKeepsTheImage) {
    for (const char* name : {"cornell-specular", "lamp-ceiling"}) {
        const std::string path = scene_path(name);
        if (!std::filesystem::exists(path)) GTEST_SKIP() << path << " does not exist";
        const Scene loaded = load_scene(path);
        const DeviceScene scene = build_device_scene(loaded, kFilm, kFilm);
        const bool lt = std::string(name) == "lamp-ceiling";
        const int depth = lt ? kMaxDepth : 8;
        const int passes = scaled_passes(64);
        RenderOptions off = make_options(Integrator::Pt, depth, 601);
        off.roulette_camera_from = off.roulette_light_from = kRouletteOff;
        RegionStats reference = render_stats_or_fail(scene, off, passes, kBlocks, "pt without roulette");
        auto with_roulette = [&](Integrator integrator, bool inner_connections, uint32_t seed) {
            RenderOptions o = make_options(integrator, depth, seed);
            o.roulette_camera_from = o.roulette_light_from = 0;
            o.inner_connections = inner_connections;
            return o;
        };
        std::vector<std::pair<std::string, RenderOptions>> cases = {
            {"pt", with_roulette(Integrator::Pt, true, 602)},
            {"bdpt", with_roulette(Integrator::Bdpt, true, 603)},
            {"bdpt without inner connections", with_roulette(Integrator::Bdpt, false, 604)}};
        if (lt) cases.push_back({"lt", with_roulette(Integrator::Lt, true, 605)});
        for (const auto& [what, options] : cases) {
            const std::string label = std::string(name) + ": " + what + " with roulette from bounce 0";
            RegionStats rendered = render_stats_or_fail(scene, options, passes, kBlocks, label);
            expect_agree(rendered, reference, kSigmas, label + " vs pt without roulette");
        }
    }
}

// Caustic merging (cl/caustic_merging.h) takes the caustics seen through the glass ball and in
// the mirror ball from s = 0 and estimates them from photons: the paths are split between the
// two, so the image must stay the same. Two checks, each pass with photons of its own
// (spp = passes), so that passes stay independent and their spread gives the standard error:
//   - paired with the same mix without merging, same seed: every other strategy draws the same
//     numbers, so the difference is the photons' estimate less s = 0's of the same paths, 0 in
//     expectation, with a standard error far below the image's (on a 96 x 96 film). Measured:
//     s = 0 left in as well (those paths counted twice) or the photons' estimate left out make
//     the image mean differ by 21 and 7.0 standard errors (+0.30% and -0.29% of it);
//   - against pt, like the mixes above (the blur of the merge moves little energy across the
//     10 x 10-pixel regions).
void expect_caustic_merging_keeps_the_image(const Scene& loaded, const std::string& name, int passes_at_scale_1,
                                            uint32_t seed) {
    const DeviceScene scene = build_device_scene(loaded, kFilm, kFilm);
    // The paired check on 6x the pixels: the difference's noise is s = 0's on the merged paths.
    const DeviceScene larger = build_device_scene(loaded, kPairedFilm, kPairedFilm);
    ASSERT_TRUE(scene_has_merged_caustics(scene));
    const int passes = scaled_passes(passes_at_scale_1);
    RenderOptions plain = make_options(Integrator::Bdpt, kMaxDepth, seed);
    plain.light_subpaths = 0.5f;
    plain.spp = passes;
    RenderOptions merged = plain;
    merged.caustic_merging = true;
    // Half the default radius: the blur's bias (0.05% of a region at the default, 4.6 standard
    // errors at 288 passes once the photons were aimed) stays well inside the tolerance.
    merged.merge_radius = 0.5;
    {
        Renderer renderer(test_device(), scene, merged);
        ASSERT_NE(renderer.caustic_photons(), nullptr);
        Film film(kFilm, kFilm);
        renderer.render_passes(film, 0, 1);
        EXPECT_GT(renderer.caustic_photons()->photons(), 0u) << "no caustic photons on " << name;
    }
    const std::string what = name + ": bdpt with caustic merging";
    const PairedStats paired = render_paired(larger, merged, larger, plain, passes, kBlocks);
    expect_same_paired(paired, kSigmas, what + " vs without, paired");
    RegionStats pt = render_stats_or_fail(scene, make_options(Integrator::Pt, kMaxDepth, seed + 1), passes, kBlocks, "pt");
    RegionStats bdpt = render_stats_or_fail(scene, merged, passes, kBlocks, what);
    expect_agree(bdpt, pt, kSigmas, what + " vs pt");
}

void expect_caustic_merging_keeps_the_image(const char* name, int passes_at_scale_1, uint32_t seed) {
    const std::string path = scene_path(name);
    if (!std::filesystem::exists(path)) GTEST_SKIP() << path << " does not exist";
    expect_caustic_merging_keeps_the_image(load_scene(path), name, passes_at_scale_1, seed);
}

TEST(SceneAgreement, CausticMergingKeepsTheImage) { expect_caustic_merging_keeps_the_image("cornell-specular", 96, 701); }

// The same in fog (cornell-fog): a medium vertex counts as non-specular on both sides of the
// split, so paths that scatter in the fog stay with the strategies that sample them, and the
// photons' and the camera subpaths' throughputs carry the fog's transmittance. s = 0 is noisier
// through fog, hence 2x the passes: measured at 192 passes, the paths counted twice fail the
// paired check at 16 standard errors and the photons' estimate left out at 5.4 (2.6 at 64).
TEST(SceneAgreement, CausticMergingKeepsTheImageInFog) { expect_caustic_merging_keeps_the_image("cornell-fog", 192, 711); }

// The same under an environment map (sky, with a glass ball added in front of its spheres): the
// environment's photons start on the disk of the sphere about the glass, and s = 0 leaves out the
// camera subpaths that escape to the map after the merged paths' specular chain.
TEST(SceneAgreement, CausticMergingKeepsTheImageUnderAnEnvironment) {
    const std::string path = scene_path("sky");
    if (!std::filesystem::exists(path)) GTEST_SKIP() << path << " does not exist";
    SceneBuilder b;
    b.scene = load_scene(path);
    b.sphere({0.0f, 0.45f, -0.8f}, 0.45f, 3, false, b.material(glass_material(1.5f), "glass"));
    expect_caustic_merging_keeps_the_image(b.scene, "sky with a glass ball", 96, 721);
}

// A delta light's caustic seen in a mirror: light that leaves a point or directional light by
// way of a mirror, lights a diffuse floor and reaches the camera by way of the mirror again. No
// strategy samples such a path (each neighbour of the floor vertex is specular, and no ray can
// hit the light), so bdpt and pt render it black and caustic merging alone renders it
// (cl/caustic_merging.h). A plane mirror gives the exact image: the floor seen in the mirror
// x = 0 from eye E, lit by light L directly and by way of the mirror, is the floor seen from E's
// mirror image, lit by L and by L's mirror image with the mirror's reflectance times L's
// intensity (radiance), with no mirror at all; that image, flipped left to right and times the
// reflectance (the camera's own reflection in the mirror), is rendered by pt. At depth 3 with
// the mirror (E M D L and E M D M L; longer paths would need the mirror image of the floor)
// against any depth without it (E D L and E D L', the floor being the only surface), the paths
// correspond one to one. The camera sees the mirror alone, and through it the floor alone, 1.3
// to 5.9 from the mirror; the mirror is tall enough that the directional light's reflection
// covers the whole floor. Merged with 4x the default radius: the blur's bias on a light this
// smooth stays below 1% of a region (a point light's irradiance varies on a scale of 2 units,
// the radius is 0.17; a directional light's is uniform), and the photons' noise 4x smaller than
// at the default. Same regions and tolerance as above.
TEST(SceneAgreement, DeltaLightCausticSeenInAMirror) {
    const float reflectance = 0.8f;
    const auto floor_quad = [](SceneBuilder& b) {
        const int white = b.material(diffuse_material({0.7f, 0.7f, 0.7f}), "floor");
        b.quad({0, 0, 4}, {8, 0, 4}, {8, 0, -4}, {0, 0, -4}, white);
    };
    LightDesc directional;
    directional.kind = LightDesc::Kind::Directional;
    directional.direction = normalize(Vec3{-1.0f, -1.2f, 0.3f});
    directional.color = {2.0f, 2.0f, 2.0f};
    const LightDesc lights[] = {point_light({0.5f, 2.0f, 0.0f}, {6.0f, 6.0f, 6.0f}), directional};
    const int passes = scaled_passes(96);
    uint32_t seed = 801;
    for (const LightDesc& light : lights) {
        const std::string what = light.kind == LightDesc::Kind::Point ? "point light" : "directional light";
        SceneBuilder with_mirror;
        floor_quad(with_mirror);
        const int mirror = with_mirror.material(mirror_material({reflectance, reflectance, reflectance}), "mirror");
        with_mirror.quad({0, 0, -4}, {0, 8, -4}, {0, 8, 4}, {0, 0, 4}, mirror);
        with_mirror.camera({1, 4, 0}, {0, 3, 0}, 30.0f);
        with_mirror.scene.lights = {light};
        // The light's mirror image: position and direction reflected in x = 0.
        LightDesc image = light;
        image.position.x = -light.position.x;
        image.direction.x = -light.direction.x;
        image.color = light.color * reflectance;
        SceneBuilder mirrored;
        floor_quad(mirrored);
        mirrored.camera({-1, 4, 0}, {0, 3, 0}, 30.0f);
        mirrored.scene.lights = {light, image};
        const DeviceScene scene = build_device_scene(with_mirror.scene, kFilm, kFilm);
        const DeviceScene reference_scene = build_device_scene(mirrored.scene, kFilm, kFilm);
        ASSERT_TRUE(scene_has_merged_caustics(scene)) << what;

        const RegionStats reference = render_stats_or_fail(reference_scene, make_options(Integrator::Pt, kMaxDepth, seed++),
                                                           passes, kBlocks, what + ": pt without the mirror");
        // Left to right: region (row, column) of one image is (row, blocks - 1 - column) of the other.
        RegionStats expected = reference;
        for (int row = 0; row < kBlocks; ++row)
            for (int column = 0; column < kBlocks; ++column) {
                const size_t to = size_t(row * kBlocks + column), from = size_t(row * kBlocks + kBlocks - 1 - column);
                expected.mean[to] = reflectance * reference.mean[from];
                expected.std_error[to] = reflectance * reference.std_error[from];
            }
        expected.image_mean *= reflectance;
        expected.image_std_error *= reflectance;

        RenderOptions merged = make_options(Integrator::Bdpt, 3, seed++);
        merged.spp = passes;
        merged.caustic_merging = true;
        merged.merge_radius = 4.0;
        const RegionStats bdpt = render_stats_or_fail(scene, merged, passes, kBlocks, what + ": bdpt with caustic merging");
        expect_agree(bdpt, expected, kSigmas, what + "'s caustic in a mirror: bdpt with merging vs the mirror image");

        // Without merging the caustic is missing: the image mean fails by far (measured: the point
        // light's 0.71x the exact one, 5 000 standard errors off).
        RenderOptions plain = merged;
        plain.caustic_merging = false;
        plain.seed = seed++;
        const RegionStats black = render_stats_or_fail(scene, plain, passes, kBlocks, what + ": bdpt without merging");
        const double z = (expected.image_mean - black.image_mean) /
                         std::sqrt(expected.image_std_error * expected.image_std_error +
                                   black.image_std_error * black.image_std_error);
        EXPECT_GT(z, 4 * kSigmas) << what << " without merging: " << black.image_mean << " +- "
                                  << black.image_std_error << " against " << expected.image_mean << " +- "
                                  << expected.image_std_error;
    }
}

INSTANTIATE_TEST_SUITE_P(Bundled, SceneAgreementTest,
                         ::testing::Values(AgreementCase{"cornell-specular", false, 96},
                                           AgreementCase{"lamp-ceiling", true, 64},
                                           AgreementCase{"veach-mis", false, 64},
                                           AgreementCase{"point-spot", true, 64},
                                           AgreementCase{"sky", false, 64}),
                         [](const ::testing::TestParamInfo<AgreementCase>& info) {
                             std::string n = info.param.scene;
                             for (char& ch : n)
                                 if (ch == '-') ch = '_';
                             return n;
                         });

}  // namespace
}  // namespace clbdpt::test
