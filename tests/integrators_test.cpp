// Whole-image tests of the BDPT kernels: bdpt, pt and lt estimate the same image (each with
// its own set of strategies and MIS over exactly that set), renders are deterministic however
// the work is batched, and nothing non-finite comes out.
#include <gtest/gtest.h>

#include <cmath>

#include "mpi/items_message.h"
#include "render/render_loop.h"
#include "render/work_units.h"
#include "render_test_util.h"

namespace clbdpt::test {
namespace {

// Two independent estimates agree if they differ by less than kSigmas combined standard errors.
// With 4x4 regions and two pairs that is 32 comparisons; at 4.5 sigma a correct renderer fails
// one with probability about 32 * 6.8e-6 = 2e-4 (and the seeds are fixed, so a pass stays a pass).
constexpr double kSigmas = 4.5;

void expect_agree(const RegionStats& a, const RegionStats& b, const char* what) {
    for (size_t r = 0; r < a.mean.size(); ++r) {
        double se = std::sqrt(a.std_error[r] * a.std_error[r] + b.std_error[r] * b.std_error[r]);
        EXPECT_LE(std::fabs(a.mean[r] - b.mean[r]), kSigmas * se)
            << what << " region " << r << ": " << a.mean[r] << " vs " << b.mean[r] << " (standard error " << se << ")";
    }
    double se = std::hypot(a.image_std_error, b.image_std_error);
    EXPECT_LE(std::fabs(a.image_mean - b.image_mean), kSigmas * se)
        << what << " image mean: " << a.image_mean << " vs " << b.image_mean << " (standard error " << se << ")";
}

DeviceScene small_scene(const std::string& name, int size) {
    Scene scene = load_scene(scene_path(name));
    return build_device_scene(scene, size, size);
}

// Renders the scene with one strategy set and sampler, each run with its own seed so that runs
// are independent of each other.
RegionStats render_with(const DeviceScene& scene, int max_depth, Integrator integrator, SamplerKind sampler,
                        uint32_t seed) {
    RenderOptions options;
    options.max_depth = max_depth;
    options.integrator = integrator;
    options.sampler = sampler;
    options.seed = seed;
    const int passes = 96;
    return render_region_stats(scene, options, passes, 4);
}

// bdpt against pt and lt (independent sampler), and optionally against bdpt with Sobol.
void expect_strategy_sets_agree(const DeviceScene& scene, int max_depth, uint32_t seed, bool with_sobol,
                                const std::string& what) {
    RegionStats bdpt = render_with(scene, max_depth, Integrator::Bdpt, SamplerKind::Independent, seed);
    RegionStats pt = render_with(scene, max_depth, Integrator::Pt, SamplerKind::Independent, seed + 1);
    RegionStats lt = render_with(scene, max_depth, Integrator::Lt, SamplerKind::Independent, seed + 2);
    ASSERT_GT(bdpt.image_mean, 0.01);
    expect_agree(bdpt, pt, (what + ": bdpt vs pt").c_str());
    expect_agree(bdpt, lt, (what + ": bdpt vs lt").c_str());
    if (with_sobol) {
        // The Sobol sampler's passes are stratified, not independent: the spread of per-pass
        // values overestimates the standard error of their mean, so this comparison is
        // conservative.
        RegionStats sobol = render_with(scene, max_depth, Integrator::Bdpt, SamplerKind::Sobol, seed + 3);
        expect_agree(bdpt, sobol, (what + ": bdpt vs bdpt with the Sobol sampler").c_str());
    }
}

TEST(Integrators, AgreeOnCornellBox) {
    expect_strategy_sets_agree(small_scene("cornell-box", 48), 5, 1, true, "cornell-box");
}

// A thin-lens camera: t = 1 strategies sample lens points (camera_sample_wi), camera subpaths
// start from them, and the importance includes 1 / lens area.
TEST(Integrators, AgreeWithThinLens) {
    Scene loaded = load_scene(scene_path("cornell-box"));
    loaded.camera.lens_radius = 25.0f;
    loaded.camera.focus_distance = 700.0f;
    expect_strategy_sets_agree(build_device_scene(loaded, 40, 40), 4, 11, false, "thin lens");
}

class BatchingTest : public ::testing::TestWithParam<SamplerKind> {};

TEST_P(BatchingTest, ImageDoesNotDependOnBatching) {
    DeviceScene scene = small_scene("cornell-box", 40);
    RenderOptions options;
    options.max_depth = 5;
    options.sampler = GetParam();
    Renderer whole(test_device(), scene, options);
    Film a(40, 40);
    whole.render_passes(a, 0, 2);
    options.batch_items = 333;    // does not divide the pixel count
    options.collect_threads = 3;  // each launch collected in three ranges, as on a GPU
    Renderer batched(test_device(), scene, options);
    Film b(40, 40);
    batched.render_passes(b, 0, 2);
    EXPECT_EQ(a.camera_sum, b.camera_sum);
    EXPECT_EQ(a.light_sum, b.light_sum);
    // Runs of several passes are rendered in one go (DeviceWorker), here a part of pass 0 and
    // then its rest with all of pass 1, in launches that straddle the passes' boundary.
    const WorkUnits units(40 * 40, 0, 512);
    DeviceWorker worker(batched);
    Film joined(40, 40);
    for (const auto& [begin, end] : {std::pair<int64_t, int64_t>{0, 2}, {2, 2 * units.units_per_pass}}) {
        const std::vector<ItemRun> runs = units.runs(begin, end);
        const std::vector<RenderedItems> results = worker.render(runs, {});
        EXPECT_EQ(results.size(), 1u);
        // What another process's device sends back this way is what the leader accepts.
        EXPECT_TRUE(results_match_runs(runs, results, 40 * 40));
        for (const RenderedItems& r : results) add_to_film(joined, r);
    }
    EXPECT_EQ(a.camera_sum, joined.camera_sum);
    EXPECT_EQ(a.light_sum, joined.light_sum);
    // Results handed back for reuse (render_loop.cpp) hold old values, in buffers larger and
    // smaller than a run needs: every item is written again, so the image is the same.
    RenderedItemsPool pool;
    for (size_t n : {size_t(10), size_t(40 * 40 * 5)}) {
        RenderedItems old;
        old.camera.assign(n * 3, std::nanf(""));
        old.rays.assign(n, -1.0f);
        old.dropped_items = {0, 1};
        old.splats.assign(n, SplatRecord{1.0f, 2.0f, 3.0f, 0});
        pool.give(std::move(old));
    }
    worker.set_result_pool(&pool);
    Film reused(40, 40);
    for (const auto& [begin, end] : {std::pair<int64_t, int64_t>{0, 2}, {2, 2 * units.units_per_pass}})
        for (const RenderedItems& r : worker.render(units.runs(begin, end), {})) add_to_film(reused, r);
    EXPECT_EQ(a.camera_sum, reused.camera_sum);
    EXPECT_EQ(a.light_sum, reused.light_sum);
    // And a different seed gives a different image.
    options.seed = 7;
    Renderer reseeded(test_device(), scene, options);
    Film c(40, 40);
    reseeded.render_passes(c, 0, 2);
    EXPECT_NE(a.camera_sum, c.camera_sum);
}

INSTANTIATE_TEST_SUITE_P(Samplers, BatchingTest, ::testing::Values(SamplerKind::Independent, SamplerKind::Sobol),
                         [](const ::testing::TestParamInfo<SamplerKind>& info) {
                             return std::string(sampler_name(info.param));
                         });

}  // namespace
}  // namespace clbdpt::test

