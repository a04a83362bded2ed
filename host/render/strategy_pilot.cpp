#include "render/strategy_pilot.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>

namespace clbdpt {

namespace {

// Work items of one sparse pilot pass: enough pixels that the variance estimates and the
// timings are steady, few enough that the pilot costs little.
constexpr int kPilotItems = 8192;
constexpr int kPilotPassesPerCandidate = 3;
// The pilot may cost at most this share of the render's samples.
constexpr double kPilotShare = 0.1;
// Variance of a 2D discontinuous integrand under Owen-scrambled Sobol points: O(N^-3/2).
constexpr double kPixelVarianceExponent = 1.5;

double seconds_between(std::chrono::steady_clock::time_point a, std::chrono::steady_clock::time_point b) {
    return std::chrono::duration<double>(b - a).count();
}

int pilot_stride(int width, int height) {
    const double ratio = double(width) * double(height) / kPilotItems;
    return std::max(1, int(std::lround(std::sqrt(ratio))));
}

// Half the mean squared difference of two sparse passes over the grid's pixels and channels:
// the variance of one full-density sample. The light image of a sparse pass holds the light
// subpaths of 1/share of the pixels, so its variance is share times that of a full pass.
double one_sample_variance(const Film& a, const Film& b, int stride, double light_share) {
    double sum = 0;
    long count = 0;
    for (int y = 0; y < a.height; y += stride)
        for (int x = 0; x < a.width; x += stride)
            for (int c = 0; c < 3; ++c) {
                const size_t i = (size_t(y) * a.width + x) * 3 + c;
                const double dc = a.camera_sum[i] - b.camera_sum[i];
                const double dl = a.light_sum[i] - b.light_sum[i];
                sum += dc * dc + dl * dl * light_share;
                ++count;
            }
    return count ? sum / (2.0 * double(count)) : 0;
}

}  // namespace

std::vector<StrategyCandidate> strategy_candidates() {
    // Full bdpt; half the light subpaths (they cost as much as the camera subpath but pay off
    // only where light arrives indirectly); path tracing plus light tracing (caustics seen
    // directly, without the connections' cost); path tracing alone, with its own leaner kernel.
    // (A quarter of the light subpaths was a candidate too; it won on none of the bundled
    // scenes, so its pilot time is saved.)
    std::vector<StrategyCandidate> c(4);
    c[0].light_subpaths = 1.0f;
    c[1].light_subpaths = 0.5f;
    c[2].light_subpaths = 1.0f;
    c[2].inner_connections = false;
    c[3].integrator = Integrator::Pt;
    for (StrategyCandidate& s : c) s.name = describe_strategy_mix(s.integrator, s.light_subpaths, s.inner_connections);
    return c;
}

std::string describe_strategy_mix(Integrator integrator, float light_subpaths, bool inner_connections) {
    if (integrator != Integrator::Bdpt) return integrator_name(integrator);
    if (light_subpaths == 0.0f) return "bdpt without light subpaths (path tracing)";
    char buf[128];
    std::snprintf(buf, sizeof buf, "bdpt, %g light subpath%s per sample%s", double(light_subpaths),
                  light_subpaths == 1.0f ? "" : "s", inner_connections ? "" : ", no inner connections");
    return buf;
}

uint64_t strategy_pilot_samples(int width, int height) {
    return uint64_t(render_item_count(width, height, pilot_stride(width, height))) * kPilotPassesPerCandidate *
           strategy_candidates().size();
}

bool strategy_pilot_fits(int width, int height, int spp) {
    return double(strategy_pilot_samples(width, height)) <= kPilotShare * double(width) * double(height) * spp;
}

StrategyPilot run_strategy_pilot(DeviceContext& device, const DeviceScene& scene, const RenderOptions& options,
                                 int spp, double time_budget, RenderStats* stats) {
    using Clock = std::chrono::steady_clock;
    StrategyPilot pilot;
    pilot.candidates = strategy_candidates();
    pilot.spp = spp;
    const int k = int(pilot.candidates.size());
    const int width = scene.camera.width, height = scene.camera.height;
    pilot.pixel_stride = pilot_stride(width, height);
    const int items = render_item_count(width, height, pilot.pixel_stride);
    const double full_per_sparse = double(width) * double(height) / items;

    // One renderer per integrator, sharing the uploaded scene; the bdpt one changes its mix.
    Renderer* by_integrator[3] = {nullptr, nullptr, nullptr};
    std::shared_ptr<SceneBuffers> buffers;
    for (const StrategyCandidate& c : pilot.candidates) {
        Renderer*& r = by_integrator[int(c.integrator)];
        if (r) continue;
        RenderOptions o = options;
        o.integrator = c.integrator;
        pilot.renderers.push_back(std::make_unique<Renderer>(device, scene, o, buffers));
        r = pilot.renderers.back().get();
        buffers = r->scene_buffers();
    }

    const Clock::time_point start = Clock::now();
    // Passes a, b, c (see the header), each from its own seed; a and b share pixel positions.
    // Round robin, so a change of the machine's load hits every candidate alike.
    const uint32_t seed_a = options.seed ^ 0x6a09e667u, seed_b = options.seed ^ 0xbb67ae85u,
                   seed_c = options.seed ^ 0x3c6ef372u;
    std::vector<std::vector<Film>> films(size_t(k), std::vector<Film>(kPilotPassesPerCandidate, Film(width, height)));
    std::vector<double> seconds(size_t(k), 0.0);
    for (int round = 0; round < kPilotPassesPerCandidate; ++round)
        for (int i = 0; i < k; ++i) {
            const StrategyCandidate& c = pilot.candidates[size_t(i)];
            Renderer* r = by_integrator[int(c.integrator)];
            if (c.integrator == Integrator::Bdpt) r->set_strategy_mix(c.light_subpaths, c.inner_connections);
            PassSpec pass;
            pass.pixel_stride = pilot.pixel_stride;
            pass.seed = round == 0 ? seed_a : round == 1 ? seed_b : seed_c;
            pass.position_seed = round == 2 ? seed_c : seed_a;
            const Clock::time_point pass_start = Clock::now();
            r->render_pass(films[size_t(i)][size_t(round)], pass);
            seconds[size_t(i)] += seconds_between(pass_start, Clock::now());
        }

    for (int i = 0; i < k; ++i) {
        StrategyCandidate& c = pilot.candidates[size_t(i)];
        const std::vector<Film>& f = films[size_t(i)];
        c.variance_transport = one_sample_variance(f[0], f[1], pilot.pixel_stride, full_per_sparse);
        c.variance_pixel = std::max(0.0, one_sample_variance(f[0], f[2], pilot.pixel_stride, full_per_sparse) -
                                             c.variance_transport);
        c.seconds_per_pass = seconds[size_t(i)] / kPilotPassesPerCandidate * full_per_sparse;
        const double n = time_budget > 0 && c.seconds_per_pass > 0 ? std::max(1.0, time_budget / c.seconds_per_pass)
                                                                    : double(std::max(spp, 1));
        c.predicted_spp = n;
        c.predicted_mse = c.variance_transport / n + c.variance_pixel / std::pow(n, kPixelVarianceExponent);
        const double cost = c.predicted_mse * n * c.seconds_per_pass;
        c.efficiency = cost > 0 ? 1.0 / cost : 0.0;
        if (c.efficiency > pilot.candidates[size_t(pilot.chosen)].efficiency) pilot.chosen = i;
    }
    pilot.samples = uint64_t(items) * kPilotPassesPerCandidate * k;
    // The renderers' counters move into `stats`, so a renderer that goes on to the main render
    // does not count the pilot twice.
    stats->program_from_cache = true;
    for (const auto& r : pilot.renderers) {
        stats->add(r->stats());
        stats->program_from_cache = stats->program_from_cache && r->stats().program_from_cache;
        r->reset_counters();
    }
    pilot.seconds = seconds_between(start, Clock::now());
    return pilot;
}

}  // namespace clbdpt
