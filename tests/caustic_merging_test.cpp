// Caustic merging (cl/caustic_merging.h, render/caustic_photons.h) beyond its estimate, which
// scene_agreement_test.cpp checks: where it applies, that its photons keep an image independent
// of how the passes are launched, and that it changes nothing where a scene has no such paths.
#include <gtest/gtest.h>

#include <filesystem>

#include "test_scenes.h"

namespace clbdpt::test {
namespace {

constexpr int kFilm = 40;
constexpr int kMaxDepth = 5;

RenderOptions merging_options(uint32_t seed) {
    RenderOptions o = make_options(Integrator::Bdpt, kMaxDepth, seed, SamplerKind::Sobol);
    o.light_subpaths = 0.5f;
    o.caustic_merging = true;
    o.spp = 4;
    return o;
}

std::vector<float> render_image(const DeviceScene& scene, const RenderOptions& options, int passes) {
    Renderer renderer(test_device(), scene, options);
    Film film(scene.camera.width, scene.camera.height);
    renderer.render_passes(film, 0, passes);
    return film.image();
}

// A pass's photons depend on the seed and the pass alone: launches of 100 items, or one pass at
// a time, give the image of whole-pass launches bit for bit.
TEST(CausticMerging, ImageDoesNotDependOnLaunches) {
    const std::string path = scene_path("cornell-specular");
    if (!std::filesystem::exists(path)) GTEST_SKIP() << path << " does not exist";
    const DeviceScene scene = build_device_scene(load_scene(path), kFilm, kFilm);
    const RenderOptions whole = merging_options(11);
    const std::vector<float> reference = render_image(scene, whole, 4);
    RenderOptions small = whole;
    small.batch_items = 100;
    EXPECT_EQ(render_image(scene, small, 4), reference) << "launches of 100 items";
    Renderer renderer(test_device(), scene, whole);
    Film film(kFilm, kFilm);
    for (uint32_t pass = 0; pass < 4; ++pass) renderer.render_passes(film, pass, 1);
    EXPECT_EQ(film.image(), reference) << "one pass at a time";
    // ... and the photons do change it: the same render without them differs.
    RenderOptions plain = whole;
    plain.caustic_merging = false;
    EXPECT_NE(render_image(scene, plain, 4), reference);
}

// The Cornell box has no mirror or glass: no paths to merge, no photons, the same image.
TEST(CausticMerging, NothingChangesWithoutSpecularSurfaces) {
    const std::string path = scene_path("cornell-box");
    if (!std::filesystem::exists(path)) GTEST_SKIP() << path << " does not exist";
    const DeviceScene scene = build_device_scene(load_scene(path), kFilm, kFilm);
    EXPECT_FALSE(scene_has_merged_caustics(scene));
    const RenderOptions merging = merging_options(12);
    EXPECT_EQ(Renderer(test_device(), scene, merging).caustic_photons(), nullptr);
    RenderOptions plain = merging;
    plain.caustic_merging = false;
    EXPECT_EQ(render_image(scene, merging, 2), render_image(scene, plain, 2));
}

// A glass material that no triangle uses (exporters' MTL files often define such) is no reason
// for photons: there is nothing to aim them at.
TEST(CausticMerging, NothingToMergeWithAnUnusedGlassMaterial) {
    const std::string path = scene_path("cornell-box");
    if (!std::filesystem::exists(path)) GTEST_SKIP() << path << " does not exist";
    Scene loaded = load_scene(path);
    add_scene_material(loaded, glass_material(1.5f), "unused_glass");
    const DeviceScene scene = build_device_scene(loaded, kFilm, kFilm);
    EXPECT_FALSE(scene_has_merged_caustics(scene));
    EXPECT_EQ(Renderer(test_device(), scene, merging_options(15)).caustic_photons(), nullptr);
}

// Strategy images record each (s, t) apart, and the photons are none of them: merging stays off.
TEST(CausticMerging, OffWithStrategyImages) {
    const std::string path = scene_path("cornell-specular");
    if (!std::filesystem::exists(path)) GTEST_SKIP() << path << " does not exist";
    const DeviceScene scene = build_device_scene(load_scene(path), kFilm, kFilm);
    RenderOptions o = merging_options(13);
    o.strategy_images = RenderOptions::StrategyImages::Weighted;
    EXPECT_EQ(Renderer(test_device(), scene, o).caustic_photons(), nullptr);
}

}  // namespace
}  // namespace clbdpt::test
