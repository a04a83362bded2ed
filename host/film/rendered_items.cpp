#include "film/rendered_items.h"

#include <algorithm>
#include <thread>

namespace clbdpt {

namespace {

// Items [begin, end) of `items` whose pixels are consecutive, from `first_pixel` on.
struct PixelSegment {
    int begin, end;
    int first_pixel;
};

// The items as segments of consecutive pixels: a whole pass or a part of one is a single
// segment; a run of pixels (PassSpec::run_length) one segment per time it goes through them.
// Empty for a sparse pass (pixel_stride > 1) or listed pixels, whose items' pixels are scattered.
std::vector<PixelSegment> pixel_segments(const RenderedItems& items) {
    std::vector<PixelSegment> segments;
    if (items.run_pixels) return segments;
    if (items.run_length > 0) {
        for (int i = 0; i < items.item_count;) {
            const int in_run = (items.first_item + i) % items.run_length;
            const int end = std::min(items.item_count, i + items.run_length - in_run);
            segments.push_back({i, end, items.run_pixel + in_run});
            i = end;
        }
    } else if (items.pixel_stride == 1) {
        segments.push_back({0, items.item_count, items.first_item});
    }
    return segments;
}

void add_camera_value(Film& film, const RenderedItems& items, int item, int pixel) {
    double* dst = &film.camera_sum[size_t(pixel) * 3];
    const float* c = &items.camera[size_t(item) * 3];
    dst[0] += c[0];
    dst[1] += c[1];
    dst[2] += c[2];
    if (!film.camera_sq.empty())
        film.camera_sq[size_t(pixel)] += double(c[0]) * c[0] + double(c[1]) * c[1] + double(c[2]) * c[2];
    if (!film.camera_rays.empty() && !items.rays.empty()) film.camera_rays[size_t(pixel)] += items.rays[size_t(item)];
    if (film.camera_late.empty()) return;
    // The item's sample: a run's items go through its pixels once per sample.
    const uint32_t sample =
        items.sample_index + (items.run_length > 0 ? uint32_t((items.first_item + item) / items.run_length) : 0u);
    if (sample >= film.late_from) {
        double* late = &film.camera_late[size_t(pixel) * 3];
        late[0] += c[0];
        late[1] += c[1];
        late[2] += c[2];
    }
}

// Adds the camera values and splats that land on pixels [lo, hi), in item order: each pixel's
// sums see the same additions in the same order as when one thread adds everything.
void add_pixel_band(Film& film, const RenderedItems& items, const std::vector<PixelSegment>& segments, int lo, int hi) {
    for (const PixelSegment& s : segments) {
        const int begin = s.begin + std::max(0, lo - s.first_pixel);
        const int end = std::min(s.end, s.begin + (hi - s.first_pixel));
        auto dropped = std::lower_bound(items.dropped_items.begin(), items.dropped_items.end(), begin);
        for (int i = begin; i < end; ++i) {
            if (dropped != items.dropped_items.end() && *dropped == i) {
                ++dropped;
                continue;
            }
            add_camera_value(film, items, i, s.first_pixel + (i - s.begin));
        }
    }
    for (const SplatRecord& s : items.splats) {
        if (s.pixel < lo || s.pixel >= hi) continue;
        double* light = &film.light_sum[size_t(s.pixel) * 3];
        light[0] += s.r;
        light[1] += s.g;
        light[2] += s.b;
    }
}

}  // namespace

void add_to_film(Film& film, const RenderedItems& items, int threads) {
    const std::vector<PixelSegment> segments = pixel_segments(items);
    const int pixels = film.width * film.height;
    if (segments.empty()) {
        // A sparse pass: item by item.
        size_t next_dropped = 0;
        for (int i = 0; i < items.item_count; ++i) {
            if (next_dropped < items.dropped_items.size() && items.dropped_items[next_dropped] == i) {
                ++next_dropped;
                continue;
            }
            add_camera_value(film, items, i,
                             run_item_pixel(items.first_item + i, film.width, film.height, items.pixel_stride,
                                            items.run_pixel, items.run_length, items.run_pixels.get()));
        }
        add_pixel_band(film, items, {}, 0, pixels);
    } else if (threads <= 1) {
        add_pixel_band(film, items, segments, 0, pixels);
    } else {
        // Bands of pixels, one per thread: the film's sums are memory-bound, and one thread
        // adding a GPU's samples was what the GPU waited for.
        std::vector<std::thread> workers;
        for (int t = 0; t < threads; ++t) {
            const int lo = int(int64_t(pixels) * t / threads), hi = int(int64_t(pixels) * (t + 1) / threads);
            workers.emplace_back([&, lo, hi] { add_pixel_band(film, items, segments, lo, hi); });
        }
        for (std::thread& w : workers) w.join();
    }
    if (items.strategy_slots > 0) {
        const size_t pixel_count = size_t(pixels);
        if (film.strategy_sum.empty()) {
            film.strategy_sum.assign(pixel_count * 3 * size_t(items.strategy_slots), 0.0);
            film.strategy_stride = items.strategy_stride;
        }
        for (const RenderedItems::StrategySplat& s : items.strategy_splats) {
            double* dst = &film.strategy_sum[(size_t(s.slot) * pixel_count + size_t(s.splat.pixel)) * 3];
            dst[0] += s.splat.r;
            dst[1] += s.splat.g;
            dst[2] += s.splat.b;
        }
    }
}

}  // namespace clbdpt
