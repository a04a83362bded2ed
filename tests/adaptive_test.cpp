// Adaptive sampling's plan (render/adaptive.h), without OpenCL: which pixels get extra samples,
// that a pixel's plan does not depend on its own samples (what keeps its value unbiased), the
// cap on the extra samples, and the light image's variance that camera-only ones cannot lower.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>

#include "render/adaptive.h"

namespace clbdpt {
namespace {

// A film of spp samples per pixel whose pixel p has sample variance variance(x, y) (summed
// over channels: every sample is (s, 0, 0), half of them m + d and half m - d, so the mean is m
// and the variance d^2 n / (n - 1)).
template <class F>
Film film_with_variance(int width, int height, int spp, F variance) {
    Film film(width, height);
    film.spp = spp;
    film.camera_sq.assign(size_t(width) * height, 0.0);
    for (int y = 0; y < height; ++y)
        for (int x = 0; x < width; ++x) {
            const size_t p = size_t(y) * width + x;
            const double m = 0.5, v = variance(x, y), d = std::sqrt(v * (spp - 1) / spp);
            film.camera_sum[p * 3] = m * spp;
            film.camera_sq[p] = spp * (m * m + d * d);
        }
    return film;
}

// An edge: column 20 of a 40 x 30 film is 1000 times noisier than the rest. Every pixel within
// kAdaptiveRadius columns of it has edge pixels in its window (the edge's own pixels those above
// and below), so those columns get extra samples; uniform noise farther away gets none, and so
// does a film of uniform noise: spread evenly, extra samples would lower the error only as
// much as they cost.
TEST(AdaptivePlan, RefinesEdgesNotUniformNoise) {
    const int w = 40, h = 30;
    const Film film = film_with_variance(w, h, 16, [](int x, int) { return x == 20 ? 1000.0 : 1.0; });
    const AdaptivePlan plan = plan_adaptive_samples(film);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            const int tier = plan.tier[size_t(y) * w + x];
            if (std::abs(x - 20) <= kAdaptiveRadius) EXPECT_GT(tier, 0) << x << ", " << y;
            else EXPECT_EQ(tier, 0) << x << ", " << y;
        }
    uint64_t extra = 0;
    for (uint8_t t : plan.tier) extra += 16u * ((1u << t) - 1);
    EXPECT_EQ(plan.extra_samples, extra);

    const AdaptivePlan uniform = plan_adaptive_samples(film_with_variance(w, h, 16, [](int, int) { return 3.0; }));
    EXPECT_EQ(uniform.extra_samples, 0u);
    EXPECT_EQ(uniform.pixels_refined, 0u);
}

// Camera-only extra samples (a bdpt film's) leave its light image's variance as it is, so the
// plan weighs what they take off the camera image against the whole image's: a light image of
// strong independent noise (variance 100 per pixel at spp against the camera image's 1000/16
// on the edge) leaves them nothing worth their time, where path-traced extra samples (whole
// estimates, which dilute the light image too) still refine the edge.
TEST(AdaptivePlan, LightImageNoiseHoldsBackCameraOnlyExtras) {
    const int w = 40, h = 30, spp = 16;
    Film film = film_with_variance(w, h, spp, [](int x, int) { return x == 20 ? 1000.0 : 1.0; });
    uint32_t state = 12345;
    for (double& l : film.light_sum) {
        state = state * 1664525u + 1013904223u;
        l = spp * (5.0 + 10.0 * std::sqrt(3.0) * (2.0 * (state >> 8) / double(1 << 24) - 1.0));  // sd 10 at spp
    }
    const AdaptivePlan whole = plan_adaptive_samples(film, kAdaptiveMaxTier, kAdaptiveMaxExtraShare, false);
    const AdaptivePlan camera_only = plan_adaptive_samples(film, kAdaptiveMaxTier, kAdaptiveMaxExtraShare, true);
    EXPECT_GT(whole.extra_samples, 0u);
    EXPECT_EQ(camera_only.extra_samples, 0u);

    // A light image of no noise (a smooth ramp) holds nothing back.
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x)
            for (int c = 0; c < 3; ++c) film.light_sum[(size_t(y) * w + x) * 3 + c] = spp * (1.0 + 0.01 * x);
    EXPECT_EQ(plan_adaptive_samples(film, kAdaptiveMaxTier, kAdaptiveMaxExtraShare, true).extra_samples,
              whole.extra_samples);
}

