#include "render/adaptive.h"

#include <algorithm>

#include "film/rendered_items.h"
#include "util/error.h"

namespace clbdpt {

namespace {

// Work items per render_items call: a run of pixels times the samples it needs can be long, and
// each item's value is held on the host until it is added.
constexpr int64_t kMaxItemsPerCall = int64_t(1) << 20;

// The variance of one camera sample of each pixel (summed over r, g and b), from its spp samples.
std::vector<double> sample_variances(const Film& film) {
    const size_t pixels = size_t(film.width) * film.height;
    std::vector<double> v(pixels, 0.0);
    if (film.spp < 2 || film.camera_sq.size() != pixels) return v;
    const double n = film.spp;
    for (size_t p = 0; p < pixels; ++p) {
        double mean_sq = 0;
        for (int c = 0; c < 3; ++c) {
            const double m = film.camera_sum[p * 3 + c] / n;
            mean_sq += m * m;
        }
        // The unbiased estimate (n - 1 in the denominator); rounding can make it slightly negative.
        v[p] = std::max(0.0, (film.camera_sq[p] - n * mean_sq) / (n - 1));
    }
    return v;
}

}  // namespace

std::vector<double> adaptive_neighbour_variances(const std::vector<double>& v, int w, int h) {
    const size_t pixels = size_t(w) * h;
    std::vector<double> u(pixels, 0.0);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            LargestTwo neighbours;
            for (int dy = -1; dy <= 1; ++dy)
                for (int dx = -1; dx <= 1; ++dx) {
                    const int nx = x + dx, ny = y + dy;
                    if ((dx == 0 && dy == 0) || nx < 0 || ny < 0 || nx >= w || ny >= h) continue;
                    neighbours.add(v[size_t(ny) * w + nx]);
                }
            u[size_t(y) * w + x] = neighbours.second;
        }
    return u;
}

AdaptiveTiers adaptive_tiers(const std::vector<double>& u, int max_tier, int spp, double max_extra_share) {
    AdaptiveTiers plan;
    const size_t pixels = u.size();
    plan.tier.assign(pixels, 0);
    max_tier = std::clamp(max_tier, 0, 8);
    double u_sum = 0;
    for (double x : u) u_sum += x;
    if (pixels == 0 || !(u_sum > 0) || max_tier == 0) return plan;
    plan.u_mean = u_sum / double(pixels);

    const double budget = max_extra_share * double(spp) * double(pixels);
    for (;;) {
        plan.extra_samples = 0;
        plan.pixels_refined = 0;
        for (size_t p = 0; p < pixels; ++p) {
            int k = 0;
            for (double threshold = 4 * plan.u_mean; k < max_tier && u[p] >= threshold; threshold *= 4) ++k;
            plan.tier[p] = uint8_t(k);
            plan.extra_samples += uint64_t(spp) * ((uint64_t(1) << k) - 1);
            plan.pixels_refined += k > 0;
        }
        if (double(plan.extra_samples) <= budget) break;
        plan.u_mean *= 2;
    }
    return plan;
}

AdaptivePlan plan_adaptive_samples(const Film& film, int max_tier, double max_extra_share) {
    AdaptivePlan plan;
    plan.spp = film.spp;
    plan.max_tier = std::clamp(max_tier, 0, 8);
    AdaptiveTiers tiers =
        adaptive_tiers(adaptive_neighbour_variances(sample_variances(film), film.width, film.height), max_tier,
                       film.spp, max_extra_share);
    plan.tier = std::move(tiers.tier);
    plan.extra_samples = tiers.extra_samples;
    plan.pixels_refined = tiers.pixels_refined;
    plan.u_mean = tiers.u_mean;
    return plan;
}

void render_adaptive_samples(Renderer& renderer, const AdaptivePlan& plan, Film& film, RenderStats* stats,
                             const std::function<bool()>& stop) {
    const int w = film.width, h = film.height;
    const size_t pixels = size_t(w) * h;
    if (plan.extra_samples == 0) return;
    if (plan.tier.size() != pixels || plan.spp != film.spp) throw Error("adaptive sampling: plan does not fit the film");
    film.extra_samples.assign(pixels, 0);
    film.extra_samples_whole = renderer.options().integrator == Integrator::Pt;
    const uint32_t seed = renderer.options().seed;
    // Tier k's pixels get samples spp 2^(k-1) .. spp 2^k - 1: rendered for every pixel of tier
    // k or more, a run of neighbouring such pixels at a time, in pixel order (so the image does
    // not depend on the launch sizes).
    for (int k = 1; k <= plan.max_tier; ++k) {
        const uint32_t first_sample = uint32_t(plan.spp) << (k - 1);
        const int64_t samples = int64_t(plan.spp) << (k - 1);
        for (size_t p = 0; p < pixels;) {
            if (plan.tier[p] < k) {
                ++p;
                continue;
            }
            size_t end = p;
            while (end < pixels && plan.tier[end] >= k) ++end;
            const int run_length = int(end - p);
            const int64_t chunk = std::max<int64_t>(1, kMaxItemsPerCall / run_length);
            for (int64_t done = 0; done < samples; done += chunk) {
                if (stop && stop()) return;
                const int64_t count = std::min(chunk, samples - done);
                PassSpec pass;
                pass.sample_index = pass.position_sample_index = first_sample + uint32_t(done);
                pass.seed = pass.position_seed = seed;
                pass.run_pixel = int(p);
                pass.run_length = run_length;
                RenderedItems items = renderer.render_items(pass, 0, int(count * run_length));
                items.splats.clear();  // the light image keeps spp samples per pixel
                add_to_film(film, items);
                for (int i = 0; i < run_length; ++i) film.extra_samples[p + size_t(i)] += uint32_t(count);
                if (stats) stats->add_counts(items.counts);
            }
            p = end;
        }
    }
}

}  // namespace clbdpt
