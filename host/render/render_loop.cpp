#include "render/render_loop.h"

#include <chrono>
#include <exception>
#include <mutex>
#include <string>
#include <thread>

#include "render/unit_queue.h"

namespace clbdpt {

namespace {

using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point start) { return std::chrono::duration<double>(Clock::now() - start).count(); }

// How often the progress callback runs while passes are in flight.
constexpr auto kProgressInterval = std::chrono::milliseconds(200);

}  // namespace

std::string DeviceWorker::name() const { return renderer_.device().entry().name; }

std::vector<RenderedItems> DeviceWorker::render(const std::vector<ItemRun>& runs,
                                                const std::function<bool()>& cancelled) {
    // Runs of consecutive passes are rendered as one run through every pixel, many samples
    // each (PassSpec::run_length), so that a device's launches are as wide as its batch and
    // pipelined across the passes. At the bundled scenes' 256 x 256 a pass is one launch of
    // 65 536 items: a GPU otherwise gets one small launch at a time and waits for the host
    // between passes. The items keep their order, so the film is the same bit for bit.
    const Camera& camera = renderer_.scene().camera;
    const int pass_items = camera.width * camera.height;
    std::vector<RenderedItems> out;
    for (size_t k = 0; k < runs.size();) {
        if (cancelled && cancelled()) break;
        const ItemRun& first = runs[k];
        int64_t items = 0;
        const size_t n = joinable_runs(runs, k, pass_items, kMaxMergedItems, &items);
        PassSpec pass;
        pass.sample_index = pass.position_sample_index = first.pass;
        pass.seed = pass.position_seed = renderer_.options().seed;
        if (n > 1) pass.run_length = pass_items;  // item i: pixel i % pass_items, pass + i / pass_items
        out.push_back(renderer_.render_items(pass, first.first_item, int(items), cancelled,
                                             pool_ ? pool_->take() : RenderedItems{}));
        k += n;
    }
    return out;
}

