#include "render/strategy_pilot.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>

#include "render/adaptive.h"

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
// How many standard errors a candidate's transport variance counts high (see the choice), and
// the share of the grid's largest terms its standard error leaves out
// (standard_error_without_largest): 6 of 3072 pixels. Scored by scripts/pilot_choices over 12
// seeds, leaving out 1% took cornell-fog to pt in 3 of 6 seeds (0.5x the mix's efficiency),
// whose fireflies are spread over more pixels; 0.2% kept it on the mix.
constexpr double kRiskStandardErrors = 2.0;
constexpr double kHedgeLeavesOut = 0.002;
// Variance of a 2D discontinuous integrand under Owen-scrambled Sobol points: O(N^-3/2).
constexpr double kPixelVarianceExponent = 1.5;

double seconds_between(std::chrono::steady_clock::time_point a, std::chrono::steady_clock::time_point b) {
    return std::chrono::duration<double>(b - a).count();
}

// Fewer pixels than this (or than the film has) give variance estimates too noisy to choose by.
constexpr int kPilotMinItems = 1024;

uint64_t pilot_samples_at(int width, int height, int stride, size_t candidates) {
    return uint64_t(render_item_count(width, height, stride)) * kPilotPassesPerCandidate * candidates;
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
// sample's rgb; and of the light image, the sums of its splats' squares. The grid alone is kept,
// so the pilot's memory and time do not grow with the film: with a full film per pass (twelve),
// a 2048^2 render's pilot took 7.8 s and the process peaked at 3.3 GB; with the grid, 0.32 s
// and 0.39 GB.
struct GridPass {
    int columns = 0, rows = 0;
    std::vector<double> camera;
    // Over all the pass's splats, wherever they land: their number, the sum of r^2 + g^2 + b^2,
    // and of its square (see LightImageVariance).
    double splats = 0, splat_squares = 0, splat_squares_squared = 0;
    // Where the pass asked for subset moments (RenderedItems::subset_moments): their sums over
    // the pass's items, and the number of items.
    double moment_own = 0, moment_outer = 0, moment_items = 0;

    GridPass(int w, int h, int k) : columns((w + k - 1) / k), rows((h + k - 1) / k), camera(size_t(columns) * rows * 3) {}
    int items() const { return columns * rows; }
    // Another pass of the same grid, pixel by pixel (a set's sum).
    void add(const GridPass& other) {
        for (size_t v = 0; v < camera.size(); ++v) camera[v] += other.camera[v];
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
            if (!r.subset_moments.empty()) {
                moment_own += r.subset_moments[size_t(i) * 2];
                moment_outer += r.subset_moments[size_t(i) * 2 + 1];
                moment_items += 1;
            }
        }
        for (const SplatRecord& s : r.splats) {
            const double q = double(s.r) * s.r + double(s.g) * s.g + double(s.b) * s.b;
            splats += 1;
            splat_squares += q;
            splat_squares_squared += q * q;
        }
    }
};

// The light image's (t = 1) variance per pixel and channel of one full pass, from the splats of
// sparse passes wherever they land. A full pass's light image at a pixel is the sum over its
// items' light subpaths of what each splats there, so its variance is the sum of theirs: about
// the sum of the squared splats, as a pixel receives a splat from a small share of the light
// subpaths. Over the film, that is per item the mean of the squares of its splats (summed over
// their channels), divided by 3 channels. A sparse pass's items trace their light subpaths as
// a full pass's do, so every splat of theirs counts, not only those that land on the grid: on
// veach-mis those were 1/70 of the variance, the rest in splats of glossy highlights that the
// grid's pixels had missed. The standard error takes the splats for independent, their number
// for fixed (an item's few splats rarely land on one pixel).
struct LightImageVariance {
    double mean = 0, standard_error = 0;
};
LightImageVariance light_image_variance(const std::vector<GridPass>& passes) {
    double splats = 0, squares = 0, squares_squared = 0, items = 0;
    for (const GridPass& p : passes) {
        splats += p.splats;
        squares += p.splat_squares;
        squares_squared += p.splat_squares_squared;
        items += p.items();
    }
    LightImageVariance v;
    if (items < 1 || splats < 2) return v;
    v.mean = squares / items / 3.0;
    // The sum of `splats` independent squares has variance splats x their variance.
    const double spread = std::max(0.0, squares_squared - squares * squares / splats) * splats / (splats - 1);
    v.standard_error = std::sqrt(spread) / items / 3.0;
    return v;
}

