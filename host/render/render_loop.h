// The whole render on one or more devices (or, under MPI, devices of other processes): passes
// (one sample of every pixel, numbered from 0) are cut into work units (render/work_units.h),
// which a UnitQueue shares out by each device's measured rate and adds to one film in unit order,
// so the image does not depend on which device rendered what. With a time budget, passes start
// until it is spent (whole passes only).
//
// A render may start from a checkpoint's film (its passes are not rendered again), may be
// asked to stop (an interrupt: no new pass starts, the pass in flight finishes), and may hand
// out snapshots of the film now and then for a checkpoint. A device that fails while others
// remain leaves the render and its work goes to the others. Every film it returns or hands out
// holds exactly passes 0 .. spp - 1.
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "film/film.h"
#include "film/rendered_items_pool.h"
#include "render/renderer.h"
#include "render/work_units.h"

namespace clbdpt {

struct RenderSchedule {
    // Passes already done (a resumed render): rendering goes on from pass resume->spp, and the
    // first device's film starts from these sums, so one device ends bit for bit where an
    // uninterrupted render would. Null: from pass 0.
    const Film* resume = nullptr;
    // Polled before each pass; true stops the render after the passes in flight.
    std::function<bool()> stop_requested;
    // Called with a snapshot of the film every checkpoint_seconds (taken at the next pass
    // boundary; the devices do not wait for it). 0: never.
    double checkpoint_seconds = 0;
    std::function<void(const Film&)> checkpoint;
    // Called when a device fails during a pass while others remain: the device leaves the
    // render, its pass goes to the others, and its film is as before that pass. The argument
    // names the device and what failed. (The last device's failure fails the render.)
    std::function<void(const std::string&)> device_dropped;
};

// Something that renders runs of work items: a device of this process (a Renderer) or, under
// MPI, a device of another process (mpi/remote_worker.h).
class UnitWorker {
public:
    virtual ~UnitWorker() = default;
    virtual std::string name() const = 0;
    // Renders the runs in order, with the render's seed. cancelled, polled between launches:
    // true means another device has delivered these runs, and the results will be discarded.
    virtual std::vector<RenderedItems> render(const std::vector<ItemRun>& runs,
                                              const std::function<bool()>& cancelled) = 0;
    // Where results whose items are in the film come back to, for render() to reuse their
    // buffers (null: none; a worker may also ignore it).
    virtual void set_result_pool(RenderedItemsPool* pool) { (void)pool; }
};

// A Renderer as a UnitWorker.
class DeviceWorker : public UnitWorker {
public:
    explicit DeviceWorker(Renderer& renderer) : renderer_(renderer) {}
    std::string name() const override;
    std::vector<RenderedItems> render(const std::vector<ItemRun>& runs,
                                      const std::function<bool()>& cancelled) override;
    void set_result_pool(RenderedItemsPool* pool) override { pool_ = pool; }

    // Items rendered in one go at most when runs of several passes are joined: the result's
    // camera values (12 bytes an item, 24 MiB) stay below glibc's largest mmap threshold, so
    // their memory is reused rather than mapped and faulted in afresh each time.
    static constexpr int64_t kMaxMergedItems = int64_t(1) << 21;

private:
    Renderer& renderer_;
    RenderedItemsPool* pool_ = nullptr;
};

// renderers: one per device, built with the same scene and options; more_workers: devices of
// other processes (mpi/cluster.h), after them. stats: totals over all devices for this run,
// seconds = wall time. Without a time budget the render ends at options.spp passes in all (the
// resumed ones included).
Film render_image(const std::vector<Renderer*>& renderers, const RenderOptions& options, RenderStats* stats,
                  const RenderSchedule& schedule = {}, const std::vector<UnitWorker*>& more_workers = {});
// The same with any workers; stats then holds the counters and device shares only (the caller
// adds its renderers' profiles and build times).
Film render_image(const std::vector<UnitWorker*>& workers, int width, int height, const RenderOptions& options,
                  RenderStats* stats, const RenderSchedule& schedule = {});

}  // namespace clbdpt