// A 40 x 30 film of 16 spp with two equally noisy edges, columns 10 and 30 (variance 1000, 1
// elsewhere), and the tier a plan gives column x of its middle row.
constexpr int kEdgesWidth = 40, kEdgesHeight = 30, kEdgesSpp = 16;
Film two_edges_film() {
    return film_with_variance(kEdgesWidth, kEdgesHeight, kEdgesSpp,
                              [](int x, int) { return x == 10 || x == 30 ? 1000.0 : 1.0; });
}
int middle_row_tier(const AdaptivePlan& plan, int x) {
    return plan.tier[size_t(kEdgesHeight / 2) * kEdgesWidth + x];
}

// Two equally noisy edges, columns 10 and 30, where a sample on the right half traces 16 times
// the rays of one on the left: samples in proportion to the standard deviation over the root of
// the cost give the right edge a quarter of the left's, two tiers fewer. Without ray counts the
// two edges get the same.
TEST(AdaptivePlan, CostlierPixelsGetFewerSamples) {
    const int w = kEdgesWidth, h = kEdgesHeight, spp = kEdgesSpp;
    Film film = two_edges_film();
    const AdaptivePlan same_cost = plan_adaptive_samples(film);
    EXPECT_GT(middle_row_tier(same_cost, 10), 0);
    EXPECT_EQ(middle_row_tier(same_cost, 10), middle_row_tier(same_cost, 30));

    film.camera_rays.assign(size_t(w) * h, 0.0);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) film.camera_rays[size_t(y) * w + x] = spp * (x < 20 ? 1.0 : 16.0);
    const AdaptivePlan by_cost = plan_adaptive_samples(film);
    EXPECT_GT(middle_row_tier(by_cost, 10), 0);
    EXPECT_EQ(middle_row_tier(by_cost, 10) - middle_row_tier(by_cost, 30), 2);
}

// An outline whose pixels' samples spread widely (variance 1000) but whose two halves of
// samples have the same mean, as Sobol's strata make them, is a mean already pinned down: with
// the halves kept (Film::camera_late) the plan leaves it alone; without them it refines it. A
// second edge whose halves differ as independent samples' would (difference of variance
// 1000 (1/8 + 1/8) per channel sum) is refined either way.
TEST(AdaptivePlan, StratifiedOutlinesAreNotRefinedForTheirSpread) {
    const int w = kEdgesWidth, h = kEdgesHeight, spp = kEdgesSpp;
    Film film = two_edges_film();
    const AdaptivePlan spread_only = plan_adaptive_samples(film);
    EXPECT_GT(middle_row_tier(spread_only, 10), 0);
    EXPECT_GT(middle_row_tier(spread_only, 30), 0);

    film.late_from = spp / 2;
    film.camera_late.assign(size_t(w) * h * 3, 0.0);
    uint32_t state = 777;
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            const size_t p = size_t(y) * w + x;
            // Halves' means m + e and m - e (the whole mean m stays), e drawn so that e^2 has
            // the mean independent samples' halves would give: var (1/n1 + 1/n2) / 4 with the
            // pixel's variance; none on the stratified edge, column 10.
            const double variance = x == 30 ? 1000.0 : x == 10 ? 0.0 : 1.0;
            state = state * 1664525u + 1013904223u;
            const double sign = (state >> 31) ? 1.0 : -1.0;
            const double e = sign * 0.5 * std::sqrt(variance * (2.0 / (spp / 2)));
            const double m = film.camera_sum[p * 3] / spp;
            film.camera_late[p * 3] = (spp / 2) * (m - e);
            film.camera_sum[p * 3] = (spp / 2) * (m + e) + film.camera_late[p * 3];
        }
    const AdaptivePlan with_halves = plan_adaptive_samples(film);
    EXPECT_EQ(middle_row_tier(with_halves, 10), 0) << "a stratified outline";
    EXPECT_GT(middle_row_tier(with_halves, 30), 0) << "an outline of independent noise";
}

