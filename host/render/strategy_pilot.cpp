#include "render/strategy_pilot.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>

#include "film/rendered_items.h"

namespace clbdpt {

namespace {

// Work items of one sparse pilot pass: enough pixels that the variance estimates and the
// timings are steady, few enough that the pilot costs little.
constexpr int kPilotItems = 3072;
// Two sets of kPilotSetSize passes that share their pixel positions, and pass c (see the header).
constexpr int kPilotSetSize = 4;
constexpr int kPilotPassesPerCandidate = 2 * kPilotSetSize + 1;
// The pilot may cost at most this share of the render's samples.
constexpr double kPilotShare = 0.1;
// How many standard errors a candidate's transport variance counts high (see the choice).
constexpr double kRiskStandardErrors = 2.0;
// Variance of a 2D discontinuous integrand under Owen-scrambled Sobol points: O(N^-3/2).
constexpr double kPixelVarianceExponent = 1.5;

double seconds_between(std::chrono::steady_clock::time_point a, std::chrono::steady_clock::time_point b) {
    return std::chrono::duration<double>(b - a).count();
}

// Fewer pixels than this (or than the film has) give variance estimates too noisy to choose by.
constexpr int kPilotMinItems = 1024;

// A candidate's timing passes (timing_pass_seconds): this many, each of runs of neighbouring
// pixels, kTimingRuns of them, in bands of rows at 1/6, 1/2 and 5/6 of the film's height (so
// that the sky and the floor both count); together about as many samples as a pass of the grid.
constexpr int kTimingPasses = 2;
constexpr int kTimingRuns = 3;
int timing_run_length(int width, int height, int items) {
    return std::min(std::max(1, items / (kTimingRuns * kTimingPasses)), width * height);
}
int timing_samples(int width, int height, int items) { return kTimingRuns * timing_run_length(width, height, items); }

// The seconds `r` takes for timing_samples(...) samples rendered as the
// render's own passes render them, and added to a film as the render adds them. The sparse grid's
// passes mistimed the candidates: their pixels lie k apart, which costs a path tracer coherence
// (sky: 0.023 s per full pass from the grid, 0.018 in the render), and they hold 1/k^2 of a full
// pass's light-image splats, whose adding on the host takes the render's cores too (sky, BDPT
// without inner connections: 0.032 against 0.034 s). So the grid made that mix 1.39x pt's time
// per pass, where the render takes 1.84x, and chose it on sky in 1 of 3 seeds, for 0.8x pt's
// efficiency.
double timing_pass_seconds(Renderer& r, uint32_t seed, int items, Film* film, RenderStats* stats) {
    using Clock = std::chrono::steady_clock;
    const int pixels = film->width * film->height, run = timing_run_length(film->width, film->height, items);
    PassSpec pass;
    pass.seed = pass.position_seed = seed;
    double seconds = 0;
    for (int b = 0; b < kTimingRuns; ++b) {
        const int centre = int(int64_t(2 * b + 1) * pixels / (2 * kTimingRuns));
        const int first = std::clamp(centre - run / 2, 0, pixels - run);
        const Clock::time_point start = Clock::now();
        const RenderedItems rendered = r.render_items(pass, first, run);
        add_to_film(*film, rendered);
        seconds += seconds_between(start, Clock::now());
        stats->add_counts(rendered.counts);
    }
    return seconds;
}

uint64_t pilot_samples_at(int width, int height, int stride, size_t candidates) {
    const int items = render_item_count(width, height, stride);
    return (uint64_t(items) * kPilotPassesPerCandidate + uint64_t(kTimingPasses) * timing_samples(width, height, items)) *
           candidates;
}

// The sparse grid's stride when the render's samples do not limit it: about kPilotItems pixels.
int full_pilot_stride(int width, int height) {
    return std::max(1, int(std::lround(std::sqrt(double(width) * double(height) / kPilotItems))));
}

// The stride for a render of `spp` samples per pixel: the full grid's, or a coarser one where
// the render is short, so that the pilot stays within kPilotShare of the render's samples (a
// 128x128 film of 64 spp gets one pixel of each 2x2 block). 0 when no grid of at least
// kPilotMinItems pixels (or the whole film, if smaller) fits: the render then goes without.
int pilot_stride(int width, int height, int spp, size_t candidates) {
    const double pixels = double(width) * double(height);
    const double allowed = kPilotShare * pixels * double(std::max(spp, 0));
    const int min_items = int(std::min<double>(kPilotMinItems, pixels));
    for (int stride = full_pilot_stride(width, height); render_item_count(width, height, stride) >= min_items; ++stride)
        if (double(pilot_samples_at(width, height, stride, candidates)) <= allowed) return stride;
    return 0;
}

// A time budget of at least this many seconds gets the full grid; a shorter one a grid of
// proportionally fewer pixels, down to kPilotMinItems (or the whole film), so that a short
// budget is not mostly pilot (a 128x128 Cornell box in 1.5 s: the whole film as grid took 0.38 s).
constexpr double kFullGridBudgetSeconds = 10.0;

// The sparse grid's values of one pilot pass: per grid pixel (the pass's work item), the camera
// sample's rgb, and the light image's rgb summed over the item's whole k x k block. The grid alone is kept, so the pilot's memory
// and time do not grow with the film: with a full film per pass (twelve), a 2048^2 render's
// pilot took 7.8 s and the process peaked at 3.3 GB; with the grid, 0.32 s and 0.39 GB.
//
// Why the block, not the grid pixel: a sparse pass traces the light subpaths of one pixel per
// block, 1/k^2 of a full pass's, and their splats land anywhere. Counting only those that land
// on grid pixels kept 1/k^2 of them, too few to see a light image's rare bright splats (glossy
// reflections of small lights), whose variance then came out low far more often than high:
// on veach-mis (k = 5) the pilot put BDPT without inner connections at 0.47-0.70x pt's
// transport variance in 5 of 6 seeds, and chose it in 2, where its images had 1.1-1.5x pt's
// squared error at 1.9x the time. The splats of a block's k^2 pixels, from as many light
// subpaths as the pass traced, estimate the mean of those pixels' light-image variances
// (block_light_scale) from k^2 times the splats.
struct GridPass {
    int columns = 0, rows = 0, stride = 1, width = 0, height = 0;
    std::vector<double> camera, light;

