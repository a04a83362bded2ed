#include "render/adaptive.h"

#include <algorithm>
#include <cmath>
#include <memory>

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

// Per pixel, a sample's variance as the two halves of its samples tell it: the squared
// difference of the means of its samples before and from Film::late_from, times
// n1 n2 / (n1 + n2), which for independent samples has the sample variance as its mean (summed
// over r, g and b). Sobol's strata make each half's mean, and the whole mean, better than
// independent samples would; this estimate shrinks with them, where the samples' own spread
// does not (an outline's pixel: samples on and off a bright light, a mean that the strata pin
// down). Empty where the film did not keep the later samples.
std::vector<double> pixel_half_variances(const Film& film) {
    const size_t pixels = size_t(film.width) * film.height;
    if (film.camera_late.size() != pixels * 3 || film.late_from == 0 || film.late_from >= uint32_t(film.spp)) return {};
    const double n1 = film.late_from, n2 = double(film.spp) - n1;
    std::vector<double> v(pixels, 0.0);
    for (size_t p = 0; p < pixels; ++p) {
        double d2 = 0;
        for (int c = 0; c < 3; ++c) {
            const double late = film.camera_late[p * 3 + c];
            const double d = (film.camera_sum[p * 3 + c] - late) / n1 - late / n2;
            d2 += d * d;
        }
        v[p] = d2 * n1 * n2 / (n1 + n2);
    }
    return v;
}

// The variance of the film's light image (t = 1 splats), summed over pixels and channels: what
// camera-only extra samples leave as it is. Estimated from each pixel's difference from the
// mean of its (up to four) edge neighbours, which for independent noise of variance s^2 has
// variance s^2 (1 + 1/k); the image's own detail adds to it, so the estimate errs high, towards
// fewer extra samples.
double light_image_variance(const Film& film) {
    const int w = film.width, h = film.height;
    if (film.spp < 1 || film.light_sum.size() != size_t(w) * h * 3) return 0.0;
    const double scale = 1.0 / film.spp;
    double sum = 0;
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            const int nx[4] = {x - 1, x + 1, x, x}, ny[4] = {y, y, y - 1, y + 1};
            for (int c = 0; c < 3; ++c) {
                double neighbours = 0;
                int k = 0;
                for (int i = 0; i < 4; ++i) {
                    if (nx[i] < 0 || ny[i] < 0 || nx[i] >= w || ny[i] >= h) continue;
                    neighbours += film.light_sum[(size_t(ny[i]) * w + nx[i]) * 3 + c];
                    ++k;
                }
                if (k == 0) continue;
                const double d = (film.light_sum[(size_t(y) * w + x) * 3 + c] - neighbours / k) * scale;
                sum += d * d / (1.0 + 1.0 / k);
            }
        }
    return sum;
}

}  // namespace

std::vector<double> adaptive_window_means(const std::vector<double>& v, int w, int h) {
    const size_t pixels = size_t(w) * h;
    std::vector<double> u(pixels, 0.0);
    if (pixels == 0 || v.size() != pixels) return u;
    // The window's sums by rows, then by columns (sums of a few non-negative terms each, so a
    // firefly's variance cannot swamp its small neighbours' by cancellation, as a summed-area
    // table's differences would).
    const int r = kAdaptiveRadius;
    std::vector<double> rows(pixels, 0.0);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            double sum = 0;
            for (int nx = std::max(0, x - r); nx <= std::min(w - 1, x + r); ++nx) sum += v[size_t(y) * w + nx];
            rows[size_t(y) * w + x] = sum;
        }
    for (int y = 0; y < h; ++y) {
        const int y0 = std::max(0, y - r), y1 = std::min(h - 1, y + r);
        for (int x = 0; x < w; ++x) {
            const int x0 = std::max(0, x - r), x1 = std::min(w - 1, x + r);
            double sum = 0;
            for (int ny = y0; ny <= y1; ++ny) sum += rows[size_t(ny) * w + x];
            const size_t p = size_t(y) * w + x;
            const int neighbours = (x1 - x0 + 1) * (y1 - y0 + 1) - 1;
            // p's own variance taken back out; rounding must not leave a negative remainder.
            u[p] = neighbours > 0 ? std::max(0.0, sum - v[p]) / neighbours : 0.0;
        }
    }
    return u;
}