// Changing one pixel's own samples, however much, changes its neighbours' plans but never its
// own: its extra samples are decided before and apart from its samples, so their mean stays
// unbiased. (The image-wide mean u_mean moves with it, by at most 1/pixels of the change; the
// pixel here is placed so that its own tier stays away from a threshold.)
TEST(AdaptivePlan, PixelsPlanDoesNotDependOnItsOwnSamples) {
    const int w = 24, h = 24;
    auto base = [](int x, int y) { return x == 12 ? 200.0 : 1.0 + 0.1 * ((x * 7 + y * 3) % 5); };
    const AdaptivePlan reference = plan_adaptive_samples(film_with_variance(w, h, 32, base));
    for (int px : {3, 11, 12}) {
        const int py = 9;
        for (double own : {0.0, 1e4}) {
            const AdaptivePlan changed = plan_adaptive_samples(
                film_with_variance(w, h, 32, [&](int x, int y) { return x == px && y == py ? own : base(x, y); }));
            EXPECT_EQ(changed.tier[size_t(py) * w + px], reference.tier[size_t(py) * w + px])
                << "pixel (" << px << ", " << py << ") with own variance " << own;
        }
    }
}

// The extra samples never exceed max_extra_share of the render's: a film whose noise rises
// steeply across it gets fewer tiers under a cap set at 3/4 of what it would take uncapped,
// and some still; max_tier 0 gives none.
TEST(AdaptivePlan, ExtraSamplesStayWithinTheirShare) {
    const int w = 64, h = 16, spp = 8;
    const Film film = film_with_variance(w, h, spp, [](int x, int) { return std::pow(10.0, x / 6.0); });
    const AdaptivePlan uncapped = plan_adaptive_samples(film, 4, 1e9);
    ASSERT_GT(uncapped.extra_samples, 0u);
    const double share = 0.75 * double(uncapped.extra_samples) / (double(spp) * w * h);
    const AdaptivePlan capped = plan_adaptive_samples(film, 4, share);
    EXPECT_GT(capped.extra_samples, 0u);
    EXPECT_LE(double(capped.extra_samples), share * spp * w * h);
    const AdaptivePlan none = plan_adaptive_samples(film, 0, 1.0);
    EXPECT_EQ(none.extra_samples, 0u);
    for (uint8_t t : none.tier) EXPECT_EQ(t, 0);
}

// A pixel with extra samples: with the passes' integrator's (a bdpt camera image's), its camera
// sum is divided by all its samples and its light image by spp; with path-traced ones (whole
// estimates of the pixel), camera and light sums together are divided by all its samples.
TEST(AdaptiveFilm, ExtraSamplesCameraOnlyOrWhole) {
    Film film(2, 1);
    film.spp = 4;
    for (int c = 0; c < 3; ++c) {
        film.camera_sum[size_t(c)] = 2.0 + c;   // pixel 0: 4 passes + 12 extra samples
        film.light_sum[size_t(c)] = 1.0;
        film.camera_sum[size_t(3 + c)] = 4.0;  // pixel 1: none
        film.light_sum[size_t(3 + c)] = 2.0;
    }
    film.extra_samples = {12, 0};
    std::vector<float> img = film.image();
    EXPECT_FLOAT_EQ(img[0], 2.0f / 16 + 1.0f / 4);
    EXPECT_FLOAT_EQ(img[2], 4.0f / 16 + 1.0f / 4);
    EXPECT_FLOAT_EQ(img[3], 6.0f / 4);
    film.extra_samples_whole = true;
    img = film.image();
    EXPECT_FLOAT_EQ(img[0], 3.0f / 16);
    EXPECT_FLOAT_EQ(img[2], 5.0f / 16);
    EXPECT_FLOAT_EQ(img[3], 6.0f / 4);
}

}  // namespace
}  // namespace clbdpt