    GridPass(int w, int h, int k)
        : columns((w + k - 1) / k), rows((h + k - 1) / k), stride(k), width(w), height(h),
          camera(size_t(columns) * rows * 3), light(size_t(columns) * rows * 3) {}
    int items() const { return columns * rows; }
    // The item whose block holds `pixel`.
    int block_item(int pixel) const { return (pixel / width / stride) * columns + (pixel % width) / stride; }
    // Pixels in item's block (fewer at the film's right and bottom edges).
    int block_pixels(int item) const {
        const int x = (item % columns) * stride, y = (item / columns) * stride;
        return std::min(stride, width - x) * std::min(stride, height - y);
    }
    // Another pass of the same grid, pixel by pixel (a set's sum).
    void add(const GridPass& other) {
        for (size_t v = 0; v < camera.size(); ++v) camera[v] += other.camera[v], light[v] += other.light[v];
    }
    // A pass's items (a dropped one adds nothing, as in add_to_film).
    void add(const RenderedItems& r) {
        size_t dropped = 0;
        for (int i = 0; i < r.item_count; ++i) {
            if (dropped < r.dropped_items.size() && r.dropped_items[dropped] == i) {
                ++dropped;
                continue;
            }
            for (int c = 0; c < 3; ++c) camera[size_t(r.first_item + i) * 3 + c] += r.camera[size_t(i) * 3 + c];
        }
        for (const SplatRecord& s : r.splats) {
            const size_t item = size_t(block_item(s.pixel));
            light[item * 3] += s.r;
            light[item * 3 + 1] += s.g;
            light[item * 3 + 2] += s.b;
        }
    }
};

// Half the squared difference of two sparse passes over the grid's pixels and channels, summed
// into kVarianceGroups interleaved groups of pixels (the grid's pixel number modulo the group
// count, so that each group spans the whole image). A group's mean is the variance of one
// full-density sample. The light image of a sparse pass holds the light subpaths of 1/share of
// the pixels, so a full pass's light-image variance is share times the sparse pass's.
constexpr int kVarianceGroups = 8;
struct GroupedVariance {
    double sum[kVarianceGroups] = {};
    long count[kVarianceGroups] = {};  // pixels x channels
    double pixel_sum_squares = 0;      // of each pixel's term, summed over its channels
    long pixels = 0;
    double mean() const {
        double s = 0;
        long n = 0;
        for (int g = 0; g < kVarianceGroups; ++g) s += sum[g], n += count[g];
        return n ? s / double(n) : 0;
    }
    double group_mean(int g) const { return count[g] ? sum[g] / double(count[g]) : 0; }
    // One grid pixel's term (summed over its channels).
    void add(int item, double pixel_term) {
        const int g = item % kVarianceGroups;
        sum[g] += pixel_term;
        count[g] += 3;
        pixel_sum_squares += pixel_term * pixel_term;
        ++pixels;
    }
    // The standard error of mean(), from the spread of the pixels' terms.
    double standard_error() const {
        if (pixels < 2) return 0;
        const double pixel_mean = 3.0 * mean();
        const double spread = std::max(0.0, pixel_sum_squares / double(pixels) - pixel_mean * pixel_mean);
        return std::sqrt(spread / double(pixels - 1)) / 3.0;
    }
};

// At one grid pixel, half the squared difference of a and b (each scaled by `scale`: 1/n for
// the sums of sets of n passes), summed over the channels; the light image's part is its block's
// (GridPass), per pixel of the block and times light_share (see GroupedVariance). *camera_part,
// if given, gets the camera image's part of the term.
double difference_term(const GridPass& a, const GridPass& b, int item, double scale, double light_share,
                       double* camera_part = nullptr) {
    double camera = 0, light = 0;
    const double block_light_scale = light_share / a.block_pixels(item);
    for (int c = 0; c < 3; ++c) {
        const size_t i = size_t(item) * 3 + size_t(c);
        const double dc = scale * (a.camera[i] - b.camera[i]);
        const double dl = scale * (a.light[i] - b.light[i]);
        camera += 0.5 * dc * dc;
        light += 0.5 * dl * dl * block_light_scale;
    }
    if (camera_part) *camera_part = camera;
    return camera + light;
}

GroupedVariance one_sample_variance(const GridPass& a, const GridPass& b, double light_share) {
    GroupedVariance v;
    for (int item = 0; item < a.items(); ++item)
        v.add(item, difference_term(a, b, item, 1.0, light_share));
    return v;
}

// The transport variance of one sample, from the pairs (x_j, y_j) of two sets of n passes that
// share their pixel positions (each pair's half squared difference, averaged over the set per
// pixel), and that of a set's mean times n (half the squared difference of the two sets' means,
// times n), so that both are per sample. `passes`: set x, then set y.
struct SetVariances {
    GroupedVariance one, set;
    std::vector<double> one_terms;  // `one`'s term of each grid pixel
    // Per grid pixel: the camera image's part of one_terms, and the second largest of its n
    // pairs' camera parts (what adaptive sampling's plan would see there; see predict_candidates).
    std::vector<double> camera_terms, camera_u;
};
SetVariances set_variances(const std::vector<GridPass>& passes, int n, double light_share) {
    const GridPass* x = passes.data();
    const GridPass* y = passes.data() + n;
    GridPass x_sum = x[0], y_sum = y[0];
    for (int j = 1; j < n; ++j) {
        x_sum.add(x[j]);
        y_sum.add(y[j]);
    }
    SetVariances v;
    for (int item = 0; item < x_sum.items(); ++item) {
        double one = 0, camera = 0, first = 0, second = 0;
        for (int j = 0; j < n; ++j) {
            double pair_camera;
            one += difference_term(x[j], y[j], item, 1.0, light_share, &pair_camera);
            camera += pair_camera;
            if (pair_camera > first) {
                second = first;
                first = pair_camera;
            } else if (pair_camera > second) {
                second = pair_camera;
            }
        }
        v.one.add(item, one / n);
        v.one_terms.push_back(one / n);
        v.camera_terms.push_back(camera / n);
        v.camera_u.push_back(second);
        v.set.add(item, n * difference_term(x_sum, y_sum, item, 1.0 / n, light_share));
    }
    return v;
}

// The median over the pixel groups of a's group means minus b's, at least 0. Two variances
// that differ by a part spread over the image (edges, smooth shading) differ so in most groups,
// while a firefly lands in one group: its cross terms with the other samples of its pixel,
// whose sign is chance, would otherwise pass for such a part.
double median_group_difference(const GroupedVariance& a, const GroupedVariance& b) {
    double d[kVarianceGroups];
    for (int g = 0; g < kVarianceGroups; ++g) d[g] = a.group_mean(g) - b.group_mean(g);
    std::sort(d, d + kVarianceGroups);
    return std::max(0.0, 0.5 * (d[kVarianceGroups / 2 - 1] + d[kVarianceGroups / 2]));
}

// The variance from where in the pixel a sample lands: whole minus transport, as the median over
// the pixel groups. Edges spread over many pixels, while one firefly in pass c (whose transport
// is independent of pass a's) lands in `whole` alone and, in the plain mean, passes for edges:
// on veach-mis a path tracer's v_pixel came out 6.3, 1.4 and 9.4 in three pilots with the plain
// mean, and 0, 0.07 and 0.013 with the median (its transport variance: 16, 3.0 and 0.72). The
// transport variance keeps the plain mean: a firefly there is the candidate's own, and the
// render will have it too.
double pixel_variance(const GroupedVariance& whole, const GroupedVariance& transport) {
    return median_group_difference(whole, transport);
}

// The candidate other than lt with the highest efficiency_transport_only: the figure lt must beat.
const StrategyCandidate* lt_rival(const std::vector<StrategyCandidate>& candidates) {
    const StrategyCandidate* rival = nullptr;
    for (const StrategyCandidate& c : candidates)
        if (c.integrator != Integrator::Lt && (!rival || c.efficiency_transport_only > rival->efficiency_transport_only))
            rival = &c;
    return rival;
}

}  // namespace

bool light_tracing_is_a_candidate(const DeviceScene& scene) {
    if (!scene.media.empty()) return false;
    for (const Material& m : scene.materials)
        if (m.kind != MATERIAL_DIFFUSE) return false;
    for (const Light& l : scene.lights)
        if (l.kind == LIGHT_ENVIRONMENT) return false;
    return true;
}

std::vector<StrategyCandidate> strategy_candidates(bool with_light_tracing) {
    // Full bdpt; half the light subpaths (they cost as much as the camera subpath but pay off
    // only where light arrives indirectly); path tracing plus light tracing (caustics seen
    // directly, without the connections' cost); path tracing alone, with its own leaner kernel;
    // and, where light_tracing_is_a_candidate, light tracing alone, as lean (a lamp aimed at the
    // ceiling: 1.4x bdpt's efficiency, whose camera subpaths and connections add little there).
    // (A quarter of the light subpaths was a candidate too; it won on none of the bundled
    // scenes, so its pilot time is saved.)
    std::vector<StrategyCandidate> c(with_light_tracing ? 5 : 4);
    c[0].light_subpaths = 1.0f;
    c[1].light_subpaths = 0.5f;
    c[2].light_subpaths = 1.0f;
    c[2].inner_connections = false;
    c[3].integrator = Integrator::Pt;
    if (with_light_tracing) c[4].integrator = Integrator::Lt;
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

int choose_strategy_candidate(const std::vector<StrategyCandidate>& candidates) {
    const StrategyCandidate* rival = lt_rival(candidates);
    const double bar = rival ? rival->efficiency_transport_only : 0.0;
    int chosen = 0;
    for (int i = 0; i < int(candidates.size()); ++i) {
        const StrategyCandidate& c = candidates[size_t(i)];
        if (c.integrator == Integrator::Lt && c.efficiency <= bar) continue;
        if (c.efficiency > candidates[size_t(chosen)].efficiency) chosen = i;
    }
    return chosen;
}

std::string light_tracing_passed_over(const std::vector<StrategyCandidate>& candidates, int chosen) {
    const StrategyCandidate* lt = nullptr;
    for (const StrategyCandidate& c : candidates)
        if (c.integrator == Integrator::Lt) lt = &c;
    const StrategyCandidate* rival = lt_rival(candidates);
    if (!lt || !rival || lt->efficiency <= candidates[size_t(chosen)].efficiency) return "";
    char buf[256];
    std::snprintf(buf, sizeof buf, "lt passed over: its efficiency %.3g does not beat %s's %.3g without v_pixel",
                  lt->efficiency, rival->name.c_str(), rival->efficiency_transport_only);
    return buf;
}

bool path_traced_extra_samples(const std::vector<StrategyCandidate>& candidates, int chosen, bool light_to_lens) {
    const StrategyCandidate& c = candidates[size_t(chosen)];
    if (c.integrator != Integrator::Bdpt || light_to_lens) return false;
    for (const StrategyCandidate& pt : candidates)
        if (pt.integrator == Integrator::Pt) return pt.efficiency >= kPathTracedExtrasMinShare * c.efficiency;
    return false;
}

bool strategy_pilot_fits(int width, int height, int spp, size_t candidates) {
    return pilot_stride(width, height, spp, candidates) > 0;
}

int timed_pilot_stride(int width, int height, double time_budget) {
    const double share = std::min(1.0, time_budget / kFullGridBudgetSeconds);
    const int target = std::max(kPilotMinItems, int(kPilotItems * share));
    int stride = full_pilot_stride(width, height);
    while (render_item_count(width, height, stride + 1) >= std::min(target, width * height)) ++stride;
    return stride;
}

std::vector<double> shared_tail_terms(const std::vector<const std::vector<double>*>& camera_terms) {
    const size_t items = camera_terms.empty() ? 0 : camera_terms[0]->size();
    if (camera_terms.size() < 2 || items == 0) return std::vector<double>(items, 0.0);
    std::vector<double> shared(items, 0.0);
    for (size_t item = 0; item < items; ++item) {
        double least = (*camera_terms[0])[item], largest = least;
        for (const std::vector<double>* terms : camera_terms) {
            least = std::min(least, (*terms)[item]);
            largest = std::max(largest, (*terms)[item]);
        }
        if (largest <= least * (1.0 + kSharedTailTolerance)) shared[item] = least;
    }
    // The largest kSharedTailShare of the pixels' shared parts (all of them, where fewer pixels
    // share one).
    std::vector<double> sorted = shared;
    const size_t keep = std::min(items - 1, size_t(double(items) * (1.0 - kSharedTailShare)));
    std::nth_element(sorted.begin(), sorted.begin() + long(keep), sorted.end());
    const double threshold = sorted[keep];
    for (double& v : shared)
        if (v < threshold) v = 0;
    return shared;
}

namespace {

// Adaptive sampling's plan (render/adaptive.h) as the pilot can foresee it: per grid pixel the
// tier k (spp x 2^k samples in all) for a pixel whose plan sees u, with u_mean doubled until the
// extra samples fit max_extra_share of the render's; returns their share.
double foreseen_adaptive_tiers(const std::vector<double>& u, std::vector<int>* tier) {
    constexpr int kMaxTier = 4;          // plan_adaptive_samples' defaults
    constexpr double kMaxExtraShare = 1.0;
    tier->assign(u.size(), 0);
    double u_mean = 0;
    for (double v : u) u_mean += v;
    u_mean /= double(std::max<size_t>(1, u.size()));
    if (!(u_mean > 0)) return 0;
    for (;;) {
        double extra = 0;
        for (size_t p = 0; p < u.size(); ++p) {
            int k = 0;
            for (double threshold = 4 * u_mean; k < kMaxTier && u[p] >= threshold; threshold *= 4) ++k;
            (*tier)[p] = k;
            extra += double((1 << k) - 1);
        }
        extra /= double(u.size());
        if (extra <= kMaxExtraShare) return extra;
        u_mean *= 2;
    }
}

// Each candidate's predicted error and efficiency (StrategyCandidate) from its tally, for a
// render of `spp` samples per pixel or, with time_budget > 0, of that many seconds, followed by
// adaptive sampling where `adaptive_sampling` says so.
void predict_candidates(const std::vector<SetVariances>& transport, const std::vector<GroupedVariance>& whole,
                        const std::vector<double>& seconds, int items, double full_per_sparse, int spp,
                        double time_budget, bool adaptive_sampling, std::vector<StrategyCandidate>* candidates) {
    const size_t k = transport.size();
    std::vector<const std::vector<double>*> camera_terms;
    for (size_t i = 0; i < k; ++i)
        if ((*candidates)[i].integrator != Integrator::Lt) camera_terms.push_back(&transport[i].one_terms);
    const std::vector<double> shared_tail = shared_tail_terms(camera_terms);
    for (size_t i = 0; i < k; ++i) {
        StrategyCandidate& c = (*candidates)[i];
        const SetVariances& t = transport[i];
        c.variance_transport = t.one.mean();
        c.variance_transport_standard_error = t.one.standard_error();
        // N x (variance of N samples' mean) = A + B / N: B is what stratification removes
        // faster than 1/N. From N = 1 and N = kPilotSetSize.
        const double n_set = kPilotSetSize;
        c.variance_transport_stratified =
            std::min(c.variance_transport, median_group_difference(t.one, t.set) * n_set / (n_set - 1.0));
        // lt's terms were not compared (it has no camera subpath): it keeps them all.
        const bool camera_candidate = c.integrator != Integrator::Lt;
        GroupedVariance own;
        for (int item = 0; item < items; ++item)
            own.add(item, t.one_terms[size_t(item)] - (camera_candidate ? shared_tail[size_t(item)] : 0.0));
        c.variance_shared_tail = c.variance_transport - own.mean();
        // Adaptive sampling gives the pixels whose neighbours' camera samples vary most 2^k
        // times the samples, which divides their camera image's variance by 2^k and leaves the
        // light image's as it is (render/adaptive.h). Where a candidate's error sits in a few
        // such pixels, that changes which candidate is best: on cornell-specular at 64 spp it
        // took pt's squared error from 6.1e-4 to 4.7e-4 and BDPT without inner connections' from
        // 2.2e-4 to 1.1e-4, the mix's caustics seen through the mirror. The pilot foresees the plan from each grid pixel's second largest camera pair
        // term, as the plan takes the second largest of a pixel's neighbours: a lone firefly
        // does not make a pixel's plan, so the pilot does not credit refinement with removing one.
        GroupedVariance refined = own;
        c.predicted_extra_share = 0;
        if (adaptive_sampling && camera_candidate) {
            std::vector<int> tier;
            c.predicted_extra_share = foreseen_adaptive_tiers(t.camera_u, &tier);
            refined = GroupedVariance();
            for (int item = 0; item < items; ++item) {
                const size_t p = size_t(item);
                const double light = std::max(0.0, t.one_terms[p] - t.camera_terms[p]);
                const double own_camera = std::max(0.0, t.camera_terms[p] - shared_tail[p]);
                refined.add(item, own_camera / double(1 << tier[p]) + light);
            }
        }
        c.variance_pixel = pixel_variance(whole[i], t.one);
        c.seconds_per_pass = seconds[i] * full_per_sparse;
        const double n = time_budget > 0 && c.seconds_per_pass > 0 ? std::max(1.0, time_budget / c.seconds_per_pass)
                                                                    : double(std::max(spp, 1));
        c.predicted_spp = n;
        // Heavy tails (a path tracer's fireflies in fog) make a sparse grid's variance come out
        // low more often than high, and a candidate chosen for a variance it does not have can
        // cost 25x (without this, fog-spot at 128x128 got pt, 0.04-0.07x of bdpt's efficiency
        // there, in one of three pilots); so the part of each transport variance that falls as
        // 1/N (less the shared tail) counts kRiskStandardErrors standard errors high.
        const double risky_transport = std::max(0.0, refined.mean() - c.variance_transport_stratified) +
                                       kRiskStandardErrors * refined.standard_error();
        const double transport_mse = risky_transport / n + c.variance_transport_stratified / (n * n);
        c.predicted_mse = transport_mse + c.variance_pixel / std::pow(n, kPixelVarianceExponent);
        const double seconds = n * c.seconds_per_pass * (1.0 + c.predicted_extra_share);
        const double cost = c.predicted_mse * seconds;
        c.efficiency = cost > 0 ? 1.0 / cost : 0.0;
        const double transport_cost = transport_mse * seconds;
        c.efficiency_transport_only = transport_cost > 0 ? 1.0 / transport_cost : 0.0;
    }
}

}  // namespace

StrategyPilot run_strategy_pilot(DeviceContext& device, const DeviceScene& scene, const RenderOptions& options,
                                 int spp, double time_budget, bool adaptive_sampling, RenderStats* stats) {
    using Clock = std::chrono::steady_clock;
    StrategyPilot pilot;
    pilot.candidates = strategy_candidates(light_tracing_is_a_candidate(scene));
    pilot.spp = spp;
    const int k = int(pilot.candidates.size());
    const int width = scene.camera.width, height = scene.camera.height;
    // A timed render has no sample count to share: its grid follows its budget (main.cpp gives
    // it a pilot only when the budget is long enough).
    pilot.pixel_stride = spp > 0 ? std::max(1, pilot_stride(width, height, spp, pilot.candidates.size()))
                                    : timed_pilot_stride(width, height, time_budget);
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
    // Sets x and y and pass c (see the header), each from its own seed; x and y share pixel
    // positions. Round robin, so a change of the machine's load hits every candidate alike.
    const uint32_t seed_x = options.seed ^ 0x6a09e667u, seed_y = options.seed ^ 0xbb67ae85u,
                   seed_c = options.seed ^ 0x3c6ef372u;
    std::vector<std::vector<GridPass>> passes(size_t(k), std::vector<GridPass>(kPilotPassesPerCandidate,
                                                                            GridPass(width, height, pilot.pixel_stride)));
    for (int p = 0; p < kPilotPassesPerCandidate; ++p)
        for (int i = 0; i < k; ++i) {
            const StrategyCandidate& c = pilot.candidates[size_t(i)];
            Renderer* r = by_integrator[int(c.integrator)];
            if (c.integrator == Integrator::Bdpt) r->set_strategy_mix(c.light_subpaths, c.inner_connections);
            PassSpec pass;
            pass.pixel_stride = pilot.pixel_stride;
            if (p < 2 * kPilotSetSize) {
                // Sample j of set x or y: the sampler's j-th sample, so that a set is stratified
                // as kPilotSetSize samples of the render are.
                const uint32_t j = uint32_t(p % kPilotSetSize);
                pass.seed = p < kPilotSetSize ? seed_x : seed_y;
                pass.sample_index = pass.position_sample_index = j;
                pass.position_seed = seed_x;
            } else {
                pass.seed = pass.position_seed = seed_c;
            }
            const RenderedItems rendered = r->render_items(pass, 0, items);
            passes[size_t(i)][size_t(p)].add(rendered);
            stats->add_counts(rendered.counts);
        }

    // Each candidate's speed, from kTimingPasses passes of the render's own kind
    // (timing_pass_seconds), round robin; its fastest counts: load from elsewhere (the image I/O
    // process loads its libraries during the pilot) and a first pass's one-off costs only ever
    // add time. With the mean of the grid's passes, a slow pass of full bdpt once handed
    // lamp-ceiling to the mix without inner connections, and a slow pass of pt handed sky to bdpt.
    Film timing_film(width, height);
    std::vector<double> seconds(size_t(k), 1e300);
    for (int round = 0; round < kTimingPasses; ++round)
        for (int i = 0; i < k; ++i) {
            const StrategyCandidate& c = pilot.candidates[size_t(i)];
            Renderer* r = by_integrator[int(c.integrator)];
            if (c.integrator == Integrator::Bdpt) r->set_strategy_mix(c.light_subpaths, c.inner_connections);
            const double s = timing_pass_seconds(*r, seed_c ^ uint32_t(0x510e527f + round), items, &timing_film, stats);
            seconds[size_t(i)] =
                std::min(seconds[size_t(i)], s * double(items) / double(timing_samples(width, height, items)));
        }

    std::vector<SetVariances> transport;
    std::vector<GroupedVariance> whole;
    for (int i = 0; i < k; ++i) {
        transport.push_back(set_variances(passes[size_t(i)], kPilotSetSize, full_per_sparse));
        whole.push_back(one_sample_variance(passes[size_t(i)][0], passes[size_t(i)][2 * kPilotSetSize], full_per_sparse));
    }
    predict_candidates(transport, whole, seconds, items, full_per_sparse, spp, time_budget, adaptive_sampling,
                       &pilot.candidates);
    pilot.chosen = choose_strategy_candidate(pilot.candidates);
    pilot.samples = pilot_samples_at(width, height, pilot.pixel_stride, size_t(k));
    // The renderers' counters (build time, profile; the passes' samples and rays went to `stats`
    // above) move into `stats`, so a renderer that goes on to the main render does not count the
    // pilot twice.
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