AdaptiveTiers adaptive_tiers(const std::vector<double>& u, int max_tier, int spp, double max_extra_share,
                             double fixed_variance, const std::vector<double>& cost) {
    AdaptiveTiers plan;
    const size_t pixels = u.size();
    plan.tier.assign(pixels, 0);
    max_tier = std::clamp(max_tier, 0, 8);
    double u_sum = 0;
    for (double x : u) u_sum += x;
    if (pixels == 0 || !(u_sum > 0) || max_tier == 0 || spp <= 0) return plan;

    // Each pixel's cost of a sample relative to the mean (1 where none is known), kept above a
    // thousandth of it; its tier follows u_p / c_p.
    std::vector<double> c(pixels, 1.0);
    double cost_sum = 0;
    if (cost.size() == pixels)
        for (double x : cost) cost_sum += x;
    if (cost_sum > 0) {
        const double mean = cost_sum / double(pixels);
        for (size_t p = 0; p < pixels; ++p) c[p] = std::max(cost[p] / mean, 1e-3);
    }
    std::vector<double> q(pixels);
    for (size_t p = 0; p < pixels; ++p) q[p] = u[p] / c[p];

    // The tiers for threshold base `base`: extra samples, predicted variance sum_p u_p / n_p and
    // time sum_p n_p c_p (in units of one sample's).
    struct Outcome {
        uint64_t extra = 0;
        double variance = 0, time = 0;
    };
    auto tiers_for = [&](double base, std::vector<uint8_t>* tier) {
        Outcome o;
        for (size_t p = 0; p < pixels; ++p) {
            int k = 0;
            for (double threshold = 4 * base; k < max_tier && q[p] >= threshold; threshold *= 4) ++k;
            if (tier) (*tier)[p] = uint8_t(k);
            const double n = double(uint64_t(spp) << k);
            o.extra += uint64_t(spp) * ((uint64_t(1) << k) - 1);
            o.variance += u[p] / n;
            o.time += n * c[p];
        }
        return o;
    };
    // Bases from the largest q (no extra samples) down by factors of sqrt 2 while the extra
    // samples fit the budget; the one of the least predicted (variance + fixed) x time wins, and
    // one with more extra samples must beat the best before it by kAdaptiveMinGain.
    const double budget = max_extra_share * double(spp) * double(pixels);
    const double q_max = *std::max_element(q.begin(), q.end());
    const Outcome none = tiers_for(q_max, nullptr);
    double best_base = q_max, best_cost = (none.variance + fixed_variance) * none.time;
    for (double base = q_max / 2; base > q_max * 1e-12; base /= std::sqrt(2.0)) {
        const Outcome o = tiers_for(base, nullptr);
        if (double(o.extra) > budget) break;
        const double predicted = (o.variance + fixed_variance) * o.time;
        if (predicted * (1 + kAdaptiveMinGain) < best_cost) best_base = base, best_cost = predicted;
    }
    plan.extra_samples = tiers_for(best_base, &plan.tier).extra;
    for (uint8_t k : plan.tier) plan.pixels_refined += k > 0;
    plan.u_mean = best_base;
    return plan;
}

AdaptivePlan plan_adaptive_samples(const Film& film, int max_tier, double max_extra_share, bool camera_only_extras) {
    AdaptivePlan plan;
    plan.spp = film.spp;
    plan.max_tier = std::clamp(max_tier, 0, 8);
    // A sample's cost around each pixel, p left out as for u (a pixel's own rays follow its own
    // paths): the rays per sample of its window.
    std::vector<double> cost;
    if (film.camera_rays.size() == size_t(film.width) * film.height && film.spp > 0)
        cost = adaptive_window_means(film.camera_rays, film.width, film.height);
    // u_p: the window's mean of its pixels' sample variances, but no more than its mean of their
    // halves' variances (pixel_half_variances), where the strata make the mean of the samples
    // better than their spread says.
    std::vector<double> u = adaptive_window_means(sample_variances(film), film.width, film.height);
    const std::vector<double> halves = pixel_half_variances(film);
    if (!halves.empty()) {
        const std::vector<double> from_halves = adaptive_window_means(halves, film.width, film.height);
        for (size_t p = 0; p < u.size(); ++p) u[p] = std::min(u[p], from_halves[p]);
    }
    AdaptiveTiers tiers = adaptive_tiers(u, max_tier, film.spp, max_extra_share,
                                         camera_only_extras ? light_image_variance(film) : 0.0, cost);
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
    // Tier k's pixels get samples spp 2^(k-1) .. spp 2^k - 1: rendered for the list of every
    // pixel of tier k or more, in pixel order, a sample of each at a time (item i: the list's
    // pixel i % length at sample i / length on), so that each pixel's samples are added in
    // sample order whatever the launches (the image does not depend on them). One list per
    // tier rather than a launch per stretch of neighbouring refined pixels: they lie scattered
    // (565 stretches on sky, launches of about a thousand samples that a GPU could not fill).
    for (int k = 1; k <= plan.max_tier; ++k) {
        auto list = std::make_shared<std::vector<int>>();
        for (size_t p = 0; p < pixels; ++p)
            if (plan.tier[p] >= k) list->push_back(int(p));
        if (list->empty()) continue;
        const int length = int(list->size());
        const uint32_t first_sample = uint32_t(plan.spp) << (k - 1);
        const int64_t samples = int64_t(plan.spp) << (k - 1);
        const int64_t chunk = std::max<int64_t>(1, kMaxItemsPerCall / length);
        for (int64_t done = 0; done < samples; done += chunk) {
            if (stop && stop()) return;
            const int64_t count = std::min(chunk, samples - done);
            PassSpec pass;
            pass.sample_index = pass.position_sample_index = first_sample + uint32_t(done);
            pass.seed = pass.position_seed = seed;
            pass.run_length = length;
            pass.run_pixels = list;
            pass.camera_image_only = true;
            RenderedItems items = renderer.render_items(pass, 0, int(count * length));
            items.splats.clear();  // the light image keeps spp samples per pixel
            add_to_film(film, items);
            for (int p : *list) film.extra_samples[size_t(p)] += uint32_t(count);
            if (stats) stats->add_counts(items.counts);
        }
    }
}

}  // namespace clbdpt
