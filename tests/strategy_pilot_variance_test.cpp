// The strategy pilot's variance estimates (render/strategy_pilot.h) against the same variances
// measured on full passes. The pilot renders a sparse grid (one pixel of each 5 x 5 block of a
// 256^2 film) and keeps only the grid's camera samples and, of the light image (t = 1), the
// squares of all the splats of the grid's light subpaths: a full pass's light image has their
// mean per item as its variance per pixel. On the Cornell box about two thirds of full bdpt's
// one-sample transport variance is the light image's, and all of lt's (a candidate there: the
// box is diffuse), so a splat left out, or a wrong scale, shows.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "render/strategy_pilot.h"
#include "test_scenes.h"

namespace clbdpt::test {
namespace {

struct Variance {
    double mean = 0, standard_error = 0;
    double light = 0;  // the light image's part of mean
};

// The variance of light transport within the pixel, from pairs of full "sets" that share their
// pixel positions: half the squared difference of the two per pixel and channel, camera and
// light images together, as the pilot's. A set is the sampler's first set_size samples of each
// pixel (their mean); the variance is per sample, times set_size.
Variance full_pass_transport_variance(const DeviceScene& scene, const RenderOptions& options, int pairs,
                                      int set_size = 1) {
    Renderer renderer(test_device(), scene, options);
    const int width = scene.camera.width, height = scene.camera.height;
    double sum = 0, sum_squares = 0, light = 0;
    long pixels = 0;
    for (int pair = 0; pair < pairs; ++pair) {
        Film a(width, height), b(width, height);
        for (int j = 0; j < set_size; ++j) {
            PassSpec pass;
            pass.position_seed = 7000u + uint32_t(pair);
            pass.sample_index = pass.position_sample_index = uint32_t(j);
            pass.seed = 9000u + 2u * uint32_t(pair);
            renderer.render_pass(a, pass);
            pass.seed += 1;
            renderer.render_pass(b, pass);
        }
        for (int p = 0; p < width * height; ++p) {
            double term = 0;
            for (int c = 0; c < 3; ++c) {
                const size_t i = size_t(p) * 3 + size_t(c);
                const double dc = (a.camera_sum[i] - b.camera_sum[i]) / set_size,
                             dl = (a.light_sum[i] - b.light_sum[i]) / set_size;
                term += 0.5 * set_size * (dc * dc + dl * dl);
                light += 0.5 * set_size * dl * dl;
            }
            sum += term;
            sum_squares += term * term;
            ++pixels;
        }
    }
    Variance v;
    const double pixel_mean = sum / double(pixels);
    v.mean = pixel_mean / 3.0;
    v.light = light / double(pixels) / 3.0;
    v.standard_error =
        std::sqrt(std::max(0.0, sum_squares / double(pixels) - pixel_mean * pixel_mean) / double(pixels - 1)) / 3.0;
    return v;
}

// Tolerance: 4.5 combined standard errors (each from the spread of its pixels' terms), for two
// comparisons; the seeds are fixed, so a pass stays a pass.
TEST(StrategyPilotVariance, TransportVarianceMatchesFullPasses) {
    const int film = 256, max_depth = 5;
    Scene loaded = load_scene(scene_path("cornell-box"));
    DeviceScene scene = build_device_scene(loaded, film, film);
    const RenderOptions options = make_options(Integrator::Bdpt, max_depth, 11, SamplerKind::Sobol);
    RenderStats stats;
    StrategyPilot pilot = run_strategy_pilot(test_device(), scene, options, 64, 0.0, false, &stats);
    ASSERT_EQ(pilot.pixel_stride, 5) << "the test is about a sparse grid";
    const uint64_t items = uint64_t(render_item_count(film, film, pilot.pixel_stride));
    EXPECT_EQ(pilot.samples, items * 9 * pilot.candidates.size());
    EXPECT_EQ(stats.samples, pilot.samples) << "every pilot sample is counted once";

    for (const StrategyCandidate& c : pilot.candidates) {
        // Full bdpt, pt and lt (the mixes between them add nothing to what is tested).
        if (!(c.integrator != Integrator::Bdpt || (c.light_subpaths == 1.0f && c.inner_connections))) continue;
        RenderOptions o = make_options(c.integrator, max_depth, 11, SamplerKind::Sobol);
        const Variance full = full_pass_transport_variance(scene, o, 2);
        if (c.integrator == Integrator::Bdpt) {
            ASSERT_GT(full.light, 0.4 * full.mean) << "the light image must carry much of bdpt's variance here";
        }
        const double z = std::fabs(c.variance_transport - full.mean) /
                         std::hypot(c.variance_transport_standard_error, full.standard_error);
        report_stat(c.name + "/transport variance", z, 4.5, z <= 4.5);
        EXPECT_LE(z, 4.5)
            << c.name << ": pilot " << c.variance_transport << " +- " << c.variance_transport_standard_error
            << ", full passes " << full.mean << " +- " << full.standard_error << " (light image " << full.light << ")";

        // A set of 4 samples: the pilot's A + B / 4 (B from the median over its pixel groups)
        // against full sets.
        const Variance set = full_pass_transport_variance(scene, o, 2, 4);
        const double pilot_set = c.variance_transport - 0.75 * c.variance_transport_stratified;
        const double z_set =
            std::fabs(pilot_set - set.mean) / std::hypot(c.variance_transport_standard_error, set.standard_error);
        report_stat(c.name + "/transport variance of a set of 4", z_set, 4.5, z_set <= 4.5);
        EXPECT_LE(z_set, 4.5) << c.name << ": pilot " << pilot_set << " (stratified part "
                              << c.variance_transport_stratified << "), full sets " << set.mean << " +- "
                              << set.standard_error;
    }
}

// cornell-specular: BDPT without inner connections renders the glass sphere's caustics far
// better than pt (64 spp with adaptive sampling: MSE 1.0e-4 against 4.5e-4, for 2.7x the time;
// without adaptive sampling 2.2e-4 against 6.1e-4), but every candidate also meets the same few
// samples through the mirror onto the caustic, which only the camera subpath reaches. Counted
// in, they made pt's predicted error only 1.55, 3.2 and 1.7 times the mix's for these seeds (the
// pilot picked pt in 5 of 5 seeds); left out (shared_tail_terms), 2.6, 25 and 2.8. The choice
// also weighs each candidate's pass time, which a loaded machine (tests run in parallel) skews,
// so the test asserts the timing-free ratio: its median over three seeds at least 2.2, between
// the two. For the same reason the pilot runs every candidate here: whether it runs the mixes
// at all depends on the ends' lead in efficiency, pass times included (a CI run under load
// skipped them once).
TEST(StrategyPilotChoice, CornellSpecularPredictsTheCausticsOfPt) {
    Scene loaded = load_scene(scene_path("cornell-specular"));
    DeviceScene scene = build_device_scene(loaded, 256, 256);
    std::vector<double> ratios;
    double shared_tail = 0;
    for (uint32_t seed : {31u, 32u, 33u}) {
        RenderOptions options = make_options(Integrator::Bdpt, loaded.render.max_depth, seed, SamplerKind::Sobol);
        options.pilot_every_candidate = true;
        RenderStats stats;
        const StrategyPilot pilot = run_strategy_pilot(test_device(), scene, options, 64, 0.0, false, &stats);
        double pt = 0, mix = 0;
        for (const StrategyCandidate& c : pilot.candidates) {
            if (c.integrator == Integrator::Pt) pt = c.predicted_mse;
            if (c.integrator == Integrator::Bdpt && c.light_subpaths == 1.0f && !c.inner_connections)
                mix = c.predicted_mse;
            shared_tail = std::max(shared_tail, c.variance_shared_tail);
        }
        ASSERT_GT(mix, 0.0);
        ratios.push_back(pt / mix);
    }
    std::sort(ratios.begin(), ratios.end());
    EXPECT_GE(ratios[1], 2.2) << "pt / BDPT without inner connections: " << ratios[0] << ", " << ratios[1] << ", "
                              << ratios[2];
    EXPECT_GT(shared_tail, 0.0) << "the mirror's caustic samples, shared by every candidate";
}

// With adaptive sampling the pilot credits each camera image with what the plan will take off
// it (run_strategy_pilot). On the Cornell box a path tracer's error gathers near the light, and
// the plan of 2026-11-26 took 43% of pt's squared error off with 3% more samples (64 spp, seeds 1 and
// 2: MSE 5.0e-5 without it, 2.9e-5 with it); the pilot credits a part of that, for extra
// samples whose time it counts. lt has no camera image: nothing to credit.
// The same seed gives the same passes, so only the prediction may differ.
TEST(StrategyPilotAdaptive, CreditsTheCameraImageNotTheLightImage) {
    Scene loaded = load_scene(scene_path("cornell-box"));
    DeviceScene scene = build_device_scene(loaded, 256, 256);
    const RenderOptions options = make_options(Integrator::Bdpt, loaded.render.max_depth, 5, SamplerKind::Sobol);
    RenderStats stats;
    const StrategyPilot plain = run_strategy_pilot(test_device(), scene, options, 64, 0.0, false, &stats);
    const StrategyPilot adaptive = run_strategy_pilot(test_device(), scene, options, 64, 0.0, true, &stats);
    // The mixes between the ends run only where no end leads by a margin measured in seconds,
    // so under load one pilot may run them and the other not (6 candidates against 3 under a
    // newcomer CI beside another build): the ends are compared, and every candidate both ran.
    bool saw_pt = false, saw_lt = false;
    for (const StrategyCandidate& a : adaptive.candidates) {
        auto same = std::find_if(plain.candidates.begin(), plain.candidates.end(),
                                 [&](const StrategyCandidate& c) { return c.name == a.name; });
        if (same == plain.candidates.end()) continue;
        const StrategyCandidate& p = *same;
        EXPECT_EQ(p.variance_transport, a.variance_transport) << p.name << ": the same passes";
        EXPECT_EQ(p.adaptive_variance_left, 1.0) << p.name;
        EXPECT_EQ(p.adaptive_extra_share, 0.0) << p.name;
        EXPECT_LE(a.adaptive_variance_left, 1.0) << a.name;
        EXPECT_LE(a.adaptive_extra_share, 1.0) << a.name << ": at most as many extra samples as the passes";
        if (a.integrator == Integrator::Pt) {
            saw_pt = true;
            EXPECT_LT(a.adaptive_variance_left, 0.95) << "pt's error near the light";
            EXPECT_GT(a.adaptive_extra_share, 0.0);
            EXPECT_LT(a.predicted_mse, p.predicted_mse);
            // Efficiency at equal seconds per pass: the two pilots time their passes apart, and
            // a pass of a few ms under a parallel ctest varies more than the gain (a.efficiency
            // once came out 0.63x p.efficiency that way).
            EXPECT_LT(a.predicted_mse * (1.0 + a.adaptive_extra_share), p.predicted_mse)
                << "extra samples planned where they pay for their time";
        }
        if (a.integrator == Integrator::Lt) {
            saw_lt = true;
            EXPECT_EQ(a.adaptive_variance_left, 1.0) << "lt's light image gets no extra samples";
            EXPECT_EQ(a.adaptive_extra_share, 0.0);
            EXPECT_EQ(a.predicted_mse, p.predicted_mse);
        }
    }
    EXPECT_TRUE(saw_pt && saw_lt) << "the Cornell box is diffuse: pt and lt are both candidates";
}

}  // namespace
}  // namespace clbdpt::test
