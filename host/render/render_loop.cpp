#include "render/render_loop.h"

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <exception>
#include <mutex>
#include <string>
#include <thread>

namespace clbdpt {

namespace {

using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point start) { return std::chrono::duration<double>(Clock::now() - start).count(); }

// How often the progress callback runs while passes are in flight.
constexpr auto kProgressInterval = std::chrono::milliseconds(200);

// Hands out pass numbers to the device threads and lets the coordinating thread hold them
// between passes (for a snapshot of the films) or stop them. A pass that a failed device gave
// back is handed out first, even to a held or stopped queue: every film the render hands out
// must hold passes first .. next - 1 with none missing.
class PassQueue {
public:
    PassQueue(int first, int end, bool timed, double budget, Clock::time_point start, int devices)
        : next_(first), first_(first), end_(end), timed_(timed), budget_(budget), start_(start), devices_(devices) {}

    // The next pass to render, or -1 when the render is over for this device. Waits while the
    // queue is held, and at the end until no pass is in flight: a failing device may yet give
    // one back.
    int take() {
        std::unique_lock<std::mutex> lock(mutex_);
        for (;;) {
            if (aborted_) return leave();
            if (!given_back_.empty()) {
                const int pass = given_back_.back();
                given_back_.pop_back();
                ++in_flight_;
                return pass;
            }
            // A time-bound render has at least one pass, however small the budget.
            const bool no_new_pass =
                stopped_ || (timed_ ? next_ > first_ && seconds_since(start_) >= budget_ : next_ >= end_);
            if (no_new_pass) {
                if (in_flight_ == 0) return leave();
            } else if (!held_) {
                ++in_flight_;
                return next_++;
            }
            changed_.wait(lock);
        }
    }
    void done() {
        std::lock_guard<std::mutex> lock(mutex_);
        --in_flight_;
        ++passes_done_;
        changed_.notify_all();
    }
    // A device failed during `pass`: true (the pass goes to the other devices, the caller's
    // device leaves the render) unless it was the last one.
    bool give_back(int pass) {
        std::lock_guard<std::mutex> lock(mutex_);
        if (devices_ <= 1) return false;
        --devices_;
        --in_flight_;
        given_back_.push_back(pass);
        changed_.notify_all();
        return true;
    }
    // Holds the queue and waits until no pass is in flight or given back; then the films hold
    // passes [first, next). Returns false instead if the render stops.
    bool hold() {
        std::unique_lock<std::mutex> lock(mutex_);
        held_ = true;
        changed_.wait(lock, [&] { return (in_flight_ == 0 && given_back_.empty()) || stopped_ || aborted_; });
        return !stopped_ && !aborted_;
    }
    void release() {
        std::lock_guard<std::mutex> lock(mutex_);
        held_ = false;
        changed_.notify_all();
    }
    // No new pass starts (an interrupt); passes given back are still rendered.
    void stop() {
        std::lock_guard<std::mutex> lock(mutex_);
        stopped_ = true;
        changed_.notify_all();
    }
    // The render has failed: nothing more starts.
    void abort() {
        std::lock_guard<std::mutex> lock(mutex_);
        aborted_ = true;
        changed_.notify_all();
    }
    // Waits until the threads are finished (all passes taken and done) or `period` has passed.
    // Returns true when finished.
    template <typename Duration>
    bool wait_finished(Duration period, const int& threads_running) {
        std::unique_lock<std::mutex> lock(mutex_);
        return changed_.wait_for(lock, period, [&] { return threads_running == 0; });
    }
    void thread_exited(int* threads_running) {
        std::lock_guard<std::mutex> lock(mutex_);
        --*threads_running;
        changed_.notify_all();
    }
    int passes_done() {
        std::lock_guard<std::mutex> lock(mutex_);
        return passes_done_;
    }

private:
    std::mutex mutex_;
    std::condition_variable changed_;
    int next_, first_, end_;
    bool timed_;
    double budget_;
    Clock::time_point start_;
    int in_flight_ = 0;
    int passes_done_ = 0;
    int devices_;  // devices that have not left the render

    int leave() {
        --devices_;
        changed_.notify_all();
        return -1;
    }
    std::vector<int> given_back_;
    bool held_ = false;
    bool stopped_ = false;
    bool aborted_ = false;
};

// The films of all devices as one, in device order (the order every merge uses).
Film merge(const std::vector<Film>& films) {
    Film film(films.front().width, films.front().height);
    for (const Film& f : films) film.add(f);
    return film;
}

}  // namespace

