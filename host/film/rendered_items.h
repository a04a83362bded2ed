// What a device returns for a run of work items of one pass, before it is added to a film: each
// item's camera value, and the t = 1 splats and strategy-image records in the order the kernel
// wrote them. Adding is kept apart from rendering so that runs rendered anywhere (another device,
// another MPI rank, out of order) are added in one fixed order: the film then does not depend on
// who rendered what, bit for bit.
#pragma once

#include <cstdint>
#include <memory>
#include <vector>

#include "film/film.h"
#include "shared/types.h"

namespace clbdpt {

// A sample left out for a non-finite value: its pixel, sample index and the first strategy
// (s, t) that gave one (-1, -1 if the kernel did not name one).
struct DroppedSample {
    int x = 0, y = 0;
    uint32_t sample = 0;
    int s = -1, t = -1;
};

// Samples rendered, rays traced, samples dropped, and the first few dropped.
struct ItemCounts {
    static constexpr size_t kFirstDropped = 5;
    uint64_t samples = 0;
    uint64_t rays = 0;
    uint64_t dropped_samples = 0;
    std::vector<DroppedSample> first_dropped;
    void add(const ItemCounts& other) {
        samples += other.samples;
        rays += other.rays;
        dropped_samples += other.dropped_samples;
        for (const DroppedSample& d : other.first_dropped)
            if (first_dropped.size() < kFirstDropped) first_dropped.push_back(d);
    }
};

struct RenderedItems {
    uint32_t sample_index = 0;  // the pass
    int first_item = 0;
    int item_count = 0;
    int pixel_stride = 1;
    int run_pixel = 0, run_length = 0;  // a run of pixels instead of a pass (PassSpec)
    std::shared_ptr<const std::vector<int>> run_pixels;  // the run's pixels, where listed (PassSpec)
    // Per item: rgb. Items in dropped_items (sorted) are not added.
    std::vector<float> camera;
    // Per item: the rays its sample traced (Film::camera_rays; may be empty).
    std::vector<float> rays;
    std::vector<int> dropped_items;
    // Light-image splats as the kernel wrote them (none with pixel < 0), in the order they are
    // added.
    std::vector<SplatRecord> splats;
    // Per item, where the pass asked for them (PassSpec::subset_moments): the sum of its
    // contributions' squares and the same with each divided by the share of its MIS weights
    // that a mix without inner connections keeps (cl/kernels/render.cl). Else empty.
    std::vector<float> subset_moments;
    // Strategy-image records (strategy images on): the strategy's slot and the record.
    struct StrategySplat {
        int slot;
        SplatRecord splat;
    };
    std::vector<StrategySplat> strategy_splats;
    int strategy_slots = 0;   // 0: no strategy images
    int strategy_stride = 0;  // max_depth + 3
    ItemCounts counts;
};

// The pixel of item `item` of a launch (launch_item_pixel), or with a pixel list that of the
// run's listed pixels.
inline int run_item_pixel(int item, int width, int height, int stride, int run_pixel, int run_length,
                          const std::vector<int>* run_pixels) {
    return run_pixels && run_length > 0 ? (*run_pixels)[size_t(run_pixel + item % run_length)]
                                        : launch_item_pixel(item, width, height, stride, run_pixel, run_length);
}

// Adds the items' values to the film's sums, in the order a single device rendering the whole
// pass at once would (items in order; each item's splats in slot order). Does not change spp.
// threads > 1: that many threads add bands of pixels, each pixel's values still in that order,
// so the film is the same bit for bit.
void add_to_film(Film& film, const RenderedItems& items, int threads = 1);

}  // namespace clbdpt
