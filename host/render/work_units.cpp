#include "render/work_units.h"

#include <algorithm>

#include "util/error.h"

namespace clbdpt {

size_t joinable_runs(const std::vector<ItemRun>& runs, size_t k, int items_per_pass, int64_t max_items,
                     int64_t* items) {
    const ItemRun& first = runs[k];
    *items = first.item_count;
    size_t n = 1;
    for (; k + n < runs.size(); ++n) {
        const ItemRun& next = runs[k + n];
        const bool follows = next.pass == first.pass + n && next.first_item == 0 &&
                             int64_t(next.pass - first.pass) * items_per_pass - first.first_item == *items;
        if (!follows || *items + next.item_count > max_items) break;
        *items += next.item_count;
    }
    return n;
}

WorkUnits::WorkUnits(int items_per_pass_, int first_pass_, int unit_items_)
    : items_per_pass(items_per_pass_), first_pass(first_pass_) {
    if (items_per_pass < 1 || unit_items_ < 1) throw Error("work units need at least one item");
    unit_items = std::min(unit_items_, items_per_pass);
    units_per_pass = (items_per_pass + unit_items - 1) / unit_items;
}

int WorkUnits::item_count_of(int64_t unit) const {
    const int first = first_item_of(unit);
    return std::min(unit_items, items_per_pass - first);
}

int64_t WorkUnits::items_in(int64_t begin, int64_t end) const {
    int64_t items = 0;
    for (const ItemRun& r : runs(begin, end)) items += r.item_count;
    return items;
}

std::vector<ItemRun> WorkUnits::runs(int64_t begin, int64_t end) const {
    std::vector<ItemRun> out;
    for (int64_t u = begin; u < end;) {
        const int64_t stop = std::min(end, (u / units_per_pass + 1) * units_per_pass);
        ItemRun r;
        r.pass = pass_of(u);
        r.first_item = first_item_of(u);
        r.item_count = first_item_of(stop - 1) + item_count_of(stop - 1) - r.first_item;
        out.push_back(r);
        u = stop;
    }
    return out;
}

}  // namespace clbdpt
