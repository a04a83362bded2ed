#include "render/render_loop.h"

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <exception>
#include <mutex>
#include <thread>

namespace clbdpt {

namespace {

using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point start) { return std::chrono::duration<double>(Clock::now() - start).count(); }

// How often the progress callback runs while passes are in flight.
constexpr auto kProgressInterval = std::chrono::milliseconds(200);

}  // namespace

Film render_image(const std::vector<Renderer*>& renderers, const RenderOptions& options, RenderStats* stats) {
    const Camera& camera = renderers.front()->scene().camera;
    const bool timed = options.time_budget > 0;
    const int planned = timed ? 0 : options.spp;
    std::atomic<int> next_pass{0}, passes_done{0};
    std::exception_ptr failure;
    std::mutex failure_mutex;
    std::atomic<bool> stop{false};
    std::vector<Film> films(renderers.size(), Film(camera.width, camera.height));
    const auto start = Clock::now();
    std::atomic<double> first_pass_seconds{0.0};

    auto worker = [&](size_t d) {
        try {
            for (;;) {
                if (stop) return;
                // A time-bound render has at least one pass, however small the budget.
                int pass = next_pass++;
                if (timed && pass > 0 && seconds_since(start) >= options.time_budget) return;
                if (!timed && pass >= options.spp) return;
                renderers[d]->render_passes(films[d], uint32_t(pass), 1);
                if (passes_done++ == 0) first_pass_seconds = seconds_since(start);
            }
        } catch (...) {
            std::lock_guard<std::mutex> lock(failure_mutex);
            if (!failure) failure = std::current_exception();
            stop = true;
        }
    };
    std::vector<std::thread> threads;
    for (size_t d = 0; d < renderers.size(); ++d) threads.emplace_back(worker, d);
    // The progress reporter waits on a condition variable, so the end of the render wakes it at
    // once (a plain sleep would add up to one interval to every render's time).
    std::mutex reporter_mutex;
    std::condition_variable reporter_wake;
    bool finished = false;
    std::thread reporter;
    if (options.progress) {
        reporter = std::thread([&] {
            std::unique_lock<std::mutex> lock(reporter_mutex);
            while (!reporter_wake.wait_for(lock, kProgressInterval, [&] { return finished; }))
                options.progress(passes_done, planned, seconds_since(start));
        });
    }
    for (std::thread& t : threads) t.join();
    const double seconds = seconds_since(start);
    {
        std::lock_guard<std::mutex> lock(reporter_mutex);
        finished = true;
    }
    reporter_wake.notify_all();
    if (reporter.joinable()) reporter.join();
    if (failure) std::rethrow_exception(failure);
    if (options.progress) options.progress(passes_done, planned, seconds);

    Film film(camera.width, camera.height);
    RenderStats total;
    total.defines = renderers.front()->stats().defines;
    total.program_from_cache = true;
    for (size_t d = 0; d < renderers.size(); ++d) {
        film.add(films[d]);
        total.add(renderers[d]->stats());
        total.program_from_cache = total.program_from_cache && renderers[d]->stats().program_from_cache;
    }
    total.seconds = seconds;
    total.first_pass_seconds = first_pass_seconds;
    if (stats) *stats = total;
    return film;
}

}  // namespace clbdpt
