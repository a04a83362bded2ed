// Efficiency-aware BDPT (Grittmann, Yazici, Georgiev & Slusallek 2022): a short pilot render
// decides, per scene, how many light subpaths a pixel sample traces and which connections it
// makes (or plain path tracing, or plain light tracing), by estimated variance times cost. The
// default `clbdpt render` (--integrator auto) runs it; --integrator bdpt|pt|lt and
// --light-subpaths / --connections fix the choice by hand.
//
// The pilot renders a sparse grid of pixels (one of each k x k block, about 3072 of them, fewer
// for a short render) nine times per candidate, on the first device, and throws the passes away
// afterwards (they are not stratified with the render's own samples, and adding them would cost
// more than it gives):
//   x, y  two sets of 4 passes, each set the sampler's first 4 samples of a pixel under its own
//         seed, both sets at the same 4 pixel positions: the half squared difference of x_j
//         and y_j estimates the variance of one sample's light transport within the pixel,
//         v_transport; that of the sets' means, times 4, the same for a set of 4 stratified
//         samples;
//   c     a sample at its own pixel position: (x_0 - c)^2 / 2 estimates the whole variance of
//         one sample, of which v_pixel = whole - v_transport comes from where in the pixel it
//         lands (the median over 8 interleaved groups of pixels, so that a firefly in pass c
//         does not pass for edges).
// A stratified sampler removes the parts at different rates. The pixel integral of an image
// with edges (a visible light's outline) is a 2D discontinuous integrand, whose variance under
// Owen-scrambled Sobol points falls as N^-3/2. Of light transport, N samples keep
// A / N + B / N^2 with A + B = v_transport: B, from the set of 4, is what the sampler's
// stratification removes (the smooth parts of the integrand), A what it cannot (fireflies, high
// dimensions); B is the median over the 8 groups, since a firefly's cross terms with the other
// samples of its pixel would pass for it. Fitted on cornell-specular's full films at 1 and 4
// spp, the model predicts the squared error at 64 spp within 12-32%, where one sample's
// variance / N overstates it 2.3x for pt and 4.6x for BDPT without inner connections. So the
// squared error of N samples is predicted as A / N + B / N^2 + v_pixel / N^1.5, and the
// candidate with the least error times time (N x seconds per sample, from its fastest pass) is
// chosen: the inverse of Grittmann et al.'s efficiency. The candidates at the ends (full bdpt,
// pt, lt) run first; where pt or lt leads the others there by kClearLeadMargin, it is chosen
// without the mixes between, which cost 2-3x a path-traced sample each. Where the choice is a
// BDPT mix, the pilot runs the mix once more with Russian roulette in its light subpaths
// (kRouletteLightFromPilot, render/features.h) as one candidate more, and chooses again among
// all. A leaves out the samples that every camera candidate has alike (shared_tail_terms), and
// the pixels where every camera candidate met the same rare path (rare_shared_pixels), counting
// a share of their common part for every camera candidate instead (common_shared_variance), and
// counts two standard errors high, so that a candidate whose fireflies the grid happened to miss
// is not chosen for them (the standard error without the grid's largest terms, which are in A
// already). The mix without inner connections samples some paths by s = 0 alone that full bdpt
// joins by inner connections, rare large samples that its grid meets too seldom: full bdpt's
// passes of set x also return their squared contributions reweighted by the share of the MIS
// weights that mix keeps (subset moments, cl/kernels/render.cl), and what they show beyond the
// mix's own variance counts in its A (variance_missed). The light image
// (t = 1) takes no part in the grid's terms: its variance is estimated from the squares of all
// the splats of the sparse passes' light subpaths, wherever they land (light_image_variance),
// 20-30x more of them than land on the grid, and counted in A.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "render/renderer.h"

