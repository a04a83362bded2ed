#include "film/film.h"

namespace clbdpt {

void Film::add(const Film& other) {
    for (size_t i = 0; i < camera_sum.size(); ++i) camera_sum[i] += other.camera_sum[i];
    for (size_t i = 0; i < light_sum.size(); ++i) light_sum[i] += other.light_sum[i];
    if (!other.camera_sq.empty()) {
        if (camera_sq.empty()) camera_sq.assign(other.camera_sq.size(), 0.0);
        for (size_t i = 0; i < camera_sq.size(); ++i) camera_sq[i] += other.camera_sq[i];
    }
    if (!other.camera_late.empty()) {
        if (camera_late.empty()) camera_late.assign(other.camera_late.size(), 0.0);
        for (size_t i = 0; i < camera_late.size(); ++i) camera_late[i] += other.camera_late[i];
        late_from = other.late_from;
    }
    if (!other.camera_rays.empty()) {
        if (camera_rays.empty()) camera_rays.assign(other.camera_rays.size(), 0.0);
        for (size_t i = 0; i < camera_rays.size(); ++i) camera_rays[i] += other.camera_rays[i];
    }
    if (!other.strategy_sum.empty()) {
        if (strategy_sum.empty()) {
            strategy_sum.assign(other.strategy_sum.size(), 0.0);
            strategy_stride = other.strategy_stride;
        }
        for (size_t i = 0; i < strategy_sum.size(); ++i) strategy_sum[i] += other.strategy_sum[i];
    }
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
