// Adding rendered items to a film (film/rendered_items.h): every layout of items (a whole pass,
// a part of one, a run through the pixels several times, a sparse pass) lands on the pixels
// the kernel rendered them for, dropped items are left out, and several threads adding bands
// of pixels give the film of one thread bit for bit.
#include <gtest/gtest.h>

#include <random>

#include "film/rendered_items.h"

namespace clbdpt {
namespace {

constexpr int kWidth = 7, kHeight = 5, kPixels = kWidth * kHeight;

// Items with values that make the order of additions visible in the last bits of a double
// sum: 1 + 2^-30 and the like do not add associatively in float-to-double sums of many.
RenderedItems make_items(int first_item, int item_count, int pixel_stride, int run_pixel, int run_length,
                         uint32_t seed) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> value(0.0f, 1e3f);
    RenderedItems r;
    r.first_item = first_item;
    r.item_count = item_count;
    r.pixel_stride = pixel_stride;
    r.run_pixel = run_pixel;
    r.run_length = run_length;
    for (int i = 0; i < item_count * 3; ++i) r.camera.push_back(value(rng) * (i % 2 ? 1e-7f : 1.0f));
    for (int i = 1; i < item_count; i += 5) r.dropped_items.push_back(i);
    for (int k = 0; k < 3 * item_count; ++k)
        r.splats.push_back({value(rng), value(rng) * 1e-6f, value(rng), int(rng() % kPixels)});
    return r;
}

// What add_to_film must do, item by item.
Film reference_film(const std::vector<RenderedItems>& runs) {
    Film film(kWidth, kHeight);
    film.camera_sq.assign(kPixels, 0.0);
    for (const RenderedItems& r : runs) {
        for (int i = 0; i < r.item_count; ++i) {
            if (std::find(r.dropped_items.begin(), r.dropped_items.end(), i) != r.dropped_items.end()) continue;
            const int pixel =
                launch_item_pixel(r.first_item + i, kWidth, kHeight, r.pixel_stride, r.run_pixel, r.run_length);
            double sq = 0;
            for (int c = 0; c < 3; ++c) {
                film.camera_sum[size_t(pixel) * 3 + c] += r.camera[size_t(i) * 3 + c];
                sq += double(r.camera[size_t(i) * 3 + c]) * r.camera[size_t(i) * 3 + c];
            }
            film.camera_sq[size_t(pixel)] += sq;
        }
        for (const SplatRecord& s : r.splats) {
            film.light_sum[size_t(s.pixel) * 3] += s.r;
            film.light_sum[size_t(s.pixel) * 3 + 1] += s.g;
            film.light_sum[size_t(s.pixel) * 3 + 2] += s.b;
        }
    }
    return film;
}

TEST(RenderedItems, EveryLayoutAddsAsItemByItemWithAnyThreadCount) {
    const std::vector<RenderedItems> runs = {
        make_items(0, kPixels, 1, 0, 0, 1),             // a whole pass
        make_items(9, 20, 1, 0, 0, 2),                  // a part of one
        make_items(30, 4 * kPixels + 3, 1, 0, kPixels, 3),  // passes joined, from within a pass
        make_items(0, 17, 1, 11, 6, 4),                 // a run of 6 pixels, several samples
        make_items(0, render_item_count(kWidth, kHeight, 2), 2, 0, 0, 5),  // a sparse pass
    };
    const Film expected = reference_film(runs);
    for (int threads : {1, 2, 3, 8}) {
        Film film(kWidth, kHeight);
        film.camera_sq.assign(kPixels, 0.0);
        for (const RenderedItems& r : runs) add_to_film(film, r, threads);
        EXPECT_EQ(film.camera_sum, expected.camera_sum) << threads << " threads";
        EXPECT_EQ(film.camera_sq, expected.camera_sq) << threads << " threads";
        EXPECT_EQ(film.light_sum, expected.light_sum) << threads << " threads";
    }
}

}  // namespace
}  // namespace clbdpt
