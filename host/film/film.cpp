#include "film/film.h"

namespace clbdpt {

namespace {

// Adds an optional per-pixel array (empty where the film does not keep it) into another,
// which starts at zero if it had none; returns whether there was anything to add.
bool add_kept(std::vector<double>& into, const std::vector<double>& from) {
    if (from.empty()) return false;
    if (into.empty()) into.assign(from.size(), 0.0);
    for (size_t i = 0; i < into.size(); ++i) into[i] += from[i];
    return true;
}

}  // namespace

void Film::add(const Film& other) {
    for (size_t i = 0; i < camera_sum.size(); ++i) camera_sum[i] += other.camera_sum[i];
    for (size_t i = 0; i < light_sum.size(); ++i) light_sum[i] += other.light_sum[i];
    add_kept(camera_sq, other.camera_sq);
    if (add_kept(camera_late, other.camera_late)) late_from = other.late_from;
    add_kept(camera_rays, other.camera_rays);
    if (add_kept(strategy_sum, other.strategy_sum)) strategy_stride = other.strategy_stride;
    spp += other.spp;
}

std::vector<float> Film::image() const {
    std::vector<float> out(camera_sum.size());
    const double inv = spp > 0 ? 1.0 / spp : 0.0;
    if (extra_samples.empty()) {
        for (size_t i = 0; i < out.size(); ++i) out[i] = float((camera_sum[i] + light_sum[i]) * inv);
        return out;
    }
    for (size_t i = 0; i < out.size(); ++i) {
        const double camera_samples = double(spp) + double(extra_samples[i / 3]);
        if (extra_samples_whole)
            out[i] = float(camera_samples > 0 ? (camera_sum[i] + light_sum[i]) / camera_samples : 0.0);
        else
            out[i] = float((camera_samples > 0 ? camera_sum[i] / camera_samples : 0.0) + light_sum[i] * inv);
    }
    return out;
}

std::vector<float> Film::strategy_image(int s, int t) const {
    const size_t pixels = size_t(width) * height;
    const size_t base = (size_t(s) * strategy_stride + t) * pixels * 3;
    std::vector<float> out(pixels * 3);
    const double inv = spp > 0 ? 1.0 / spp : 0.0;
    for (size_t i = 0; i < out.size(); ++i) out[i] = float(strategy_sum[base + i] * inv);
    return out;
}

}  // namespace clbdpt
