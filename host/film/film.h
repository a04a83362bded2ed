// The film: per-pixel sums of a render's samples in double precision, kept apart by where they
// come from so that passes, devices and resumed renders merge exactly:
//   image = (camera_sum + light_sum) / spp
// camera_sum gathers each pixel's own camera subpaths, light_sum the t = 1 splats that light
// subpaths leave on any pixel. A pass adds one sample of every pixel and one to spp. Pixels that
// adaptive sampling gave extra camera samples divide their camera_sum by spp + their extra, or,
// where those samples were whole estimates of the pixel (path-traced), camera_sum + light_sum.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

namespace clbdpt {

struct Film {
    int width = 0;
    int height = 0;
    int spp = 0;
    std::vector<double> camera_sum;  // rgb per pixel
    std::vector<double> light_sum;   // rgb per pixel, t = 1 splats
    // With strategy images: rgb per pixel for each (s, t), strategy_slot(s, t) major.
    std::vector<double> strategy_sum;
    int strategy_stride = 0;  // max_depth + 3
    // Adaptive sampling (render/adaptive.h). camera_sq: per pixel, the sum over its camera
    // samples of r^2 + g^2 + b^2 (kept when RenderOptions::track_variance is set), from which
    // the pixel's sample variance follows. extra_samples: per pixel, camera samples beyond spp,
    // added to camera_sum (empty: none); the light image keeps spp samples per pixel.
    // camera_rays: per pixel, the rays its camera samples traced (kept with camera_sq), what a
    // sample there costs.
    // camera_late: rgb per pixel, the camera samples of passes late_from and after (kept with
    // camera_sq where the passes are counted beforehand, late_from = half of them), so that
    // adaptive sampling can compare the two halves of a pixel's samples.
    std::vector<double> camera_sq;
    std::vector<double> camera_rays;
    std::vector<double> camera_late;
    uint32_t late_from = 0;
    std::vector<uint32_t> extra_samples;
    // Whether the extra samples are whole estimates of their pixel (a path tracer's, in a bdpt
    // render): the pixel is then the mean of its spp samples (camera_sum and light_sum) and its
    // extra ones alike, (camera_sum + light_sum) / (spp + extra).
    bool extra_samples_whole = false;

    Film() = default;
    Film(int w, int h) : width(w), height(h), camera_sum(size_t(w) * h * 3), light_sum(size_t(w) * h * 3) {}
    void add(const Film& other);  // merges sums and sample counts (another device's passes)
    std::vector<float> image() const;
    // The image of strategy (s, t) alone (sum / spp); requires strategy images.
    std::vector<float> strategy_image(int s, int t) const;
};

}  // namespace clbdpt