Film render_image(const std::vector<Renderer*>& renderers, const RenderOptions& options, RenderStats* stats,
                  const RenderSchedule& schedule) {
    const Camera& camera = renderers.front()->scene().camera;
    const bool timed = options.time_budget > 0;
    const int first_pass = schedule.resume ? schedule.resume->spp : 0;
    const int planned = timed ? 0 : options.spp;
    std::vector<Film> films(renderers.size(), Film(camera.width, camera.height));
    if (schedule.resume) films.front() = *schedule.resume;
    const auto start = Clock::now();
    PassQueue queue(first_pass, options.spp, timed, options.time_budget, start, int(renderers.size()));
    std::exception_ptr failure;
    std::mutex failure_mutex;
    std::atomic<double> first_pass_seconds{0.0};
    int threads_running = int(renderers.size());

    std::vector<std::string> dropped_devices;
    // With other devices to take over, a device's film (and its counters) is kept as it was
    // before each pass: a pass that fails half-way leaves part of its samples in the film,
    // which are taken out again by restoring the copy (exactly, unlike subtracting them).
    const bool can_fail_over = renderers.size() > 1;
    auto worker = [&](size_t d) {
        Film before_pass;
        RenderStats stats_before_pass;
        for (int pass; (pass = queue.take()) >= 0;) {
            if (can_fail_over) {
                before_pass = films[d];
                stats_before_pass = renderers[d]->stats();
            }
            try {
                renderers[d]->render_passes(films[d], uint32_t(pass), 1);
            } catch (const std::exception& e) {
                if (can_fail_over && queue.give_back(pass)) {
                    films[d] = std::move(before_pass);
                    renderers[d]->restore_stats(stats_before_pass);
                    std::lock_guard<std::mutex> lock(failure_mutex);
                    dropped_devices.push_back(renderers[d]->device().entry().name + ": " + e.what());
                    if (schedule.device_dropped) schedule.device_dropped(dropped_devices.back());
                    break;
                }
                std::lock_guard<std::mutex> lock(failure_mutex);
                if (!failure) failure = std::current_exception();
                queue.abort();
                break;
            }
            if (queue.passes_done() == 0) first_pass_seconds = seconds_since(start);
            queue.done();
        }
        queue.thread_exited(&threads_running);
    };
    if (schedule.stop_requested && schedule.stop_requested()) queue.stop();
    std::vector<std::thread> threads;
    for (size_t d = 0; d < renderers.size(); ++d) threads.emplace_back(worker, d);

    // This thread reports progress, watches for a stop request and takes the snapshots.
    auto last_checkpoint = Clock::now();
    int checkpointed_spp = first_pass;
    for (;;) {
        if (queue.wait_finished(kProgressInterval, threads_running)) break;
        if (schedule.stop_requested && schedule.stop_requested()) queue.stop();
        if (options.progress) options.progress(first_pass + queue.passes_done(), planned, seconds_since(start));
        if (schedule.checkpoint && schedule.checkpoint_seconds > 0 &&
            seconds_since(last_checkpoint) >= schedule.checkpoint_seconds) {
            Film snapshot;
            if (queue.hold()) snapshot = merge(films);
            queue.release();
            // Written while the devices go on; a snapshot with no new pass is not written again.
            if (snapshot.spp > checkpointed_spp) {
                try {
                    schedule.checkpoint(snapshot);
                } catch (...) {
                    // Rethrown once the device threads are joined.
                    std::lock_guard<std::mutex> lock(failure_mutex);
                    if (!failure) failure = std::current_exception();
                    queue.abort();
                }
                checkpointed_spp = snapshot.spp;
            }
            last_checkpoint = Clock::now();
        }
    }
    for (std::thread& t : threads) t.join();
    const double seconds = seconds_since(start);
    if (failure) std::rethrow_exception(failure);
    const int passes_done = queue.passes_done();
    if (options.progress) options.progress(first_pass + passes_done, planned, seconds);

    Film film = merge(films);
    RenderStats total;
    total.defines = renderers.front()->stats().defines;
    total.program_from_cache = true;
    for (size_t d = 0; d < renderers.size(); ++d) {
        total.add(renderers[d]->stats());
        total.program_from_cache = total.program_from_cache && renderers[d]->stats().program_from_cache;
    }
    total.seconds = seconds;
    total.dropped_devices = dropped_devices;
    total.first_pass_seconds = first_pass_seconds;
    if (stats) *stats = total;
    return film;
}

}  // namespace clbdpt
