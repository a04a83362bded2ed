// Result buffers handed back once their items are in the film, for the next run of items to
// reuse. A GPU renders a run of 2^21 items in milliseconds; giving each run fresh buffers cost
// more host time than the kernel took (memory mapped and faulted in afresh, then zeroed: 49% of
// a 1024 x 1024 path-traced render's wall time on an H200). Reused, the pages are in already
// and nothing needs zeroing (Renderer::render_items writes every item).
#pragma once

#include <mutex>
#include <utility>
#include <vector>

#include "film/rendered_items.h"

namespace clbdpt {

// Keeps every result handed back: it holds no more than were once on their way at the same
// time (rendered, waiting to be added or being added), memory the render already had. A GPU's
// grab of work is 0.2 s of it, 16 results of 2^21 items for a fast path tracer, and two grabs
// may wait to be added while a third renders, so a bound of a few results kept almost none.
class RenderedItemsPool {
public:
    // A result handed back earlier (its buffers hold old values: the taker overwrites or
    // clears them), or an empty one.
    RenderedItems take() {
        std::lock_guard<std::mutex> lock(mutex_);
        if (free_.empty()) return RenderedItems{};
        RenderedItems items = std::move(free_.back());
        free_.pop_back();
        return items;
    }

    void give(RenderedItems&& items) {
        std::lock_guard<std::mutex> lock(mutex_);
        free_.push_back(std::move(items));
    }

private:
    std::mutex mutex_;
    std::vector<RenderedItems> free_;
};

}  // namespace clbdpt
