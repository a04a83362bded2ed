// Adaptive sampling: after the render's spp passes, extra camera samples for the pixels whose
// neighbourhood is noisiest, where most of an image's squared error sits (at 64 spp, 41% of a
// path-traced Cornell box's in 1% of its pixels, on the light's outline; 98% of veach-mis's in
// 0.5%, on the small lights' glossy reflections).
//
// Which pixels, and how many samples. The variance of pixel p's samples is estimated from its
// spp samples (Film::camera_sq), but p's own plan is made from its eight neighbours' variances
// alone: the second largest of them, u_p, which a lone firefly cannot raise but an edge through
// p, with neighbours on it on both sides, does. So how many samples p gets does not depend on
// p's own samples, and its pixel value, their mean, stays unbiased (with the sobol and
// independent samplers, whose pixels draw independent samples; zsobol shares a sequence
// between neighbours and gets no extra samples). Minimising the image's squared error for a
// number of samples gives each pixel samples in proportion to its standard deviation, so p gets
// spp x 2^k samples in all for the largest k <= max_tier with u_p >= 4^k u_mean, where u_mean
// is u's mean over the image: a pixel of uniform noise gets none. Powers of two keep a pixel's
// sample count a whole number of Sobol's strata. If the extra samples would exceed
// max_extra_share of the render's, u_mean counts twice as high until they do not.
//
// The extra samples of pixel p are its samples spp .. n_p - 1, so they continue its Sobol
// sequence. They add to the camera image only: a bdpt sample's light-image splats (t = 1) are
// left out, so the light image keeps spp samples per pixel and each strategy's estimate its
// own count (the MIS weights of a path still sum to one, so the sum stays unbiased). Extra
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

struct AdaptivePlan {
    int spp = 0;                // the render's samples per pixel
    int max_tier = 0;
    std::vector<uint8_t> tier;  // per pixel: spp x 2^tier samples in all
    uint64_t extra_samples = 0;
    uint64_t pixels_refined = 0;  // pixels with tier > 0
    double u_mean = 0;            // the variance of a pixel of tier 0 and 1 meet at 4 u_mean
};

// The largest and second largest of the values added (0 while there are fewer): the second
// is what one outlier cannot raise.
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
// of what the plan will do (render/strategy_pilot.h): u_p, the second largest of p's eight
// neighbours' variances in an image of w x h per-pixel variances v; then the tiers for a render
// of spp samples per pixel from any per-pixel u.
struct AdaptiveTiers {
    std::vector<uint8_t> tier;
    uint64_t extra_samples = 0;
    uint64_t pixels_refined = 0;
    double u_mean = 0;
};
std::vector<double> adaptive_neighbour_variances(const std::vector<double>& v, int w, int h);
AdaptiveTiers adaptive_tiers(const std::vector<double>& u, int max_tier, int spp, double max_extra_share);

// The plan for a film of spp samples per pixel with camera_sq kept.
constexpr int kAdaptiveMaxTier = 4;
constexpr double kAdaptiveMaxExtraShare = 1.0;
AdaptivePlan plan_adaptive_samples(const Film& film, int max_tier = kAdaptiveMaxTier,
                                   double max_extra_share = kAdaptiveMaxExtraShare);

// Renders the plan's extra samples with `renderer` (whose options give the seed; the passes' own
// or the path tracer) and adds them to the film's camera sums and extra_samples (setting
// extra_samples_whole for the path tracer's); stats gain their samples and rays. `stop`, polled
// between launches, ends it early (Ctrl-C): the samples added so far stay, each pixel's count
// with them, and since when it stops does not depend on any pixel's samples the image stays
// unbiased.
void render_adaptive_samples(Renderer& renderer, const AdaptivePlan& plan, Film& film, RenderStats* stats,
                             const std::function<bool()>& stop = {});

}  // namespace clbdpt