// Half the squared difference of two sparse passes over the grid's pixels and channels, summed
// into kVarianceGroups interleaved groups of pixels (the grid's pixel number modulo the group
// count, so that each group spans the whole image). A group's mean is the variance of one
// full-density sample. The light image of a sparse pass holds the light subpaths of 1/share of
// the pixels, so its variance is share times that of a full pass.
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

// At one grid pixel, half the squared difference of a's and b's camera values (each scaled by
// `scale`: 1/n for the sums of sets of n passes), summed over the channels.
double difference_term(const GridPass& a, const GridPass& b, int item, double scale) {
    double term = 0;
    for (int c = 0; c < 3; ++c) {
        const size_t i = size_t(item) * 3 + size_t(c);
        const double dc = scale * (a.camera[i] - b.camera[i]);
        term += 0.5 * dc * dc;
    }
    return term;
}

GroupedVariance one_sample_variance(const GridPass& a, const GridPass& b) {
    GroupedVariance v;
    for (int item = 0; item < a.items(); ++item) v.add(item, difference_term(a, b, item, 1.0));
    return v;
}

// The transport variance of one sample, from the pairs (x_j, y_j) of two sets of n passes that
// share their pixel positions (each pair's half squared difference, averaged over the set per
// pixel), and that of a set's mean times n (half the squared difference of the two sets' means,
// times n), so that both are per sample. `passes`: set x, then set y.
struct SetVariances {
    GroupedVariance one, set;
    std::vector<double> one_terms;  // `one`'s term of each grid pixel
    // Per grid pixel, the second largest of its n pairs' terms: high where the pixel's variance
    // is (an outline, a highlight), not where one sample was a firefly.
    std::vector<double> second_pair_terms;
};
SetVariances set_variances(const std::vector<GridPass>& passes, int n) {
    const GridPass* x = passes.data();
    const GridPass* y = passes.data() + n;
    GridPass x_sum = x[0], y_sum = y[0];
    for (int j = 1; j < n; ++j) {
        x_sum.add(x[j]);
        y_sum.add(y[j]);
    }
    SetVariances v;
    for (int item = 0; item < x_sum.items(); ++item) {
        double one = 0;
        LargestTwo pairs;
        for (int j = 0; j < n; ++j) {
            const double term = difference_term(x[j], y[j], item, 1.0);
            one += term;
            pairs.add(term);
        }
        v.second_pair_terms.push_back(pairs.second);
        v.one.add(item, one / n);
        v.one_terms.push_back(one / n);
        v.set.add(item, n * difference_term(x_sum, y_sum, item, 1.0 / n));
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

// The standard error of the mean of `terms` (one per grid pixel) as GroupedVariance gives it,
// from all but the largest `leave_out` share of them (at least one). What the hedge guards
// against is a candidate whose fireflies the grid missed; with the grid's largest terms in, its
// standard error grew with the very fireflies the grid had seen, which are in the mean already:
// on veach-mis (seed 3) pt's hedge was 0.019 of its predicted 0.036 where its image measured
// 0.0048, and the default chose a BDPT mix with 0.1-0.2x pt's efficiency in half the seeds.
double standard_error_without_largest(std::vector<double> terms, double leave_out) {
    std::sort(terms.begin(), terms.end());
    const size_t dropped = std::max<size_t>(1, size_t(double(terms.size()) * leave_out));
    GroupedVariance kept;
    for (size_t i = 0; i + dropped < terms.size(); ++i) kept.add(int(i), terms[i]);
    return kept.standard_error();
}

// What adaptive sampling would do to a candidate's camera image (run_strategy_pilot): the plan's
// tiers (render/adaptive.h) from the grid's per-pixel `u`, applied to its per-pixel variances of
// one sample, `terms`, for a render of spp samples per pixel whose light image has per-pixel
// variance light_variance per sample (which camera-only extra samples leave as it is).
struct AdaptiveEffect {
    double variance_left = 1.0;  // share of the terms' sum that the extra samples leave
    double extra_share = 0.0;    // extra samples per sample of the render
};
AdaptiveEffect adaptive_effect(const std::vector<double>& terms, const std::vector<double>& u, int spp,
                               double light_variance) {
    AdaptiveEffect e;
    double sum = 0;
    for (double t : terms) sum += t;
    if (!(sum > 0) || spp < kAdaptiveMinSpp || u.size() != terms.size()) return e;
    const AdaptiveTiers tiers = adaptive_tiers(u, kAdaptiveMaxTier, spp, kAdaptiveMaxExtraShare,
                                               light_variance * double(terms.size()) / spp);
    double left = 0;
    for (size_t p = 0; p < terms.size(); ++p) left += terms[p] / double(1u << tiers.tier[p]);
    e.variance_left = left / sum;
    e.extra_share = double(tiers.extra_samples) / (double(spp) * double(terms.size()));
    return e;
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
    for (const Material& m : materials_in_use(scene))
        if (m.kind != MATERIAL_DIFFUSE) return false;
    for (const Light& l : scene.lights)
        if (l.kind == LIGHT_ENVIRONMENT) return false;
    return true;
}

bool delta_light_meets_specular(const DeviceScene& scene) {
    const bool delta_light = std::any_of(scene.lights.begin(), scene.lights.end(), [](const Light& l) {
        return l.kind == LIGHT_POINT || l.kind == LIGHT_SPOT || l.kind == LIGHT_DIRECTIONAL;
    });
    return delta_light && has_specular_surfaces(scene);
}

std::string path_tracing_shortfall(const DeviceScene& scene) {
    if (delta_light_meets_specular(scene)) return std::string("it ") + kDeltaLightSpecularShortfall;
    for (const Light& l : scene.lights)
        if ((l.kind == LIGHT_POINT || l.kind == LIGHT_SPOT) && l.medium != 0)
            return "its variance near a point or spot light inside a medium is unbounded";
    return "";
}

CandidateScope candidate_scope(const DeviceScene& scene) {
    CandidateScope scope;
    scope.without_inner_connections = !delta_light_meets_specular(scene);
    scope.path_tracing = path_tracing_shortfall(scene).empty();
    scope.light_tracing = light_tracing_is_a_candidate(scene);
    return scope;
}

std::vector<StrategyCandidate> strategy_candidates(const CandidateScope& scope, int roulette_light_from) {
    // Full bdpt; half the light subpaths (they cost as much as the camera subpath but pay off
    // only where light arrives indirectly); path tracing plus light tracing (caustics seen
    // directly, without the connections' cost); path tracing alone, with its own leaner kernel;
    // and light tracing alone, as lean (a lamp aimed at the ceiling: 1.4x bdpt's efficiency,
    // whose camera subpaths and connections add little there); the last three where the scene
    // allows them (candidate_scope).
    // (A quarter of the light subpaths was a candidate too; it won on none of the bundled
    // scenes, so its pilot time is saved.)
    std::vector<StrategyCandidate> c(2);
    c[0].light_subpaths = 1.0f;
    c[1].light_subpaths = 0.5f;
    if (scope.without_inner_connections) c.emplace_back().inner_connections = false;
    if (scope.path_tracing) c.emplace_back().integrator = Integrator::Pt;
    if (scope.light_tracing) c.emplace_back().integrator = Integrator::Lt;
    for (StrategyCandidate& s : c) {
        s.roulette_light_from = roulette_light_from;
        s.name = describe_strategy_mix(s.integrator, s.light_subpaths, s.inner_connections, roulette_light_from);
    }
    return c;
}

std::vector<StrategyCandidate> strategy_candidates(const DeviceScene& scene, int roulette_light_from) {
    return strategy_candidates(candidate_scope(scene), roulette_light_from);
}

std::string candidates_left_out(const DeviceScene& scene) {
    const std::string pt = path_tracing_shortfall(scene);
    if (pt.empty()) return "";
    if (!delta_light_meets_specular(scene)) return "pt left out: " + pt;
    return std::string("pt and bdpt without inner connections left out: they ") + kDeltaLightSpecularShortfall;
}

std::string describe_strategy_mix(Integrator integrator, float light_subpaths, bool inner_connections,
                                  int roulette_light_from) {
    const std::string roulette =
        roulette_light_from < kRouletteOff && integrator != Integrator::Pt && light_subpaths > 0.0f
            ? ", Russian roulette from light bounce " + std::to_string(roulette_light_from)
            : "";
    if (integrator != Integrator::Bdpt) return integrator_name(integrator) + roulette;
    if (light_subpaths == 0.0f) return "bdpt without light subpaths (path tracing)";
    char buf[128];
    std::snprintf(buf, sizeof buf, "bdpt, %g light subpath%s per sample%s", double(light_subpaths),
                  light_subpaths == 1.0f ? "" : "s", inner_connections ? "" : ", no inner connections");
    return buf + roulette;
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

double choice_margin(const std::vector<StrategyCandidate>& candidates, int chosen) {
    const StrategyCandidate& c = candidates[size_t(chosen)];
    double runner_up = 0;
    for (int i = 0; i < int(candidates.size()); ++i)
        if (i != chosen) runner_up = std::max(runner_up, candidates[size_t(i)].efficiency);
    if (c.integrator == Integrator::Lt)
        if (const StrategyCandidate* rival = lt_rival(candidates))
            runner_up = std::max(runner_up, rival->efficiency_transport_only);
    return runner_up > 0 ? c.efficiency / runner_up : INFINITY;
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

std::vector<bool> rare_shared_pixels(const std::vector<const std::vector<double>*>& camera_terms) {
    const size_t items = camera_terms.empty() ? 0 : camera_terms[0]->size();
    std::vector<bool> rare(items, false);
    if (camera_terms.size() < 2 || items == 0) return rare;
    std::vector<double> thresholds;
    for (const std::vector<double>* terms : camera_terms) {
        double sum = 0;
        for (double v : *terms) sum += v;
        thresholds.push_back(kRarePathFactor * sum / double(items));
    }
    for (size_t item = 0; item < items; ++item) {
        bool in_every = true;
        for (size_t c = 0; c < camera_terms.size() && in_every; ++c)
            in_every = (*camera_terms[c])[item] > thresholds[c];
        rare[item] = in_every;
    }
    return rare;
}

double common_shared_variance(const std::vector<double>& shared_tail, const std::vector<bool>& rare_paths,
                              const std::vector<const std::vector<double>*>& camera_terms) {
    if (camera_terms.empty()) return 0.0;
    // Per pixel and channel, as the candidates' variances are.
    GroupedVariance common;
    for (size_t item = 0; item < shared_tail.size(); ++item) {
        double shared = shared_tail[item];
        if (rare_paths[item]) {
            shared = (*camera_terms[0])[item];
            for (const std::vector<double>* terms : camera_terms) shared = std::min(shared, (*terms)[item]);
        }
        common.add(int(item), shared);
    }
    return common.mean();
}

// Whether `c` is full bdpt: one light subpath per sample and every connection.
bool is_full_bdpt(const StrategyCandidate& c) {
    return c.integrator == Integrator::Bdpt && c.light_subpaths == 1.0f && c.inner_connections;
}

// Whether `c` is bdpt without inner connections at one light subpath per sample (with or
// without light roulette).
bool is_without_inner_connections(const StrategyCandidate& c) {
    return c.integrator == Integrator::Bdpt && c.light_subpaths == 1.0f && !c.inner_connections;
}

StrategyPilot run_strategy_pilot(DeviceContext& device, const DeviceScene& scene, const RenderOptions& options,
                                 int spp, double time_budget, bool adaptive, RenderStats* stats) {
    using Clock = std::chrono::steady_clock;
    StrategyPilot pilot;
    // Light roulette as the command line fixed it (with auto, none until tried below).
    pilot.candidates = strategy_candidates(scene, options.roulette_light_from);
    pilot.spp = spp;
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
    // positions.
    const uint32_t seed_x = options.seed ^ 0x6a09e667u, seed_y = options.seed ^ 0xbb67ae85u,
                   seed_c = options.seed ^ 0x3c6ef372u;
    std::vector<std::vector<GridPass>> passes;
    // Each candidate's fastest pass: load from elsewhere and a first pass's one-off costs only
    // ever add time, and a pass lasts 5-50 ms. With the mean of the three, a slow pass of full
    // bdpt once handed lamp-ceiling to the mix without inner connections, and a slow pass of pt
    // handed sky to bdpt. (The image I/O process, which loads its libraries meanwhile, is stopped
    // during the pilot: ImageIoProcessPause, film/image_io_process.h.)
    std::vector<double> seconds;
    // The passes of the candidates `which` (indices). Round robin, so a change of the machine's
    // load hits every candidate alike.
    auto run_passes = [&](const std::vector<int>& which) {
        const size_t end = pilot.candidates.size();
        passes.resize(end, std::vector<GridPass>(kPilotPassesPerCandidate, GridPass(width, height, pilot.pixel_stride)));
        seconds.resize(end, 1e300);
        for (int round = 0; round < kPilotPassesPerCandidate; ++round)
            for (int i : which) {
                const StrategyCandidate& c = pilot.candidates[size_t(i)];
                Renderer* r = by_integrator[int(c.integrator)];
                if (c.integrator == Integrator::Bdpt) r->set_strategy_mix(c.light_subpaths, c.inner_connections);
                r->set_light_roulette(c.roulette_light_from);
                PassSpec pass;
                pass.pixel_stride = pilot.pixel_stride;
                // Full bdpt's set x also brings the subset moments (kernel time not counted:
                // their MIS sums skip the subpaths' tails, 7% of a pass on cornell-specular).
                pass.subset_moments = is_full_bdpt(c) && round < kPilotSetSize;
                if (round < 2 * kPilotSetSize) {
                    // Sample j of set x or y: the sampler's j-th sample, so that a set is
                    // stratified as kPilotSetSize samples of the render are.
                    const uint32_t j = uint32_t(round % kPilotSetSize);
                    pass.seed = round < kPilotSetSize ? seed_x : seed_y;
                    pass.sample_index = pass.position_sample_index = j;
                    pass.position_seed = seed_x;
                } else {
                    pass.seed = pass.position_seed = seed_c;
                }
                const Clock::time_point pass_start = Clock::now();
                const RenderedItems rendered = r->render_items(pass, 0, items);
                if (!pass.subset_moments)
                    seconds[size_t(i)] = std::min(seconds[size_t(i)], seconds_between(pass_start, Clock::now()));
                passes[size_t(i)][size_t(round)].add(rendered);
                stats->add_counts(rendered.counts);
            }
    };
    // What the passes of the mix without inner connections (one light subpath per sample, light
    // roulette as full bdpt's) missed of its variance, from full bdpt's subset moments: their
    // outer part less full bdpt's own is what the mix adds to full bdpt's variance for the same
    // paths, among them those that only inner connections sample well (a caustic's light on a
    // wall seen through glass: the mix has s = 0 alone for them, whose rare large samples a
    // sparse grid meets too seldom; on cornell-specular its passes measured 1.0-1.2x full
    // bdpt's variance, where its renders have 1.2x the error of half the light subpaths').
    // 0 unless both ran (`which`), and where the mix's own passes saw as much.
    auto missed_without_inner_connections = [&](const std::vector<int>& which, const std::vector<SetVariances>& transport) {
        int full = -1, outer = -1;
        for (int i : which) {
            const StrategyCandidate& c = pilot.candidates[size_t(i)];
            if (c.roulette_light_from != options.roulette_light_from) continue;
            if (is_full_bdpt(c)) full = i;
            if (is_without_inner_connections(c)) outer = i;
        }
        if (full < 0 || outer < 0) return 0.0;
        double own = 0, outer_moment = 0, items = 0;
        for (const GridPass& p : passes[size_t(full)]) {
            own += p.moment_own;
            outer_moment += p.moment_outer;
            items += p.moment_items;
        }
        if (items <= 0) return 0.0;
        const double added = std::max(0.0, outer_moment - own) / (3.0 * items);
        auto transport_variance = [&](int i) {
            return transport[size_t(i)].one.mean() + light_image_variance(passes[size_t(i)]).mean;
        };
        return std::max(0.0, transport_variance(full) + added - transport_variance(outer));
    };
    // The variances, predicted error and efficiency of the candidates `which` (those whose
    // passes ran), from their passes.
    auto evaluate = [&](const std::vector<int>& which) {
        std::vector<SetVariances> transport(pilot.candidates.size());
        for (int i : which) transport[size_t(i)] = set_variances(passes[size_t(i)], kPilotSetSize);
        std::vector<const std::vector<double>*> camera_terms;
        for (int i : which)
            if (pilot.candidates[size_t(i)].integrator != Integrator::Lt)
                camera_terms.push_back(&transport[size_t(i)].one_terms);
        const std::vector<double> shared_tail = shared_tail_terms(camera_terms);
        const std::vector<bool> rare_paths = rare_shared_pixels(camera_terms);
        const double shared_counted = kSharedVarianceCounted * common_shared_variance(shared_tail, rare_paths, camera_terms);
        const double missed_without_inner = missed_without_inner_connections(which, transport);

        for (int i : which) {
            StrategyCandidate& c = pilot.candidates[size_t(i)];
            const std::vector<GridPass>& f = passes[size_t(i)];
            const SetVariances& t = transport[size_t(i)];
            const GroupedVariance whole = one_sample_variance(f[0], f[2 * kPilotSetSize]);
            const LightImageVariance light = light_image_variance(f);
            c.variance_light_image = light.mean;
            c.variance_transport = t.one.mean() + light.mean;
            c.variance_transport_standard_error = std::hypot(t.one.standard_error(), light.standard_error);
            // N x (variance of N samples' mean) = A + B / N: B is what stratification removes
            // faster than 1/N. From N = 1 and N = kPilotSetSize.
            const double n_set = kPilotSetSize;
            c.variance_transport_stratified =
                std::min(c.variance_transport, median_group_difference(t.one, t.set) * n_set / (n_set - 1.0));
            // The candidate's own terms, less the shared tail and the rare shared paths; lt's terms
            // were not compared (it has no camera subpath): it keeps them all.
            std::vector<double> own_terms = t.one_terms;
            if (c.integrator != Integrator::Lt)
                for (size_t item = 0; item < size_t(items); ++item)
                    own_terms[item] = rare_paths[item] ? 0.0 : own_terms[item] - shared_tail[item];
            GroupedVariance own;
            for (int item = 0; item < items; ++item) own.add(item, own_terms[size_t(item)]);
            const double own_hedge_error = standard_error_without_largest(own_terms, kHedgeLeavesOut);
            c.variance_shared_tail = t.one.mean() - own.mean();
            if (c.integrator != Integrator::Lt) c.variance_shared_counted = shared_counted;
            c.variance_pixel = pixel_variance(whole, t.one);
            if (is_without_inner_connections(c)) c.variance_missed = missed_without_inner;
            c.seconds_per_pass = seconds[size_t(i)] * full_per_sparse;
            const double n = time_budget > 0 && c.seconds_per_pass > 0 ? std::max(1.0, time_budget / c.seconds_per_pass)
                                                                        : double(std::max(spp, 1));
            c.predicted_spp = n;
            // With adaptive sampling, what its plan leaves of the camera image's 1/N variance, for
            // what extra samples (their time counts). The share is of the candidate's own terms,
            // those it is applied to below, without the pixels left out above (which the plan
            // rarely refines: a lone large sample does not raise its pixel's second pair term).
            if (adaptive && spp > 0) {
                const AdaptiveEffect a = adaptive_effect(own_terms, t.second_pair_terms, spp, light.mean);
                c.adaptive_variance_left = a.variance_left;
                c.adaptive_extra_share = a.extra_share;
            }
            // Heavy tails (a path tracer's fireflies in fog) make a sparse grid's variance come out
            // low more often than high, and a candidate chosen for a variance it does not have can
            // cost 25x (without this, fog-spot at 128x128 got pt, 0.04-0.07x of bdpt's efficiency
            // there, in one of three pilots); so the part of each transport variance that falls as
            // 1/N (less the shared tail) counts kRiskStandardErrors standard errors high.
            const double risky_transport =
                std::max(0.0, (own.mean() - c.variance_transport_stratified) * c.adaptive_variance_left + light.mean) +
                c.variance_shared_counted + c.variance_missed +
                kRiskStandardErrors * std::hypot(own_hedge_error, light.standard_error);
            const double transport_mse = risky_transport / n + c.variance_transport_stratified / (n * n);
            c.predicted_mse = transport_mse + c.variance_pixel / std::pow(n, kPixelVarianceExponent);
            const double seconds = n * c.seconds_per_pass * (1.0 + c.adaptive_extra_share);
            const double cost = c.predicted_mse * seconds;
            c.efficiency = cost > 0 ? 1.0 / cost : 0.0;
            const double transport_cost = transport_mse * seconds;
            c.efficiency_transport_only = transport_cost > 0 ? 1.0 / transport_cost : 0.0;
        }
    };
    auto every_candidate = [&]() {
        std::vector<int> all(pilot.candidates.size());
        for (int i = 0; i < int(all.size()); ++i) all[size_t(i)] = i;
        return all;
    };
    // First the candidates at the ends: full bdpt, pt and lt (those the scene allows). Where pt
    // or lt leads full bdpt (and the other) by kClearLeadMargin, it is chosen without the
    // mixes between (half the light subpaths; no inner connections), which cost 2-3x a
    // path-traced sample each and so most of the pilot's time there; else they run too, and the
    // choice is among all, as if all had run at once.
    std::vector<int> ends, between;
    for (int i = 0; i < int(pilot.candidates.size()); ++i) {
        const StrategyCandidate& c = pilot.candidates[size_t(i)];
        (is_full_bdpt(c) || c.integrator != Integrator::Bdpt ? ends : between).push_back(i);
    }
    run_passes(ends);
    evaluate(ends);
    std::vector<StrategyCandidate> at_ends;
    for (int i : ends) at_ends.push_back(pilot.candidates[size_t(i)]);
    const int end_choice = choose_strategy_candidate(at_ends);
    pilot.lead_at_ends = choice_margin(at_ends, end_choice);
    if (!between.empty() && (options.pilot_every_candidate ||
                             at_ends[size_t(end_choice)].integrator == Integrator::Bdpt ||
                             pilot.lead_at_ends < kClearLeadMargin)) {
        run_passes(between);
        evaluate(every_candidate());
    } else {
        // The mixes between did not run: the pilot's candidates are those that did.
        for (int i : between) pilot.skipped.push_back(pilot.candidates[size_t(i)].name);
        std::vector<std::vector<GridPass>> ran;
        std::vector<double> ran_seconds;
        for (int i : ends) {
            ran.push_back(std::move(passes[size_t(i)]));
            ran_seconds.push_back(seconds[size_t(i)]);
        }
        pilot.candidates = at_ends;
        passes = std::move(ran);
        seconds = std::move(ran_seconds);
    }
    const int k = int(pilot.candidates.size());
    pilot.chosen = choose_strategy_candidate(pilot.candidates);
    // Russian roulette in the light subpaths of the chosen bdpt mix, tried as one candidate more:
    // it paid 1.25x on cornell-specular, whose light subpaths serve the caustics alone, but it
    // would thin out light that light subpaths carry (the light tracer on lamp-ceiling: 0.88x).
    if (options.roulette_light_by_pilot && pilot.choice().integrator == Integrator::Bdpt &&
        pilot.choice().light_subpaths > 0.0f) {
        StrategyCandidate c = pilot.choice();
        c.roulette_light_from = kRouletteLightFromPilot;
        c.name = describe_strategy_mix(c.integrator, c.light_subpaths, c.inner_connections, c.roulette_light_from);
        pilot.candidates.push_back(c);
        run_passes({k});
        evaluate(every_candidate());
        pilot.chosen = choose_strategy_candidate(pilot.candidates);
    }
    pilot.samples = uint64_t(items) * kPilotPassesPerCandidate * pilot.candidates.size();
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
