// How a render is cut into work units, fixed before the render starts and independent of the
// devices: unit u is a band of consecutive work items (pixels) of one pass, bands in item order,
// passes in order. The film adds the units in this order whoever rendered them, so the image is
// the same bit for bit however the units were shared out.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

namespace clbdpt {

// A run of consecutive work items of one pass: what a device renders in one go.
struct ItemRun {
    uint32_t pass = 0;
    int first_item = 0;
    int item_count = 0;
};

// How many of runs[k..] a device may render as one run through the pixels of consecutive
// passes (DeviceWorker, PassSpec::run_length): each next run starts the pass after the one
// before it ends, and together they stay within max_items. At least 1; *items: their items.
size_t joinable_runs(const std::vector<ItemRun>& runs, size_t k, int items_per_pass, int64_t max_items,
                     int64_t* items);

struct WorkUnits {
    // Items per unit: small enough that a unit of a slow device does not hold up the end of a
    // render for long (4096 samples: about 10 ms on one CPU core), large enough that a device
    // that takes one unit at a time still runs whole work-groups.
    static constexpr int kDefaultUnitItems = 4096;

    WorkUnits() = default;
    WorkUnits(int items_per_pass, int first_pass, int unit_items = kDefaultUnitItems);

    int items_per_pass = 0;
    int unit_items = 0;
    int units_per_pass = 0;
    int first_pass = 0;  // the pass of unit 0 (a resumed render starts past pass 0)

    uint32_t pass_of(int64_t unit) const { return uint32_t(first_pass + unit / units_per_pass); }
    int first_item_of(int64_t unit) const { return int(unit % units_per_pass) * unit_items; }
    int item_count_of(int64_t unit) const;
    int64_t items_in(int64_t begin, int64_t end) const;
    // Units [begin, end) as runs of items, one run per pass they touch.
    std::vector<ItemRun> runs(int64_t begin, int64_t end) const;
    // The first unit of the pass after the one `unit` lies in (unit itself if it starts a pass).
    int64_t pass_end(int64_t unit) const { return (unit + units_per_pass - 1) / units_per_pass * units_per_pass; }
};

}  // namespace clbdpt