namespace clbdpt::test {
namespace {

// 4 passes of bdpt over a 24 x 24 film, with weighted strategy images.
constexpr int kStrategyImagesMaxDepth = 3;
Film render_strategy_images(const DeviceScene& scene) {
    RenderOptions options;
    options.max_depth = kStrategyImagesMaxDepth;
    options.strategy_images = RenderOptions::StrategyImages::Weighted;
    Renderer renderer(test_device(), scene, options);
    Film film(24, 24);
    renderer.render_passes(film, 0, 4);
    return film;
}

// The strategy images split the image: their sum is the image (up to float rounding of the
// per-sample products). On point-spot a sample's s = 1 strategies take a light sample of each of
// its two lights (NEE_EVERY_LIGHT), which add into one record per (s, t).
TEST(Integrators, StrategyImagesSumToTheImage) {
    for (const char* name : {"cornell-box", "point-spot"}) {
        const Film film = render_strategy_images(build_device_scene(load_scene(scene_path(name)), 24, 24));
        std::vector<float> image = film.image();
        std::vector<double> sum(image.size(), 0.0);
        for (int depth = 0; depth <= kStrategyImagesMaxDepth; ++depth)
            for (int t = 1; t <= depth + 2; ++t) {
                std::vector<float> part = film.strategy_image(depth + 2 - t, t);
                for (size_t i = 0; i < sum.size(); ++i) sum[i] += part[i];
            }
        double total = 0;
        for (size_t i = 0; i < sum.size(); ++i) {
            EXPECT_NEAR(sum[i], image[i], 1e-5 * (1.0 + std::fabs(image[i]))) << name << ": channel value " << i;
            total += image[i];
        }
        EXPECT_GT(total, 0.0) << name;
    }
}

// bdpt joins a light point straight to the lens (strategy (1,1), cl/strategies.h) only with a
// thin lens or in a scene with media: through a pinhole in vacuum s = 0 sees an emitter without
// noise. The Cornell box's light is in view, so (1,1) carries light wherever it is on.
TEST(Integrators, LightToLensOnlyThroughALensOrInMedia) {
    struct Case {
        const char* scene;
        float lens_radius;
        bool light_to_lens;
    };
    for (const Case& c : {Case{"cornell-box", 0.0f, false}, Case{"cornell-box", 0.05f, true},
                          Case{"cornell-fog", 0.0f, true}}) {
        Scene loaded = load_scene(scene_path(c.scene));
        loaded.camera.lens_radius = c.lens_radius;
        const Film film = render_strategy_images(build_device_scene(loaded, 24, 24));
        double light_to_lens = 0;
        for (float v : film.strategy_image(1, 1)) light_to_lens += v;
        if (c.light_to_lens)
            EXPECT_GT(light_to_lens, 0.0) << c.scene << " lens radius " << c.lens_radius;
        else
            EXPECT_EQ(light_to_lens, 0.0) << c.scene << " lens radius " << c.lens_radius;
    }
}

}  // namespace
}  // namespace clbdpt::test