Film render_image(const std::vector<UnitWorker*>& workers, int width, int height, const RenderOptions& options,
                  RenderStats* stats, const RenderSchedule& schedule) {
    const bool timed = options.time_budget > 0;
    const int first_pass = schedule.resume ? schedule.resume->spp : 0;
    const int planned = timed ? 0 : options.spp;
    Film film = schedule.resume ? *schedule.resume : Film(width, height);
    if (options.track_variance && film.camera_sq.empty()) film.camera_sq.assign(size_t(width) * height, 0.0);
    if (options.track_variance && film.camera_rays.empty()) film.camera_rays.assign(size_t(width) * height, 0.0);
    if (options.track_variance && planned >= 2 && film.camera_late.empty()) {
        film.camera_late.assign(size_t(width) * height * 3, 0.0);
        film.late_from = uint32_t(planned / 2);
    }
    const WorkUnits units(width * height, first_pass);
    const auto start = Clock::now();
    UnitQueue queue(units, &film, options.spp - first_pass, options.time_budget, start, int(workers.size()));
    // Results come back once added, for the workers to reuse their buffers.
    RenderedItemsPool pool;
    queue.set_result_pool(&pool);
    for (UnitWorker* w : workers) w->set_result_pool(&pool);
    std::exception_ptr failure;
    std::mutex failure_mutex;
    std::vector<std::string> dropped_devices;

    auto worker = [&](size_t w) {
        for (std::optional<UnitQueue::Grab> grab; (grab = queue.take(int(w)));) {
            const auto grab_start = Clock::now();
            std::vector<RenderedItems> results;
            try {
                const auto done = grab->done;
                results = workers[w]->render(units.runs(grab->begin, grab->end), [done] { return done->load(); });
            } catch (const std::exception& e) {
                std::lock_guard<std::mutex> lock(failure_mutex);
                if (queue.fail(int(w), *grab)) {
                    dropped_devices.push_back(workers[w]->name() + ": " + e.what());
                    if (schedule.device_dropped) schedule.device_dropped(dropped_devices.back());
                } else {
                    if (!failure) failure = std::current_exception();
                    queue.abort();
                }
                break;
            }
            queue.complete(int(w), *grab, std::move(results), seconds_since(grab_start));
        }
        queue.worker_exited();
    };
    if (schedule.stop_requested && schedule.stop_requested()) queue.stop();
    std::vector<std::thread> threads;
    for (size_t w = 0; w < workers.size(); ++w) threads.emplace_back(worker, w);
    // Adding to the film has a thread of its own: a fast device (a GPU renders a pass in
    // milliseconds) would otherwise wait for it after every run.
    std::thread adder([&queue] { queue.add_results(); });

    // This thread reports progress, watches for a stop request and hands out the snapshots.
    auto last_checkpoint = Clock::now();
    int checkpointed_spp = first_pass;
    for (;;) {
        const bool finished = queue.wait_finished(kProgressInterval);
        if (schedule.stop_requested && schedule.stop_requested()) queue.stop();
        if (options.progress) options.progress(first_pass + queue.passes_done(), planned, seconds_since(start));
        if (schedule.checkpoint && schedule.checkpoint_seconds > 0) {
            // Written while the devices go on; a snapshot with no new pass is not written again.
            std::optional<Film> snapshot = queue.take_snapshot();
            if (snapshot && snapshot->spp > checkpointed_spp) {
                try {
                    schedule.checkpoint(*snapshot);
                } catch (...) {
                    // Rethrown once the device threads are joined.
                    std::lock_guard<std::mutex> lock(failure_mutex);
                    if (!failure) failure = std::current_exception();
                    queue.abort();
                }
                checkpointed_spp = snapshot->spp;
            }
            if (seconds_since(last_checkpoint) >= schedule.checkpoint_seconds) {
                queue.request_snapshot();
                last_checkpoint = Clock::now();
            }
        }
        if (finished) break;
    }
    for (std::thread& t : threads) t.join();
    adder.join();
    for (UnitWorker* w : workers) w->set_result_pool(nullptr);
    const double seconds = seconds_since(start);
    if (failure) std::rethrow_exception(failure);
    if (options.progress) options.progress(first_pass + queue.passes_done(), planned, seconds);

    if (stats) {
        RenderStats total;
        total.add_counts(queue.counts());
        total.seconds = seconds;
        total.first_pass_seconds = queue.first_pass_seconds();
        total.profile.film_add_seconds = queue.film_add_seconds();
        total.profile.backlog_wait_seconds = queue.backlog_wait_seconds();
        total.dropped_devices = dropped_devices;
        const std::vector<UnitQueue::WorkerShare> shares = queue.shares();
        for (size_t w = 0; w < workers.size(); ++w)
            total.device_shares.push_back(
                {workers[w]->name(), shares[w].samples, shares[w].wasted_samples, shares[w].busy_seconds});
        *stats = total;
    }
    return film;
}

Film render_image(const std::vector<Renderer*>& renderers, const RenderOptions& options, RenderStats* stats,
                  const RenderSchedule& schedule, const std::vector<UnitWorker*>& more_workers) {
    std::vector<std::unique_ptr<DeviceWorker>> devices;
    std::vector<UnitWorker*> workers;
    for (Renderer* r : renderers) {
        devices.push_back(std::make_unique<DeviceWorker>(*r));
        workers.push_back(devices.back().get());
    }
    workers.insert(workers.end(), more_workers.begin(), more_workers.end());
    const Camera& camera = renderers.front()->scene().camera;
    RenderStats total;
    Film film = render_image(workers, camera.width, camera.height, options, &total, schedule);
    total.defines = renderers.front()->stats().defines;
    total.program_from_cache = true;
    for (Renderer* r : renderers) {
        const RenderStats& rs = r->stats();
        total.profile.add(rs.profile);
        total.build_seconds += rs.build_seconds;
        total.program_from_cache = total.program_from_cache && rs.program_from_cache;
    }
    if (stats) *stats = total;
    return film;
}

}  // namespace clbdpt
