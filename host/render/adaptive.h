// Adaptive sampling: after the render's spp passes, extra camera samples for the pixels whose
// neighbourhood is noisiest, where most of an image's squared error sits (at 64 spp, 41% of a
// path-traced Cornell box's in 1% of its pixels, on the light's outline; 98% of veach-mis's in
// 0.5%, on the small lights' glossy reflections).
//
// Which pixels. The variance of pixel p's samples is estimated from its spp samples
// (Film::camera_sq), but p's own plan is made from its neighbours' variances alone: u_p, their
// mean over the (2 kAdaptiveRadius + 1)^2 window around p, p left out. So how many samples p
// gets does not depend on p's own samples, and its pixel value, their mean, stays unbiased
// (with the sobol and independent samplers, whose pixels draw independent samples; zsobol
// shares a sequence between neighbours and gets no extra samples). A window of 80 neighbours
// rather than the eight next to p: the noise that pays for extra samples is often made of rare
// large samples (caustics seen through glass, glossy reflections of small lights), which a
// pixel's 64 samples catch or miss by chance, so a region's variance shows in the mean over
// many pixels far better than in any one of them. And no more than the window's mean of the
// variance its pixels' two halves of samples show (the difference of the means of samples
// before and after half the passes): on an outline, samples on and off a bright light spread
// widely, but Sobol's strata pin down their mean, and the halves agree.
//
// How many samples. Minimising the image's squared error for a given time gives each pixel
// samples in proportion to its standard deviation over the square root of what a sample there
// costs (c_p: the rays per sample of p's window, p left out again, relative to the image's
// mean). So p gets spp x 2^k samples in all for the largest k <= max_tier with
// u_p / c_p >= 4^k base (powers of two keep a pixel's sample count a whole number of Sobol's
// strata). The base is the one of the least predicted variance x time,
// (sum_p u_p / n_p + what the extra samples cannot lower) x sum_p n_p c_p, among bases a
// factor sqrt 2 apart from the largest u_p / c_p (no extra samples) down, as long as the extra
// samples stay within max_extra_share of the render's; a base with more extra samples must
// predict kAdaptiveMinGain less than the best before it. So a film of uniform noise gets none,
// and one whose noise sits in a few regions gets as many as pay for their time.
//
// The extra samples of pixel p are its samples spp .. n_p - 1, so they continue its Sobol
// sequence. They add to the camera image only: a bdpt sample's light-image splats (t = 1) are
// left out, so the light image keeps spp samples per pixel and each strategy's estimate its
// own count (the MIS weights of a path still sum to one, so the sum stays unbiased); a mix
// without inner connections traces no light subpaths for them (PassSpec::camera_image_only). Extra
// samples rendered by the path tracer are whole estimates of the pixel instead: the pixel is
// then the mean of all its samples, its passes' light image counted as theirs (the default does
// this for a bdpt mix where the pilot found pt close, render/strategy_pilot.h).
#pragma once

#include <cstdint>
#include <functional>
#include <vector>

#include "film/film.h"
#include "render/renderer.h"

namespace clbdpt {

// Renders of fewer samples per pixel get no extra samples: their variance estimates are too rough.
constexpr int kAdaptiveMinSpp = 8;

// The radius of the window whose mean variance plans a pixel's samples, and the predicted gain
// in variance x samples that a plan with more extra samples must bring.
constexpr int kAdaptiveRadius = 4;
constexpr double kAdaptiveMinGain = 0.01;

struct AdaptivePlan {
    int spp = 0;                // the render's samples per pixel
    int max_tier = 0;
    std::vector<uint8_t> tier;  // per pixel: spp x 2^tier samples in all
    uint64_t extra_samples = 0;
    uint64_t pixels_refined = 0;  // pixels with tier > 0
    double u_mean = 0;            // the base: the u of a pixel of tier 0 and 1 meet at 4 u_mean
};

// The largest and second largest of the values added (0 while there are fewer): the second
// is what one outlier cannot raise (the strategy pilot's stand-in for a pixel's u).
struct LargestTwo {
    double first = 0, second = 0;
    void add(double value) {
        if (value > first) {
            second = first;
            first = value;
        } else if (value > second) {
            second = value;
        }
    }
};

// The rule above in two steps, for plan_adaptive_samples and for the strategy pilot's prediction
// of what the plan will do (render/strategy_pilot.h): the mean of v over the window around each
// pixel of a w x h image, the pixel left out and the window clipped at the image's edges (u_p
// from per-pixel variances, c_p from per-pixel rays); then the tiers for a render of spp
// samples per pixel from any per-pixel u.
struct AdaptiveTiers {
    std::vector<uint8_t> tier;
    uint64_t extra_samples = 0;
    uint64_t pixels_refined = 0;
    double u_mean = 0;
};
std::vector<double> adaptive_window_means(const std::vector<double>& v, int w, int h);
// fixed_variance: the variance of the image that extra samples leave as it is (a bdpt film's
// light image under camera-only extra samples), summed over pixels and channels, which the
// prediction adds to the camera image's sum_p u_p / n_p. cost: per pixel, what a sample there
// costs (its neighbourhood's rays per sample; empty: the same everywhere).
AdaptiveTiers adaptive_tiers(const std::vector<double>& u, int max_tier, int spp, double max_extra_share,
                             double fixed_variance = 0.0, const std::vector<double>& cost = {});

// The plan for a film of spp samples per pixel with camera_sq kept. camera_only_extras: the extra
// samples will add to the camera image alone (those of the passes' own bdpt or lt renderer), so
// the film's light image keeps its variance (estimated from its pixels' differences from their
// neighbours); path-traced extra samples are whole estimates, which dilute it.
constexpr int kAdaptiveMaxTier = 4;
constexpr double kAdaptiveMaxExtraShare = 1.0;
AdaptivePlan plan_adaptive_samples(const Film& film, int max_tier = kAdaptiveMaxTier,
                                   double max_extra_share = kAdaptiveMaxExtraShare, bool camera_only_extras = false);

// Renders the plan's extra samples with `renderer` (whose options give the seed; the passes' own
// or the path tracer) and adds them to the film's camera sums and extra_samples (setting
// extra_samples_whole for the path tracer's); stats gain their samples and rays. `stop`, polled
// between launches, ends it early (Ctrl-C): the samples added so far stay, each pixel's count
// with them, and since when it stops does not depend on any pixel's samples the image stays
// unbiased.
void render_adaptive_samples(Renderer& renderer, const AdaptivePlan& plan, Film& film, RenderStats* stats,
                             const std::function<bool()>& stop = {});

}  // namespace clbdpt
