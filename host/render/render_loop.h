// The whole render on one or more devices: passes (one sample of every pixel, numbered from 0)
// are handed out one at a time to whichever device is free, each device adds into its own film,
// and the films are merged in device order at the end. With a time budget, devices start passes
// until it is spent (whole passes only).
//
// A render may start from a checkpoint's film (its passes are not rendered again), may be
// asked to stop (an interrupt: no new pass starts, the passes in flight finish), and may hand
// out snapshots of the film now and then for a checkpoint. A device that fails while others
// remain leaves the render and its pass goes to the others. Every film it returns or hands out
// holds exactly passes 0 .. spp - 1.
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "film/film.h"
#include "render/renderer.h"

namespace clbdpt {

struct RenderSchedule {
    // Passes already done (a resumed render): rendering goes on from pass resume->spp, and the
    // first device's film starts from these sums, so one device ends bit for bit where an
    // uninterrupted render would. Null: from pass 0.
    const Film* resume = nullptr;
    // Polled before each pass; true stops the render after the passes in flight.
    std::function<bool()> stop_requested;
    // Called with a snapshot of the film every checkpoint_seconds (devices pause between passes
    // while it is taken, not while it is written). 0: never.
    double checkpoint_seconds = 0;
    std::function<void(const Film&)> checkpoint;
    // Called when a device fails during a pass while others remain: the device leaves the
    // render, its pass goes to the others, and its film is as before that pass. The argument
    // names the device and what failed. (The last device's failure fails the render.)
    std::function<void(const std::string&)> device_dropped;
};

// renderers: one per device, built with the same scene and options. stats: totals over all
// devices for this run, seconds = wall time. Without a time budget the render ends at
// options.spp passes in all (the resumed ones included).
Film render_image(const std::vector<Renderer*>& renderers, const RenderOptions& options, RenderStats* stats,
                  const RenderSchedule& schedule = {});

}  // namespace clbdpt
