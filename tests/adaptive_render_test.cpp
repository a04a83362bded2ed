// Adaptive sampling (render/adaptive.h) keeps the image unbiased: on the Cornell box, whose
// light's outline it refines, the mean over the refined pixels and the image mean of many
// adaptive renders match those of uniform passes within stated standard errors, for pt, for
// bdpt (whose extra samples leave their light-image splats out) and for bdpt whose extra samples
// are path-traced (whole pixel estimates, averaged with the light image). The adaptive renders use the
// independent sampler: a plan made from the pixel's own samples would bias it, and with
// independent samples that shows (planning from each pixel's own variance, tried, fails the pt
// comparisons at 5.2 and 5.3 standard errors), while Sobol's strata make the variance of an
// outline pixel nearly the same in every render and hide it.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <string>

#include "render/adaptive.h"
#include "test_scenes.h"

namespace clbdpt::test {
namespace {

// Two comparisons (the refined pixels, the image) per case, 3 cases: at 4.5 standard errors a
// correct renderer fails one with probability ~6 * 6.8e-6 under a normal
// model. The adaptive side's standard error is the spread of whole independent renders (each a
// mean of thousands of samples, close to normal); the uniform side's that of one-sample passes.
constexpr double kSigmas = 4.5;
constexpr int kSpp = 16;

struct MeanAndError {
    double mean = 0, std_error = 0;
};

MeanAndError summarise(const std::vector<double>& values) {
    const double n = double(values.size());
    double sum = 0, sum2 = 0;
    for (double v : values) sum += v, sum2 += v * v;
    MeanAndError m;
    m.mean = sum / n;
    m.std_error = std::sqrt(std::max(0.0, sum2 / n - m.mean * m.mean) / (n - 1));
    return m;
}

// The adaptive renders' mean against the uniform passes', within kSigmas combined standard errors.
void expect_same_means(const std::string& what, const MeanAndError& a, const MeanAndError& u) {
    const double se = std::sqrt(a.std_error * a.std_error + u.std_error * u.std_error);
    EXPECT_LE(std::fabs(a.mean - u.mean), kSigmas * se)
        << what << ": adaptive " << a.mean << " +- " << a.std_error << ", uniform " << u.mean << " +- "
        << u.std_error << " (" << std::fabs(a.mean - u.mean) / se << " SE)";
}

// Mean over the masked pixels' channels (all pixels with an empty mask).
double masked_mean(const std::vector<float>& img, const std::vector<uint8_t>& mask) {
    double sum = 0;
    size_t count = 0;
    for (size_t p = 0; p * 3 < img.size(); ++p)
        if (mask.empty() || mask[p]) {
            sum += double(img[p * 3]) + img[p * 3 + 1] + img[p * 3 + 2];
            count += 3;
        }
    return count ? sum / double(count) : 0.0;
}

// One adaptive render: kSpp passes that keep each pixel's variance, then the plan's extra samples.
Film adaptive_render(const DeviceScene& scene, const RenderOptions& options, AdaptivePlan* plan) {
    Renderer renderer(test_device(), scene, options);
    const int w = scene.camera.width, h = scene.camera.height;
    Film film(w, h);
    film.camera_sq.assign(size_t(w) * h, 0.0);
    renderer.render_passes(film, 0, kSpp);
    *plan = plan_adaptive_samples(film);
    render_adaptive_samples(renderer, *plan, film, nullptr);
    EXPECT_EQ(film.extra_samples_whole, options.integrator == Integrator::Pt);
    return film;
}

// film: bdpt's camera samples are noisy all over (its connections), so its plan refines the
// outline only on a larger film.
void check_unbiased(Integrator integrator, int film, int renders, int passes) {
    const DeviceScene scene = build_device_scene(load_scene(scene_path("cornell-box")), film, film);
    // The pixels to compare: those that renders of three other seeds refine (the light's
    // outline; one render of bdpt refines 10-40 pixels of a 64 x 64 film).
    std::vector<uint8_t> mask(size_t(film) * film, 0);
    for (uint32_t seed = 9000; seed < 9003; ++seed) {
        AdaptivePlan mask_plan;
        adaptive_render(scene, make_options(integrator, 5, seed, SamplerKind::Sobol), &mask_plan);
        for (size_t p = 0; p < mask.size(); ++p) mask[p] |= mask_plan.tier[p] > 0;
    }
    size_t refined = 0;
    for (uint8_t m : mask) refined += m;
    ASSERT_GT(refined, 5u) << "the light's outline is refined";
    ASSERT_LT(refined, mask.size() / 4);

    std::vector<double> adaptive_masked, adaptive_image;
    uint64_t extra = 0;
    for (int r = 0; r < renders; ++r) {
        AdaptivePlan plan;
        const Film film = adaptive_render(scene, make_options(integrator, 5, 100 + uint32_t(r), SamplerKind::Independent), &plan);
        extra += plan.extra_samples;
        const std::vector<float> img = film.image();
        adaptive_masked.push_back(masked_mean(img, mask));
        adaptive_image.push_back(masked_mean(img, {}));
    }
    EXPECT_GT(extra, 0u);

    std::vector<double> uniform_masked, uniform_image;
    Renderer uniform(test_device(), scene, make_options(integrator, 5, 7, SamplerKind::Independent));
    for (int pass = 0; pass < passes; ++pass) {
        Film pass_film(film, film);
        uniform.render_passes(pass_film, uint32_t(pass), 1);
        const std::vector<float> img = pass_film.image();
        uniform_masked.push_back(masked_mean(img, mask));
        uniform_image.push_back(masked_mean(img, {}));
    }
    const std::string name = integrator_name(integrator);
    expect_same_means(name + " refined pixels", summarise(adaptive_masked), summarise(uniform_masked));
    expect_same_means(name + " image", summarise(adaptive_image), summarise(uniform_image));
}

TEST(AdaptiveSampling, PathTracerStaysUnbiased) { check_unbiased(Integrator::Pt, 32, scaled_passes(48), scaled_passes(768)); }

TEST(AdaptiveSampling, BdptStaysUnbiased) { check_unbiased(Integrator::Bdpt, 64, scaled_passes(16), scaled_passes(256)); }

// bdpt's passes with path-traced extra samples (what the default does where the pilot found pt
// close to the chosen mix): each refined pixel is the mean of its passes' camera and light
// images and its path-traced samples. The plan is made by hand, kSpp extra samples for each
// pixel of the film's lower half (the floor and the boxes, where bdpt's light image carries
// much of the value: counted twice there, as a film that took the path-traced samples for
// camera images would, the half's mean came out 85 standard errors high), so its pixels
// are compared, and the image, against uniform bdpt passes.
TEST(AdaptiveSampling, BdptWithPathTracedExtraSamplesStaysUnbiased) {
    const int size = 32;
    const DeviceScene scene = build_device_scene(load_scene(scene_path("cornell-box")), size, size);
    std::vector<uint8_t> lower_half(size_t(size) * size, 0);
    for (size_t p = lower_half.size() / 2; p < lower_half.size(); ++p) lower_half[p] = 1;
    std::vector<double> adaptive_half, adaptive_image;
    for (int r = 0; r < scaled_passes(16); ++r) {
        const RenderOptions options = make_options(Integrator::Bdpt, 5, 300 + uint32_t(r), SamplerKind::Independent);
        RenderOptions pt_options = options;
        pt_options.integrator = Integrator::Pt;
        Renderer bdpt(test_device(), scene, options), pt(test_device(), scene, pt_options);
        Film film(size, size);
        bdpt.render_passes(film, 0, kSpp);
        AdaptivePlan plan;
        plan.spp = kSpp;
        plan.max_tier = 1;
        plan.tier = lower_half;
        plan.extra_samples = uint64_t(kSpp) * lower_half.size() / 2;
        plan.pixels_refined = lower_half.size() / 2;
        render_adaptive_samples(pt, plan, film, nullptr);
        ASSERT_TRUE(film.extra_samples_whole);
        const std::vector<float> img = film.image();
        adaptive_half.push_back(masked_mean(img, lower_half));
        adaptive_image.push_back(masked_mean(img, {}));
    }
    std::vector<double> uniform_half, uniform_image;
    Renderer uniform(test_device(), scene, make_options(Integrator::Bdpt, 5, 7, SamplerKind::Independent));
    for (int pass = 0; pass < scaled_passes(256); ++pass) {
        Film pass_film(size, size);
        uniform.render_passes(pass_film, uint32_t(pass), 1);
        const std::vector<float> img = pass_film.image();
        uniform_half.push_back(masked_mean(img, lower_half));
        uniform_image.push_back(masked_mean(img, {}));
    }
    expect_same_means("bdpt + pt extra samples, lower half", summarise(adaptive_half), summarise(uniform_half));
    expect_same_means("bdpt + pt extra samples, image", summarise(adaptive_image), summarise(uniform_image));
}

// Extra samples of scattered pixels go out as one launch over a list of them
// (PassSpec::run_pixels): each listed pixel's samples must come out bit for bit as when the pixel
// is rendered as a run of its own, and land on that pixel of the film.
TEST(AdaptiveSampling, ListedPixelsRenderAsTheirOwnRuns) {
    const int size = 16, samples = 3;
    const DeviceScene scene = build_device_scene(load_scene(scene_path("cornell-box")), size, size);
    Renderer renderer(test_device(), scene, make_options(Integrator::Pt, 5, 5, SamplerKind::Sobol));
    auto list = std::make_shared<std::vector<int>>(std::vector<int>{3, 77, 150, 151, 255});
    PassSpec listed;
    listed.sample_index = listed.position_sample_index = 16;
    listed.seed = listed.position_seed = 5;
    listed.run_length = int(list->size());
    listed.run_pixels = list;
    const int length = int(list->size());
    const RenderedItems all = renderer.render_items(listed, 0, samples * length);
    Film film(size, size);
    add_to_film(film, all);
    for (int j = 0; j < length; ++j) {
        PassSpec own = listed;
        own.run_pixels = nullptr;
        own.run_pixel = (*list)[size_t(j)];
        own.run_length = 1;
        const RenderedItems one = renderer.render_items(own, 0, samples);
        double sum[3] = {0, 0, 0};
        for (int k = 0; k < samples; ++k)
            for (int c = 0; c < 3; ++c) {
                EXPECT_EQ(all.camera[size_t(k * length + j) * 3 + c], one.camera[size_t(k) * 3 + c])
                    << "pixel " << own.run_pixel << ", sample " << k;
                sum[c] += one.camera[size_t(k) * 3 + c];
            }
        for (int c = 0; c < 3; ++c) EXPECT_EQ(film.camera_sum[size_t(own.run_pixel) * 3 + c], sum[c]);
    }
    double elsewhere = 0;
    for (int p = 0; p < size * size; ++p)
        if (std::find(list->begin(), list->end(), p) == list->end())
            elsewhere += film.camera_sum[size_t(p) * 3] + film.camera_sum[size_t(p) * 3 + 1] + film.camera_sum[size_t(p) * 3 + 2];
    EXPECT_EQ(elsewhere, 0.0);
}

// Extra samples keep only the camera image (PassSpec::camera_image_only). A bdpt mix without inner
// connections then traces no light subpaths for them: its camera image must come out bit for bit
// as with them, for fewer rays and no splats; a mix with inner connections still traces them.
TEST(AdaptiveSampling, CameraImageOnlySkipsUselessLightSubpaths) {
    const int size = 16, samples = 4;
    const DeviceScene scene = build_device_scene(load_scene(scene_path("cornell-specular")), size, size);
    for (bool connections : {false, true}) {
        RenderOptions options = make_options(Integrator::Bdpt, 8, 5, SamplerKind::Sobol);
        options.light_subpaths = 0.5f;
        options.inner_connections = connections;
        Renderer renderer(test_device(), scene, options);
        PassSpec whole;
        whole.sample_index = whole.position_sample_index = 64;
        whole.seed = whole.position_seed = 5;
        whole.run_pixel = 0;
        whole.run_length = size * size;
        PassSpec camera_only = whole;
        camera_only.camera_image_only = true;
        const RenderedItems a = renderer.render_items(whole, 0, samples * size * size);
        const RenderedItems b = renderer.render_items(camera_only, 0, samples * size * size);
        ASSERT_EQ(a.camera.size(), b.camera.size());
        double rays_a = 0, rays_b = 0;
        for (size_t i = 0; i < a.rays.size(); ++i) {
            rays_a += a.rays[i];
            rays_b += b.rays[i];
        }
        if (connections) {
            EXPECT_EQ(a.camera, b.camera);
            EXPECT_EQ(rays_a, rays_b);
            EXPECT_EQ(a.splats.size(), b.splats.size());
            continue;
        }
        for (size_t i = 0; i < a.camera.size(); ++i) ASSERT_EQ(a.camera[i], b.camera[i]) << "item " << i / 3;
        EXPECT_LT(rays_b, 0.9 * rays_a);
        EXPECT_GT(a.splats.size(), 0u);
        EXPECT_EQ(b.splats.size(), 0u);
    }
}

}  // namespace
}  // namespace clbdpt::test
