#include "render/unit_queue.h"

#include <algorithm>
#include <cmath>
#include <thread>

namespace clbdpt {

namespace {

// How long an idle worker waits before it looks again for a run worth taking over.
constexpr auto kTakeOverPoll = std::chrono::milliseconds(20);

}  // namespace

UnitQueue::UnitQueue(const WorkUnits& units, Film* film, int passes, double budget_seconds, Clock::time_point start,
                     int workers)
    : units_(units),
      film_(film),
      timed_(budget_seconds > 0),
      budget_(budget_seconds),
      start_(start),
      rate_(size_t(workers), 0.0),
      shares_(size_t(workers)),
      workers_in_render_(workers),
      workers_running_(workers),
      max_add_threads_(std::clamp(int(std::thread::hardware_concurrency()) / 2, 1, kMaxAddThreads)) {
    // A time-bound render has at least one pass, however small the budget.
    end_ = int64_t(timed_ ? 1 : std::max(passes, 0)) * units_.units_per_pass;
}

UnitQueue::Clock::duration UnitQueue::time_for(int64_t begin, int64_t end, double rate) const {
    return std::chrono::duration_cast<Clock::duration>(
        std::chrono::duration<double>(double(units_.items_in(begin, end)) / rate));
}

double UnitQueue::seconds_since_start() const {
    return std::chrono::duration<double>(Clock::now() - start_).count();
}

std::optional<UnitQueue::Grab> UnitQueue::leave() {
    --workers_in_render_;
    changed_.notify_all();
    return std::nullopt;
}

void UnitQueue::extend_end(int worker) {
    if (stopped_) {
        end_ = std::min(end_, units_.pass_end(next_));
    } else if (timed_ && seconds_since_start() < budget_) {
        // While the budget lasts, the passes that this worker's next run (about kGrabSeconds of
        // its work) reaches into start: a fast device's run spans several passes, which it
        // renders in one go (DeviceWorker), as in a render of a given spp.
        const int64_t wanted = grab_units(worker);
        if (next_ + wanted > end_) end_ = units_.pass_end(std::max(next_ + wanted, end_ + 1));
    }
}

int64_t UnitQueue::grab_units(int worker) const {
    const double rate = rate_[size_t(worker)];
    if (rate <= 0) return 1;  // not measured yet: one unit
    return std::max<int64_t>(1, std::llround(rate * kGrabSeconds / units_.unit_items));
}

int64_t UnitQueue::grab_size(int worker) const {
    const double rate = rate_[size_t(worker)];
    int64_t n = grab_units(worker);
    if (rate <= 0) return n;
    if (!timed_ && workers_in_render_ > 1) {
        // Towards the end, at most half of this worker's share of what is left (guided
        // self-scheduling), so that the last runs are short on every worker.
        double total = 0;
        for (double r : rate_) total += r;
        const double share = double(end_ - next_) * rate / total;
        n = std::min(n, std::max<int64_t>(1, int64_t(std::ceil(share / 2))));
    }
    // A run of a pass or more ends on a pass boundary: whole passes launch as whole passes.
    const int64_t whole_passes_end = (next_ + n) / units_.units_per_pass * units_.units_per_pass;
    if (n >= units_.units_per_pass && whole_passes_end > next_) n = whole_passes_end - next_;
    return std::min(n, end_ - next_);
}

std::optional<UnitQueue::Grab> UnitQueue::take_over(int worker, Clock::time_point now) {
    const double rate = rate_[size_t(worker)];
    if (rate <= 0) return std::nullopt;
    Held* best = nullptr;
    Clock::time_point best_end;
    for (Held& h : held_) {
        if (h.worker == worker || h.duplicated) continue;
        // A holder past its expected end is assumed to need as long again as it has taken.
        const Clock::time_point holder_end = h.expected_end > now ? h.expected_end : now + (now - h.start);
        if (now + time_for(h.begin, h.end, rate) < holder_end && (!best || holder_end > best_end)) {
            best = &h;
            best_end = holder_end;
        }
    }
    if (!best) return std::nullopt;
    best->duplicated = true;
    return Grab{best->begin, best->end, true, best->done};
}

int UnitQueue::ready_backlog() const {
    int n = 0;
    for (auto it = finished_.find(added_end_); it != finished_.end(); it = finished_.find(it->second.end)) ++n;
    return n;
}

std::optional<UnitQueue::Grab> UnitQueue::take(int worker) {
    std::unique_lock<std::mutex> lock(mutex_);
    for (;;) {
        if (aborted_) return leave();
        if (ready_backlog() >= kMaxReadyBacklog) {
            const Clock::time_point wait_start = Clock::now();
            changed_.wait(lock);
            backlog_wait_seconds_ += std::chrono::duration<double>(Clock::now() - wait_start).count();
            continue;
        }
        const Clock::time_point now = Clock::now();
        const double rate = rate_[size_t(worker)];
        auto expected_end = [&](int64_t begin, int64_t end) {
            return rate > 0 ? now + time_for(begin, end, rate) : Clock::time_point::max();
        };
        if (!given_back_.empty()) {
            Held h = given_back_.back();
            given_back_.pop_back();
            h.worker = worker;
            h.start = now;
            h.expected_end = expected_end(h.begin, h.end);
            h.duplicated = false;
            held_.push_back(h);
            return Grab{h.begin, h.end, false, h.done};
        }
        extend_end(worker);
        if (next_ < end_) {
            Held h;
            h.begin = next_;
            h.end = next_ + grab_size(worker);
            h.worker = worker;
            h.start = now;
            h.expected_end = expected_end(h.begin, h.end);
            h.done = std::make_shared<std::atomic<bool>>(false);
            next_ = h.end;
            held_.push_back(h);
            return Grab{h.begin, h.end, false, h.done};
        }
        if (held_.empty()) return leave();
        if (std::optional<Grab> copy = take_over(worker, now)) return copy;
        changed_.wait_for(lock, kTakeOverPoll);
    }
}

void UnitQueue::complete(int worker, const Grab& grab, std::vector<RenderedItems>&& results, double seconds) {
    {
        std::lock_guard<std::mutex> lock(mutex_);
        const uint64_t items = uint64_t(units_.items_in(grab.begin, grab.end));
        WorkerShare& share = shares_[size_t(worker)];
        share.busy_seconds += seconds;
        auto h = std::find_if(held_.begin(), held_.end(), [&](const Held& x) { return x.begin == grab.begin; });
        if (h == held_.end()) {
            // The other copy delivered first.
            share.wasted_samples += items;
            return;
        }
        if (seconds > 0) {
            double& rate = rate_[size_t(worker)];
            const double measured = double(items) / seconds;
            rate = rate > 0 ? 0.5 * (rate + measured) : measured;
        }
        h->done->store(true);
        held_.erase(h);
        share.samples += items;
        finished_[grab.begin] = Finished{grab.end, std::move(results)};
    }
    changed_.notify_all();
}

void UnitQueue::add_results() {
    for (;;) {
        Finished f;
        {
            std::unique_lock<std::mutex> lock(mutex_);
            changed_.wait(lock, [&] { return finished_.count(added_end_) > 0 || workers_running_ == 0; });
            auto it = finished_.find(added_end_);
            if (it == finished_.end()) return;  // every worker has left: nothing more comes
            f = std::move(it->second);
            finished_.erase(it);
        }
        // Outside mutex_, so workers go on meanwhile: this thread alone touches the film.
        const Clock::time_point add_start = Clock::now();
        ItemCounts counts;
        for (RenderedItems& r : f.results) {
            // A GPU's runs are millions of items, added by several threads (the film's sums
            // are memory-bound); a CPU device's far fewer, by this one.
            const int threads = std::clamp(r.item_count / kMinItemsPerAddThread, 1, max_add_threads_);
            add_to_film(*film_, r, threads);
            counts.add(r.counts);
            if (pool_) pool_->give(std::move(r));
        }
        const double add_seconds = std::chrono::duration<double>(Clock::now() - add_start).count();
        std::lock_guard<std::mutex> lock(mutex_);
        film_add_seconds_ += add_seconds;
        added_end_ = f.end;
        counts_.add(counts);
        film_->spp = units_.first_pass + int(added_end_ / units_.units_per_pass);
        const bool on_pass_boundary = added_end_ % units_.units_per_pass == 0;
        if (on_pass_boundary && first_pass_seconds_ == 0) first_pass_seconds_ = seconds_since_start();
        if (on_pass_boundary && snapshot_requested_) {
            snapshot_ = *film_;
            snapshot_requested_ = false;
        }
        changed_.notify_all();
    }
}

bool UnitQueue::fail(int worker, const Grab& grab) {
    std::lock_guard<std::mutex> lock(mutex_);
    rate_[size_t(worker)] = 0;
    if (workers_in_render_ <= 1) return false;
    --workers_in_render_;
    auto h = std::find_if(held_.begin(), held_.end(), [&](const Held& x) { return x.begin == grab.begin; });
    if (h != held_.end()) {
        if (grab.duplicate) {
            h->duplicated = false;  // the original goes on
        } else if (h->duplicated) {
            h->worker = -1;  // the copy goes on
        } else {
            given_back_.push_back(*h);
            held_.erase(h);
        }
    }
    changed_.notify_all();
    return true;
}

void UnitQueue::stop() {
    std::lock_guard<std::mutex> lock(mutex_);
    stopped_ = true;
    changed_.notify_all();
}

void UnitQueue::abort() {
    std::lock_guard<std::mutex> lock(mutex_);
    aborted_ = true;
    changed_.notify_all();
}

void UnitQueue::request_snapshot() {
    std::lock_guard<std::mutex> lock(mutex_);
    snapshot_requested_ = true;
}

std::optional<Film> UnitQueue::take_snapshot() {
    std::lock_guard<std::mutex> lock(mutex_);
    std::optional<Film> out = std::move(snapshot_);
    snapshot_.reset();
    return out;
}

bool UnitQueue::wait_finished(std::chrono::milliseconds period) {
    std::unique_lock<std::mutex> lock(mutex_);
    return changed_.wait_for(lock, period, [&] { return workers_running_ == 0; });
}

void UnitQueue::worker_exited() {
    std::lock_guard<std::mutex> lock(mutex_);
    --workers_running_;
    changed_.notify_all();
}

int UnitQueue::passes_done() {
    std::lock_guard<std::mutex> lock(mutex_);
    return int(added_end_ / units_.units_per_pass);
}

std::vector<UnitQueue::WorkerShare> UnitQueue::shares() {
    std::lock_guard<std::mutex> lock(mutex_);
    return shares_;
}

ItemCounts UnitQueue::counts() {
    std::lock_guard<std::mutex> lock(mutex_);
    return counts_;
}

double UnitQueue::film_add_seconds() {
    std::lock_guard<std::mutex> lock(mutex_);
    return film_add_seconds_;
}

double UnitQueue::backlog_wait_seconds() {
    std::lock_guard<std::mutex> lock(mutex_);
    return backlog_wait_seconds_;
}

double UnitQueue::first_pass_seconds() {
    std::lock_guard<std::mutex> lock(mutex_);
    return first_pass_seconds_;
}

}  // namespace clbdpt