namespace clbdpt {

struct StrategyCandidate {
    std::string name;
    Integrator integrator = Integrator::Bdpt;
    float light_subpaths = 1.0f;
    bool inner_connections = true;
    // Russian roulette's first bounce in the light subpaths (kRouletteOff: none).
    int roulette_light_from = kRouletteOff;
    // Per pixel and channel, of one sample: within the pixel (transport) and from the position
    // in the pixel.
    double variance_transport = 0;
    double variance_transport_standard_error = 0;  // over the pilot's pixels
    // The light image's (t = 1) part of variance_transport, from every splat of the pilot's passes.
    double variance_light_image = 0;
    // The part B of variance_transport = A + B that the render's stratified samples remove faster
    // than 1/N: N samples' transport variance is A / N + B / N^2.
    double variance_transport_stratified = 0;
    // The part of variance_transport from the grid's few pixels where every camera candidate has
    // the same large term (shared_tail_terms) or met the same rare path (rare_shared_pixels):
    // left out of the candidate's own terms (see run_strategy_pilot).
    double variance_shared_tail = 0;
    // What the prediction counts instead, the same for every camera candidate: a share of the
    // part common to all (common_shared_variance); 0 for lt.
    double variance_shared_counted = 0;
    double variance_pixel = 0;
    // Without inner connections: the variance its own passes missed, which full bdpt's subset
    // moments show (run_strategy_pilot), counted in the prediction's 1/N part; 0 for the others.
    double variance_missed = 0;
    // With adaptive sampling: the share of the camera image's 1/N transport variance that its
    // extra samples leave, and their number as a share of the render's samples (1 and 0 without).
    double adaptive_variance_left = 1;
    double adaptive_extra_share = 0;
    double seconds_per_pass = 0;    // a full pass, scaled from the sparse ones
    double predicted_spp = 0;       // what the render will reach (given, or from a time budget)
    double predicted_mse = 0;       // of the image at predicted_spp
    // 1 / (predicted squared error x render seconds); 0 when the image is black.
    double efficiency = 0;
    // The same with v_pixel taken as 0: the most a camera candidate can be credited with (lt is
    // weighed against it; see run_strategy_pilot).
    double efficiency_transport_only = 0;
};

// Whether light tracing alone (t = 1) is one of the pilot's candidates: where it renders every
// path, and without the heavy tails that a sparse pilot cannot see. So every material is diffuse
// (a mirror or glass next to the camera joins no light subpath; glossy surfaces seen by the
// camera gave veach-mis 700x pt's squared error, where the pilot had measured lt's variance as
// 0.45 +- 0.35), there is no environment (a camera ray that escapes meets no light subpath) and
// no medium (fog-spot: a firefly of 1 680 in a 64-spp image, 125x the default's squared error).
bool light_tracing_is_a_candidate(const DeviceScene& scene);

// Whether a point, spot or directional light and a mirror or glass are in the scene. Then light
// goes from a delta light by way of a delta reflection or refraction, and two candidates cannot
// make every such path, so their images lack light, which is wrong, not noisy, and their pilot
// passes show no variance for what they miss:
// - pt: its strategies are s = 0 (a camera path that hits an emitter: a delta light cannot be hit)
//   and s = 1 (a light sampled from the camera path's end, which cannot be joined to a delta
//   lobe), so it misses every path whose first vertex after a delta light is a mirror or glass
//   (with a mirror beside point-spot's point light: 13% of the image's light, and the pilot
//   chose pt in 3 seeds of 3);
// - bdpt without inner connections adds t = 1, which joins the light subpath's last vertex to
//   the lens: it misses such light where the camera sees it by way of a mirror or glass too
//   (point light, glass and mirror spheres in cornell-specular's box: some pixels of the spheres
//   10-20% dark).
// Neither is then a candidate, nor does pt take adaptive sampling's extra samples
// (path_traced_extra_samples; they made that scene 0.7% dark), and --integrator pt or
// --connections off warn.
bool delta_light_meets_specular(const DeviceScene& scene);
// What such a scene's left-out candidates cannot do, as the summary and the warnings say it.
constexpr const char* kDeltaLightSpecularShortfall =
    "cannot render light from point, spot or directional lights by way of mirror or glass";

// Why a path tracer alone cannot render the scene as it must be rendered, or "" where it can:
// delta_light_meets_specular, or a point or spot light inside a medium, which gives light
// samples at medium points near the light a 1/r^2 that makes their variance unbounded where camera
// rays pass close by: a sparse grid may meet none of those fireflies (fog-spot: pt chosen in 1
// seed of 36, at 0.05x the default's efficiency); the bdpt mixes weight them against light
// tracing's own samples of the same points.
std::string path_tracing_shortfall(const DeviceScene& scene);

// Which candidates the scene allows besides full bdpt and half its light subpaths.
struct CandidateScope {
    bool without_inner_connections = true;  // !delta_light_meets_specular
    bool path_tracing = true;               // path_tracing_shortfall is ""
    bool light_tracing = false;             // light_tracing_is_a_candidate
};
CandidateScope candidate_scope(const DeviceScene& scene);

// What the pilot can choose from, in its order: full bdpt, half its light subpaths, without inner
// connections, pt, lt (those the scope allows), each with Russian roulette in its light
// subpaths from bounce roulette_light_from (kRouletteOff: none).
std::vector<StrategyCandidate> strategy_candidates(const CandidateScope& scope, int roulette_light_from = kRouletteOff);
std::vector<StrategyCandidate> strategy_candidates(const DeviceScene& scene, int roulette_light_from = kRouletteOff);

// The candidates the scene leaves out and why, for the render's summary, or "".
std::string candidates_left_out(const DeviceScene& scene);

// "bdpt, 0.5 light subpaths per sample, no inner connections", "pt", ...
// With Russian roulette in the light subpaths: ", Russian roulette from light bounce 2".
std::string describe_strategy_mix(Integrator integrator, float light_subpaths, bool inner_connections,
                                  int roulette_light_from = kRouletteOff);

struct StrategyPilot {
    std::vector<StrategyCandidate> candidates;
    int chosen = 0;       // index into candidates
    int spp = 0;          // the render's samples per pixel the errors are predicted for (0: timed)
    int pixel_stride = 1;  // the sparse grid: every pixel_stride-th pixel of every pixel_stride-th row
    uint64_t samples = 0;  // pilot samples, all candidates
    double seconds = 0;    // wall time of the pilot's passes (kernel builds count as builds)
    // The efficiency of the best of the candidates at the ends (full bdpt, pt, lt) over the next
    // (choice_margin), and the candidates between that did not run since it was clear.
    double lead_at_ends = 0;
    std::vector<std::string> skipped;
    // Kept so the main render reuses their kernels and uploaded scene (one per integrator).
    std::vector<std::unique_ptr<Renderer>> renderers;
    const StrategyCandidate& choice() const { return candidates[size_t(chosen)]; }
};

// The index of the candidate with the highest efficiency; light tracing only where its
// efficiency also beats every other candidate's efficiency_transport_only (run_strategy_pilot).
// Candidate 0 when every efficiency is 0 (a black image).
int choose_strategy_candidate(const std::vector<StrategyCandidate>& candidates);

// How far the chosen candidate leads: its efficiency over the highest of the others' (and, for
// lt, over its rival's efficiency_transport_only, which it must beat too); infinite where every
// other is 0.
double choice_margin(const std::vector<StrategyCandidate>& candidates, int chosen);
// The lead of pt or lt over full bdpt (and each other) from which the pilot chooses it without
// running the mixes between (run_strategy_pilot). Measured on the nine bundled scenes (seeds
// 1-8, 64 and 16 spp, 144 pilots that ran every candidate): at 1.2 the ends decided alone in 93,
// and in 87 of them the whole pilot chose the same; in the other 6 it chose a mix that full
// renders measure at 0.10-0.84x of the ends' choice (scripts/pilot_choices' truth: veach-mis,
// half the light subpaths, 0.10x pt; the Cornell box at 16 spp, no inner connections, 0.46x,
// 4 times; sky, no inner connections, 0.84x). Of the 12 that 1.2 decides and 1.5 did not, 10 are
// lamp-ceiling's lt (leads 1.37-1.50; its mixes measure 0.53-0.62x of lt, and the whole pilot
// chose lt too) and 2 the Cornell box's pt (1.27, 1.47). At 1.5 the ends decided alone in 81, at
// 2.0 in 57. Not 1.0: a mix between two ends that nearly tie may beat both (half the light
// subpaths did on cornell-specular, where full bdpt led).
constexpr double kClearLeadMargin = 1.2;

// Where light tracing had the highest efficiency but was not chosen (choose_strategy_candidate):
// one line saying so, with the efficiency it did not beat; else "".
std::string light_tracing_passed_over(const std::vector<StrategyCandidate>& candidates, int chosen);

// Whether the pilot of `candidates` candidates is worth running for a render of `spp` samples per
// pixel: it may cost at most a tenth of the render's samples, on a sparse grid of at least 1024
// pixels (or the whole film, if smaller).
bool strategy_pilot_fits(int width, int height, int spp, size_t candidates);

// The sparse grid's stride for a render of `time_budget` seconds: the full grid (about 3072
// pixels) from 10 s on, proportionally fewer pixels for less, down to 1024 (or the whole film).
int timed_pilot_stride(int width, int height, double time_budget);

// Whether adaptive sampling's extra samples (render/adaptive.h) of a render with the pilot's
// choice are better taken by the path tracer than by the chosen bdpt mix: the extra samples
// refine the camera image only, so where a mix carries a highlight in its light image (t = 1),
// they leave that part of its error as it was (veach-mis, 64 spp, BDPT without inner
// connections: adaptive sampling took the squared error from 0.043 to 0.021, and pt's from
// 0.030 to 0.0034). A path tracer's sample estimates the whole pixel, so with it the pixel
// becomes the mean of all its samples, light image included (film/film.h), and the same render
// reached 0.0046. That holds where the path tracer renders the refined pixels about as well as
// the mix: so only where the pilot found pt at least kPathTracedExtrasMinShare of the chosen
// mix's efficiency, and where bdpt does not use the (1,1) strategy, which carries what a path
// tracer finds by chance (a small light through a thin lens, a light seen through fog). On
// lamp-ceiling with bdpt, whose pt is 50x less efficient, path-traced extra samples took the
// squared error from 1.67e-4 to 2.5e-4.
constexpr double kPathTracedExtrasMinShare = 0.5;
bool path_traced_extra_samples(const std::vector<StrategyCandidate>& candidates, int chosen, bool light_to_lens);

// Per grid pixel, the transport term (one sample's, as in variance_transport) that every camera
// candidate has alike there, where it is among the largest kSharedTailShare of such terms; else
// 0. The candidates' passes use the same seeds, so a path that each samples the same way (on
// cornell-specular: through the mirror onto the glass sphere's caustic, which only the camera
// subpath reaches) comes out as the same sample in each, to within kSharedTailTolerance. Such
// a lone sample raises every candidate's estimate by the same amount: it cannot say which
// candidate is better, yet it flattens the ratios towards the cheapest, and a sparse grid
// catches a handful of them or none (cornell-specular, pass pairs of three seeds: the BDPT
// mixes' transport variance 0.028, 0.0083 and 0.023, of which a few such pixels made 0.021 in the
// first). The prediction leaves them out of each candidate's own terms (a share of them counts for
// all: common_shared_variance); a candidate's own fireflies stay in. camera_terms:
// each camera candidate's terms, all of one length; with fewer than two candidates, all 0.
constexpr double kSharedTailShare = 0.01;
constexpr double kSharedTailTolerance = 0.05;
std::vector<double> shared_tail_terms(const std::vector<const std::vector<double>*>& camera_terms);

// Per grid pixel, whether every camera candidate's term there is at least kRarePathFactor times
// that candidate's mean term: a rare path that the candidates' shared seeds sampled in each of
// them, and that each weights differently (on veach-mis, seed 10031: two pixels of 2 752 held
// 0.51 of the full bdpt mix's 0.78 and 1.33 of pt's 1.87, pt's terms 1.1-4.3x the mix's, beyond
// kSharedTailTolerance). Whether the render meets such a path 100 times or none is beyond what
// a grid that met it once or twice can say, yet its unequal weights decided the choice: pt lost
// to a mix with 0.1-0.45x its efficiency in 3 of 40 seeds on veach-mis, and in 7 of 40 on sky
// (where pt is 1.4-1.6x the mixes). The prediction leaves these pixels out of every camera
// candidate; a candidate's own fireflies (pt's in fog, where the mixes' terms stay small) stay
// in. With a factor of 100, the default chose pt in 40 of 40 seeds on veach-mis and in 39 on
// sky, and kept its choices on cornell-specular, cornell-fog and fog-spot (a BDPT mix in 36 of
// 36 seeds each), lamp-ceiling (lt) and the Cornell box (pt); with 30, fog-spot went to pt once
// in 12; with 300, veach-mis and sky each went to a mix once in 40. With fewer than two camera
// candidates, none.
constexpr double kRarePathFactor = 100.0;
std::vector<bool> rare_shared_pixels(const std::vector<const std::vector<double>*>& camera_terms);

// The variance per sample (per pixel and channel) that every camera candidate has in common at
// the pixels left out above: at a shared-tail pixel its shared term, at a rare shared pixel the
// least of the candidates' terms. Left out whole, it is missed: such paths are real variance of
// every candidate's render, and a part common to all weighs for the cheaper candidates. Counted
// whole, the grid's lone samples of them mislead (cornell-specular went to pt). Measured
// (12 seeds' pilots against full renders at 256², 64 spp, seeds 1-3), the variance that every
// candidate's render had beyond its prediction was 0.0075-0.0079 per sample on cornell-fog, 0.63
// of the grid's mean shared part there (0.0119), and 0.0017-0.0020 on cornell-specular, 0.23 of
// its 0.0087. So kSharedVarianceCounted of it counts for every camera candidate. With 0.25,
// cornell-fog's pilot chose full BDPT (0.66x the mix without inner connections there) in 2 of
// 36 seeds instead of 7, cornell-specular in 0 of 36 instead of 1 (but once in 12 in a later
// run, a near tie that pass timings decide), and no other scene's choices changed in 12 seeds;
// with 0.5, fog-spot went to pt once in 12 and cornell-specular to the mix with half a light
// subpath more often.
constexpr double kSharedVarianceCounted = 0.25;
double common_shared_variance(const std::vector<double>& shared_tail, const std::vector<bool>& rare_paths,
                              const std::vector<const std::vector<double>*>& camera_terms);

// Renders the pilot of every candidate on `device` (stats gain its samples, rays and build
// time) and picks the candidate with the least predicted error x time at `spp` samples, or,
// with time_budget > 0, the least predicted error after that many seconds. With `adaptive`
// (the render gets adaptive sampling, render/adaptive.h) each prediction takes in what the
// plan will do to the candidate's camera image: the plan's tiers from each grid pixel's second
// largest pair term (an outline or a highlight raises it, a lone firefly does not; the plan's
// own rule, a pixel's neighbours, sees nothing on a grid whose pixels are k apart) give the
// share of the camera image's 1/N variance left and the extra samples' cost. pt's predicted
// error at 64 spp over the measured, medians of 4 seeds, before -> after: cornell-box 1.65 ->
// 1.42, veach-mis 9.4 -> 2.5, lamp-ceiling 1.62 -> 1.35; the BDPT mixes' 0.89-1.09 but for
// veach-mis's full BDPT and no-inner mix (0.88 -> 0.45).
// Light tracing must also beat every other candidate's efficiency_transport_only: the light
// image gets no extra samples, and a camera candidate may still be better than predicted (lt:
// within 3-16% on lamp-ceiling).
StrategyPilot run_strategy_pilot(DeviceContext& device, const DeviceScene& scene, const RenderOptions& options,
                                 int spp, double time_budget, bool adaptive, RenderStats* stats);

}  // namespace clbdpt
