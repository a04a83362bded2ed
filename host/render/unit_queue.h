// Shares a render's work units (render/work_units.h) between workers of unequal speed and adds
// their results to one film in unit order.
//
// - A worker takes a run of consecutive units sized by its measured rate (about kGrabSeconds
//   of work), and smaller towards the end, so that the workers finish together.
// - When no unit is left, an idle worker that would finish another's run sooner than that
//   worker is expected to renders the same run; the first result is added, the other discarded
//   (and the slower copy is told to stop).
// - A worker that fails gives its run back; the others render it first.
// - Results are added to the film strictly in unit order, by a thread of their own
//   (add_results); a run that finishes early waits, and a worker waits while the adding is
//   kMaxReadyBacklog results behind.
//
// Whole passes: a time-bound render hands out passes until its budget is spent (a pass starts
// when a run taken before then reaches into it), and a stop (an interrupt) finishes the pass it
// is in; the film always ends on a pass boundary.
#pragma once

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <vector>

#include "film/film.h"
#include "film/rendered_items.h"
#include "film/rendered_items_pool.h"
#include "render/work_units.h"

namespace clbdpt {

class UnitQueue {
public:
    using Clock = std::chrono::steady_clock;
    // Work per take, in seconds of the taker's measured rate.
    static constexpr double kGrabSeconds = 0.2;

    struct Grab {
        int64_t begin = 0, end = 0;
        bool duplicate = false;  // a take-over of a run another worker holds
        // Set when the run's result is in (from whichever copy): a copy still rendering may stop.
        std::shared_ptr<std::atomic<bool>> done;
    };

    // What one worker did: samples of its results that were added, samples it rendered that
    // another copy had already delivered, and seconds spent rendering.
    struct WorkerShare {
        uint64_t samples = 0;
        uint64_t wasted_samples = 0;
        double busy_seconds = 0;
    };

    // film: holds passes [0, units.first_pass) already (a resumed render) and receives the rest.
    // passes: passes to render in all (from units.first_pass on) when budget_seconds is 0.
    UnitQueue(const WorkUnits& units, Film* film, int passes, double budget_seconds, Clock::time_point start,
              int workers);

    // The next run for `worker`, or nothing when the render is over for it. Waits while the
    // only work left is runs that other workers hold and it would not finish sooner.
    std::optional<Grab> take(int worker);
    // The results of a grab (one RenderedItems per pass the run touches), rendered in `seconds`.
    // They wait for add_ready_results (another thread), so the worker goes on rendering.
    void complete(int worker, const Grab& grab, std::vector<RenderedItems>&& results, double seconds);
    // The adding thread's loop: adds results to the film in unit order as they come in, and
    // returns once every worker has left and all that can be added is in.
    void add_results();
    // `worker` failed on `grab`: true if it leaves the render and the run goes to the others;
    // false if it was the last worker (the render fails).
    bool fail(int worker, const Grab& grab);
    // No new pass starts; the pass in flight is finished.
    void stop();
    // Nothing more starts; every worker leaves.
    void abort();

    // Asks for a copy of the film at the next pass boundary (a checkpoint).
    void request_snapshot();
    // The copy, once taken.
    std::optional<Film> take_snapshot();

    // Waits until every worker has left or `period` has passed; true when all have left.
    bool wait_finished(std::chrono::milliseconds period);
    void worker_exited();

    int passes_done();  // passes added to the film so far (beyond units.first_pass)
    std::vector<WorkerShare> shares();
    // Results are handed back to `pool` once added (null: freed).
    void set_result_pool(RenderedItemsPool* pool) { pool_ = pool; }
    ItemCounts counts();          // of the results added to the film
    // Seconds the adding thread spent adding, and the workers waiting for it (--profile).
    double film_add_seconds();
    double backlog_wait_seconds();
    double first_pass_seconds();  // since start, until the first pass was in the film (0: none yet)

private:
    struct Held {
        int64_t begin, end;
        int worker;  // -1: its worker failed while a copy goes on
        Clock::time_point start, expected_end;
        bool duplicated = false;
        std::shared_ptr<std::atomic<bool>> done;
    };
    struct Finished {
        int64_t end;
        std::vector<RenderedItems> results;
    };

    // Units of about kGrabSeconds of `worker`'s measured rate (1 until measured).
    int64_t grab_units(int worker) const;
    int64_t grab_size(int worker) const;
    std::optional<Grab> take_over(int worker, Clock::time_point now);
    void extend_end(int worker);
    // Results next in unit order that wait to be added (the caller holds mutex_).
    int ready_backlog() const;
    std::optional<Grab> leave();
    double seconds_since_start() const;
    // How long units [begin, end) take at `rate` items per second.
    Clock::duration time_for(int64_t begin, int64_t end, double rate) const;

    const WorkUnits units_;
    Film* film_;
    const bool timed_;
    const double budget_;
    const Clock::time_point start_;

    std::mutex mutex_;
    std::condition_variable changed_;
    int64_t next_ = 0;       // first unit not handed out
    int64_t end_ = 0;        // units to hand out in all (grows by passes in a timed render)
    int64_t added_end_ = 0;  // units [0, added_end_) are in the film
    std::vector<Held> held_;
    std::vector<Held> given_back_;
    std::map<int64_t, Finished> finished_;  // by first unit, waiting for the units before them
    std::vector<double> rate_;              // items per second, 0 until measured
    std::vector<WorkerShare> shares_;
    int workers_in_render_;
    int workers_running_;
    bool stopped_ = false;
    bool aborted_ = false;
    bool snapshot_requested_ = false;
    std::optional<Film> snapshot_;
    ItemCounts counts_;
    double first_pass_seconds_ = 0;
    double film_add_seconds_ = 0;
    RenderedItemsPool* pool_ = nullptr;
    double backlog_wait_seconds_ = 0;

    // A worker waits in take() while this many results wait to be added, so that a device
    // faster than the adding does not pile up results without bound.
    static constexpr int kMaxReadyBacklog = 2;
    // A result is added to the film by one thread per this many items, at most
    // max_add_threads_ (half the host's cores, up to kMaxAddThreads).
    static constexpr int kMinItemsPerAddThread = 1 << 18;
    static constexpr int kMaxAddThreads = 8;
    const int max_add_threads_;
};

}  // namespace clbdpt
