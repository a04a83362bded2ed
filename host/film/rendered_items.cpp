#include "film/rendered_items.h"

namespace clbdpt {

void add_to_film(Film& film, const RenderedItems& items) {
    size_t next_dropped = 0;
    for (int i = 0; i < items.item_count; ++i) {
        if (next_dropped < items.dropped_items.size() && items.dropped_items[next_dropped] == i) {
            ++next_dropped;
            continue;
        }
        const int pixel = launch_item_pixel(items.first_item + i, film.width, film.height, items.pixel_stride,
                                            items.run_pixel, items.run_length);
        double* dst = &film.camera_sum[size_t(pixel) * 3];
        const float* c = &items.camera[size_t(i) * 3];
        dst[0] += c[0];
        dst[1] += c[1];
        dst[2] += c[2];
        if (!film.camera_sq.empty())
            film.camera_sq[size_t(pixel)] += double(c[0]) * c[0] + double(c[1]) * c[1] + double(c[2]) * c[2];
    }
    for (const SplatRecord& s : items.splats) {
        double* light = &film.light_sum[size_t(s.pixel) * 3];
        light[0] += s.r;
        light[1] += s.g;
        light[2] += s.b;
    }
    if (items.strategy_slots > 0) {
        const size_t pixels = size_t(film.width) * film.height;
        if (film.strategy_sum.empty()) {
            film.strategy_sum.assign(pixels * 3 * size_t(items.strategy_slots), 0.0);
            film.strategy_stride = items.strategy_stride;
        }
        for (const RenderedItems::StrategySplat& s : items.strategy_splats) {
            double* dst = &film.strategy_sum[(size_t(s.slot) * pixels + size_t(s.splat.pixel)) * 3];
            dst[0] += s.splat.r;
            dst[1] += s.splat.g;
            dst[2] += s.splat.b;
        }
    }
}

}  // namespace clbdpt
