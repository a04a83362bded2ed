#include "render/renderer.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <iterator>
#include <numeric>
#include <optional>
#include <thread>

#include <sys/resource.h>

#include "util/error.h"

namespace clbdpt {

namespace {

// Russian roulette's first bounce, as RenderOptions holds it (kRouletteOff: none).
int checked_roulette_bounce(int from_bounce) {
    if (from_bounce < 0) throw Error("Russian roulette's first bounce must be >= 0");
    return from_bounce;
}

// Output memory per launch is bounded: a camera float4 and max_depth + 1 splat records per item.
constexpr size_t kMaxBatchBytes = size_t(256) << 20;
constexpr int kMaxBatchItems = 1 << 18;

// So a work-group size on a CPU device is refused where its items' path vertices would not fit
// in a thread's stack: the stack limit (ulimit -s, which PoCL's threads get; 2 MiB assumed where
// it is unlimited) less a margin (kStackMargin, or a quarter of a smaller limit). A bdpt item
// keeps 2 max_depth + 3 vertices (PathVertex in cl/vertex.h: 112 bytes, 32 more with textures,
// 16 more with emission textures, 16 more with media) and kItemOtherBytes of other locals (a
// path tracer's item keeps fewer: the bound holds for it too). Measured with 8 MiB and 112-byte vertices: 512
// items at max depth 64 (7.5 MiB of vertices) rendered, 1024 crashed; with a 32 MiB limit 1024
// rendered; at max depth 5, 4096 items (6.0 MiB) rendered.
constexpr double kStackMargin = 256.0 * 1024;
constexpr double kItemOtherBytes = 512;

void check_cpu_group_fits_stack(int local_size, bool by_hand, int max_depth, const std::vector<std::string>& defines) {
    auto has = [&](const char* name) { return std::find(defines.begin(), defines.end(), name) != defines.end(); };
    const double vertex_bytes = 112.0 + (has("HAS_TEXTURES") ? 32 : 0) + (has("HAS_EMISSION_TEXTURES") ? 16 : 0) +
                                (has("HAS_MEDIA") ? 16 : 0);
    rlimit limit{};
    double stack = 2.0 * (1 << 20);
    if (getrlimit(RLIMIT_STACK, &limit) == 0 && limit.rlim_cur != RLIM_INFINITY) stack = double(limit.rlim_cur);
    const double per_item = (2.0 * max_depth + 3.0) * vertex_bytes + kItemOtherBytes;
    const double budget = stack - std::min(kStackMargin, stack / 4);
    if (double(local_size) * per_item <= budget) return;
    const int items_that_fit = int(budget / per_item);
    const int depth_that_fits = int(std::floor(((budget / local_size - kItemOtherBytes) / vertex_bytes - 3.0) / 2.0));
    char buf[500];
    std::snprintf(buf, sizeof buf,
                  "a CPU work-group of %d items (%s) at max depth %d needs about %.1f MiB of a thread's stack for "
                  "its path vertices, more than the stack limit of %.1f MiB (ulimit -s) allows: at this depth at most "
                  "%d items fit (--local-size), and with %d items at most max depth %d (--max-depth)",
                  local_size, by_hand ? "--local-size" : "the default", max_depth,
                  double(local_size) * per_item / (1 << 20), stack / (1 << 20), std::max(0, items_that_fit),
                  local_size, std::max(0, depth_that_fits));
    throw Error(buf);
}

// A launch that takes longer than this makes the following ones smaller: a GPU driver's
// watchdog kills long launches (about 2 s on some), and a long launch delays the progress bar
// and the reaction to an interrupt.
constexpr double kMaxLaunchSeconds = 0.25;
// ... but launches no smaller than this many work-groups, which keep a device busy.
constexpr int kMinLaunchGroups = 64;

// A GPU's launch is collected by up to this many host threads (collect), each taking at least
// kMinItemsPerCollectThread items; a CPU device's by its worker thread alone, as PoCL's threads
// use every core.
constexpr int kMaxCollectThreads = 8;
constexpr int kMinItemsPerCollectThread = 16384;

// render_bdpt(SCENE_KERNEL_ARGS, RenderParams params, camera_out, splats, run_pixels, subset_moments
//             [, strategy_out])
constexpr cl_uint kParamsArg = SceneBuffers::kSceneArgCount;
constexpr cl_uint kSubsetMomentsArg = kParamsArg + 4;
constexpr cl_uint kStrategyArg = kParamsArg + 5;
// With caustic merging (never with strategy images): photons, cells, slices, slice count.
constexpr cl_uint kMergeArg = kParamsArg + 5;

}  // namespace

Renderer::Renderer(DeviceContext& device, const DeviceScene& scene, const RenderOptions& options,
                   std::shared_ptr<SceneBuffers> buffers)
    : device_(device), scene_(scene), options_(options), scene_buffers_(std::move(buffers)) {
    if (options.max_depth < 0) throw Error("--max-depth must be >= 0");
    // A light tracer has no strategy for the directions a compensated map never samples.
    if (options.integrator == Integrator::Lt && scene.info.env_width > 0 &&
        scene.env_sampling != EnvironmentSampling::Luminance)
        throw Error("internal: the light tracer needs the environment map sampled by luminance (render/device_scene.h)");
    set_strategy_mix(options.light_subpaths, options.inner_connections);  // validates it
    set_light_roulette(options.roulette_light_from);
    checked_roulette_bounce(options.roulette_camera_from);
    if (options.sampler == SamplerKind::ZSobol) {
        // ZSobol orders a known number of samples per pixel (cl/rng.h).
        if (options.time_budget > 0) throw Error("--sampler zsobol needs --spp: it orders a known number of samples");
        while ((1 << zsobol_log2_spp_) < options.spp) ++zsobol_log2_spp_;
        int log2_resolution = 0;
        while ((1 << log2_resolution) < std::max(scene.camera.width, scene.camera.height)) ++log2_resolution;
        zsobol_base4_digits_ = log2_resolution + (zsobol_log2_spp_ + 1) / 2;
    }
    local_size_ = options.local_size > 0 ? options.local_size : (device.entry().type == "CPU" ? kCpuLocalSize : 0);
    collect_threads_ = options.collect_threads > 0 ? options.collect_threads
                       : device.entry().type == "CPU"
                           ? 1
                           : std::clamp(int(std::thread::hardware_concurrency()) / 2, 1, kMaxCollectThreads);
    stats_.defines = kernel_defines(scene, options.integrator, options.max_depth, options.all_features, options.sampler,
                                    options.light_sampling);
    if (device.entry().type == "CPU" && local_size_ > 0)
        check_cpu_group_fits_stack(local_size_, options.local_size > 0, options.max_depth, stats_.defines);
    if (options.strategy_images != RenderOptions::StrategyImages::Off) {
        stats_.defines.push_back("STRATEGY_IMAGES");
        if (options.strategy_images == RenderOptions::StrategyImages::Unweighted)
            stats_.defines.push_back("STRATEGY_IMAGES_UNWEIGHTED");
        strategy_slots_ = (options.max_depth + 2) * (options.max_depth + 3);
    }
    const bool merging = options.caustic_merging && options.integrator == Integrator::Bdpt &&
                         options.strategy_images == RenderOptions::StrategyImages::Off &&
                         scene_has_merged_caustics(scene);
    if (merging) stats_.defines.push_back("HAS_CAUSTIC_MERGING");
    if (options.pt_from_subpaths && options.integrator == Integrator::Pt) stats_.defines.push_back("PT_FROM_SUBPATHS");
    if (options.debug_nan_pixel >= 0) stats_.defines.push_back("DEBUG_NAN_PIXEL=" + std::to_string(options.debug_nan_pixel));
    const ProgramBuild& build = device.program("kernels/render.cl", stats_.defines);
    stats_.build_seconds = build.seconds;
    stats_.program_from_cache = build.from_cache;
    try {
        kernel_ = cl::Kernel(build.program, "render_bdpt");
        cl::Context& ctx = device.context();
        if (!scene_buffers_) {
            check_scene_fits_device(scene, device.entry());
            scene_buffers_ = std::make_shared<SceneBuffers>(ctx, scene);
        }
        // One splat record per light subpath vertex; none for a path tracer (SPLAT_SLOTS in
        // cl/kernels/render.cl).
        splat_slots_ = options.integrator == Integrator::Pt ? 0 : options.max_depth + 1;
        const size_t bytes_per_item = sizeof(cl_float4) + sizeof(SplatRecord) * size_t(splat_slots_ + strategy_slots_);
        const int pixels = scene.camera.width * scene.camera.height;
        const size_t slot_bytes = kMaxBatchBytes / std::size(slots_);
        size_t limit = std::min<size_t>(slot_bytes, device.entry().max_alloc) / bytes_per_item;
        // A GPU fills only with many items in flight, so its launches may span several passes
        // (DeviceWorker joins runs of passes; a 256 x 256 pass is 65 536 items). A CPU
        // device's stay within one pass: it is full with far fewer, and small images keep
        // small buffers.
        const size_t wanted = device.entry().type == "CPU" ? size_t(pixels) : size_t(kMaxBatchItems);
        batch_items_ = int(std::min<size_t>({wanted, size_t(kMaxBatchItems), limit}));
        if (options.batch_items > 0) batch_items_ = std::min(batch_items_, options.batch_items);
        batch_items_ = std::max(batch_items_, 1);
        launch_items_ = batch_items_;
        for (LaunchSlot& slot : slots_) {
            slot.camera_out = cl::Buffer(ctx, CL_MEM_WRITE_ONLY, sizeof(cl_float4) * batch_items_);
            slot.splats = cl::Buffer(ctx, CL_MEM_WRITE_ONLY,
                                     sizeof(SplatRecord) * std::max<size_t>(1, size_t(batch_items_) * splat_slots_));
            if (strategy_slots_ > 0) {
                slot.strategy_out =
                    cl::Buffer(ctx, CL_MEM_WRITE_ONLY, sizeof(SplatRecord) * size_t(batch_items_) * strategy_slots_);
                slot.strategy_host =
                    PinnedHostArray<SplatRecord>(ctx, device.queue(), size_t(batch_items_) * strategy_slots_);
            }
            slot.camera_host = PinnedHostArray<cl_float4>(ctx, device.queue(), size_t(batch_items_));
            slot.splats_host = PinnedHostArray<SplatRecord>(ctx, device.queue(), size_t(batch_items_) * splat_slots_);
        }
        scene_buffers_->set_args(kernel_);
        kernel_.setArg(kParamsArg + 1, slots_[0].camera_out);
        kernel_.setArg(kParamsArg + 2, slots_[0].splats);
        run_pixels_ = cl::Buffer(ctx, CL_MEM_READ_ONLY, sizeof(cl_int));  // no list yet: never read
        kernel_.setArg(kParamsArg + 3, run_pixels_);
        no_subset_moments_ = cl::Buffer(ctx, CL_MEM_WRITE_ONLY, sizeof(cl_float2));  // never written
        kernel_.setArg(kSubsetMomentsArg, no_subset_moments_);
        if (strategy_slots_ > 0) kernel_.setArg(kStrategyArg, slots_[0].strategy_out);
        if (merging) {
            // A time-bound render's passes are not known ahead.
            const int passes = options.time_budget > 0 ? 0 : std::max(options.spp, 1);
            const auto photons_start = std::chrono::steady_clock::now();
            caustic_photons_ = std::make_unique<CausticPhotons>(device, build.program, *scene_buffers_, scene,
                                                                options.seed, passes, options.merge_radius, local_size_);
            stats_.build_seconds +=
                std::chrono::duration<double>(std::chrono::steady_clock::now() - photons_start).count();
            caustic_photons_->set_args(kernel_, kMergeArg);
        }
        if (local_size_ > 0) {
            // PoCL compiles the work-group function of a kernel at its first launch: do that
            // now, with an empty launch, so it counts as build time and not as render time.
            // The launch is as wide as the widest this renderer makes: PoCL loads a function
            // for the width of its first launch and reuses it only for launches no wider, so
            // launches of varying widths would each load another (and devices doing that at
            // once trip an assertion in PoCL's cache of them, observed with two "basic"
            // devices, pocl 3.1).
            const auto warm_start = std::chrono::steady_clock::now();
            RenderParams empty{};  // pixel_count 0: every work item returns at once
            kernel_.setArg(kParamsArg, empty);
            const size_t local = size_t(local_size_);
            const size_t widest = (size_t(batch_items_) + local - 1) / local * local;
            device.queue().enqueueNDRangeKernel(kernel_, cl::NullRange, cl::NDRange(widest), cl::NDRange(local));
            device.queue().finish();
            stats_.build_seconds +=
                std::chrono::duration<double>(std::chrono::steady_clock::now() - warm_start).count();
        }
    } catch (const cl::Error& e) {
        throw Error(std::string("OpenCL: ") + e.what() + ": " + cl_error_name(e.err()) +
                    " while setting up the render on " + device.entry().name);
    }
}

void Renderer::reset_counters() {
    stats_.samples = 0;
    stats_.rays = 0;
    stats_.profile = RenderProfile();
    stats_.build_seconds = 0;
    stats_.dropped_samples = 0;
    stats_.first_dropped.clear();
}

void Renderer::set_light_roulette(int from_bounce) { options_.roulette_light_from = checked_roulette_bounce(from_bounce); }

void Renderer::set_strategy_mix(float light_subpaths, bool inner_connections) {
    if (!(light_subpaths >= 0.0f && light_subpaths <= 1.0f)) throw Error("light subpaths per sample must lie in [0, 1]");
    options_.light_subpaths = light_subpaths;
    options_.inner_connections = inner_connections;
}

RenderParams Renderer::batch_params(const PassSpec& pass, int first_item, int item_count) const {
    RenderParams params{};
    params.width = scene_.camera.width;
    params.height = scene_.camera.height;
    params.first_pixel = first_item;
    params.pixel_count = item_count;
    params.sample_index = pass.sample_index;
    params.seed = pass.seed;
    params.pixel_stride = pass.pixel_stride;
    params.run_pixel = pass.run_pixel;
    params.run_length = pass.run_length;
    params.run_listed = pass.run_pixels ? 1 : 0;
    params.position_sample_index = pass.position_sample_index;
    params.position_seed = pass.position_seed;
    params.zsobol_log2_spp = zsobol_log2_spp_;
    params.zsobol_base4_digits = zsobol_base4_digits_;
    const bool bdpt = options_.integrator == Integrator::Bdpt;
    params.light_subpaths = bdpt ? options_.light_subpaths : 1.0f;
    params.inner_connections = bdpt ? (options_.inner_connections ? 1 : 0) : 1;
    params.light_to_lens = uses_light_to_lens(scene_) ? 1 : 0;
    params.roulette_camera_from = options_.roulette_camera_from;
    params.roulette_light_from = options_.roulette_light_from;
    params.camera_image_only = pass.camera_image_only ? 1 : 0;
    params.subset_moments = pass.subset_moments && bdpt ? 1 : 0;
    return params;
}

bool uses_light_to_lens(const DeviceScene& scene) { return scene.camera.lens_radius > 0 || !scene.media.empty(); }

Error Renderer::rendering_failure(const cl::Error& e) const {
    return Error(std::string("OpenCL: ") + e.what() + ": " + cl_error_name(e.err()) + " while rendering on " +
                 device_.entry().name);
}

void Renderer::enqueue_launch(LaunchSlot& slot, const RenderParams& params, int item_count) {
    cl::CommandQueue& queue = device_.queue();
    try {
        if (caustic_photons_) {
            // The passes of the launch's samples (item i: sample index + i / run_length).
            const uint32_t first = params.sample_index + (params.run_length > 0 ? params.first_pixel / params.run_length : 0);
            const uint32_t last = params.sample_index +
                                  (params.run_length > 0 ? (params.first_pixel + item_count - 1) / params.run_length : 0);
            caustic_photons_->ensure(first, last);
            caustic_photons_->set_args(kernel_, kMergeArg);
        }
        kernel_.setArg(kParamsArg, params);
        kernel_.setArg(kParamsArg + 1, slot.camera_out);
        kernel_.setArg(kParamsArg + 2, slot.splats);
        kernel_.setArg(kParamsArg + 3, run_pixels_);
        if (params.subset_moments && slot.subset_moments_host.size() == 0) {
            // Only the pilot's passes of full bdpt ask for them: made at the first.
            slot.subset_moments = cl::Buffer(device_.context(), CL_MEM_WRITE_ONLY, sizeof(cl_float2) * batch_items_);
            slot.subset_moments_host = PinnedHostArray<cl_float2>(device_.context(), queue, size_t(batch_items_));
        }
        kernel_.setArg(kSubsetMomentsArg, params.subset_moments ? slot.subset_moments : no_subset_moments_);
        if (strategy_slots_ > 0) kernel_.setArg(kStrategyArg, slot.strategy_out);
        slot.enqueued = std::chrono::steady_clock::now();
        if (local_size_ > 0) {
            const size_t local = size_t(local_size_);
            const size_t global = (size_t(item_count) + local - 1) / local * local;
            queue.enqueueNDRangeKernel(kernel_, cl::NullRange, cl::NDRange(global), cl::NDRange(local), nullptr,
                                       &slot.kernel_done);
        } else {
            queue.enqueueNDRangeKernel(kernel_, cl::NullRange, cl::NDRange(size_t(item_count)), cl::NullRange, nullptr,
                                       &slot.kernel_done);
        }
        queue.enqueueReadBuffer(slot.camera_out, CL_FALSE, 0, sizeof(cl_float4) * item_count, slot.camera_host.data(),
                                nullptr, &slot.camera_read);
        if (splat_slots_ > 0)
            queue.enqueueReadBuffer(slot.splats, CL_FALSE, 0, sizeof(SplatRecord) * size_t(item_count) * splat_slots_,
                                    slot.splats_host.data(), nullptr, &slot.splats_read);
        if (strategy_slots_ > 0)
            queue.enqueueReadBuffer(slot.strategy_out, CL_FALSE, 0,
                                    sizeof(SplatRecord) * size_t(item_count) * strategy_slots_,
                                    slot.strategy_host.data(), nullptr, &slot.strategies_read);
        slot.with_subset_moments = params.subset_moments != 0;
        if (slot.with_subset_moments)
            queue.enqueueReadBuffer(slot.subset_moments, CL_FALSE, 0, sizeof(cl_float2) * item_count,
                                    slot.subset_moments_host.data(), nullptr, &slot.subset_moments_read);
        queue.flush();
    } catch (const cl::Error& e) {
        throw rendering_failure(e);
    }
}

void Renderer::finish_launch(RenderedItems& out, const PassSpec& pass, const InFlight& launch) {
    LaunchSlot& slot = slots_[launch.slot];
    try {
        // The queue is in order: the last read being in means the kernel and the other reads are.
        (strategy_slots_ > 0 ? slot.strategies_read : splat_slots_ > 0 ? slot.splats_read : slot.camera_read).wait();
        if (slot.with_subset_moments) slot.subset_moments_read.wait();
        if (device_.profiling()) {
            auto seconds = [](const cl::Event& e) {
                return 1e-9 * double(e.getProfilingInfo<CL_PROFILING_COMMAND_END>() -
                                     e.getProfilingInfo<CL_PROFILING_COMMAND_START>());
            };
            stats_.profile.kernel_seconds += seconds(slot.kernel_done);
            stats_.profile.transfer_seconds += seconds(slot.camera_read);
            if (splat_slots_ > 0) stats_.profile.transfer_seconds += seconds(slot.splats_read);
            if (strategy_slots_ > 0) stats_.profile.transfer_seconds += seconds(slot.strategies_read);
        }
    } catch (const cl::Error& e) {
        throw rendering_failure(e);
    }
    // The device worked on this launch from when it was enqueued or the one before it was done,
    // whichever was later.
    const auto done = std::chrono::steady_clock::now();
    const double launch_seconds = std::chrono::duration<double>(done - std::max(slot.enqueued, last_done_)).count();
    last_done_ = done;
    limit_launch_size(launch_seconds, launch.item_count);
    collect(out, pass, slot, launch.first_item, launch.item_count);
    stats_.profile.accumulate_seconds +=
        std::chrono::duration<double>(std::chrono::steady_clock::now() - done).count();
    if (options_.debug_slowdown > 1)
        std::this_thread::sleep_for(std::chrono::duration<double>((options_.debug_slowdown - 1) * launch_seconds));
}

void Renderer::drop_sample(RenderedItems& out, const LaunchSlot& slot, int item, int pixel,
                           uint32_t sample_index) const {
    const cl_float4& c = slot.camera_host[size_t(item)];
    DroppedSample d;
    d.x = pixel % scene_.camera.width;
    d.y = pixel / scene_.camera.width;
    d.sample = sample_index;
    if (c.s[3] < 0) {
        const int strategy = int(-1.0f - c.s[3]), stride = options_.max_depth + 3;
        d.s = strategy / stride;
        d.t = strategy % stride;
    }
    if (!options_.drop_non_finite)
        throw Error("non-finite radiance at pixel (" + std::to_string(d.x) + ", " + std::to_string(d.y) + ") sample " +
                    std::to_string(d.sample) +
                    (d.s >= 0 ? " from strategy s=" + std::to_string(d.s) + " t=" + std::to_string(d.t) : "") +
                    " (a bug: please report it with the scene)");
    ++out.counts.dropped_samples;
    if (out.counts.first_dropped.size() < ItemCounts::kFirstDropped) out.counts.first_dropped.push_back(d);
}

void Renderer::collect_range(CollectedRange& range, float* camera_dst, float* rays_dst, const LaunchSlot& slot,
                             int begin, int end) const {
    // One pass over the outputs, pointers stepping along: on a GPU this loop is what the
    // device waits for.
    const cl_float4* camera = slot.camera_host.data() + begin;
    const SplatRecord* splats = slot.splats_host.data() + size_t(begin) * splat_slots_;
    float* dst = camera_dst + size_t(begin) * 3;
    uint64_t rays = 0;
    for (int i = begin; i < end; ++i, ++camera, dst += 3, splats += splat_slots_) {
        const float* c = camera->s;
        // A non-finite value is a bug: the kernel names the first strategy that gave one in w
        // (cl/kernels/render.cl), and a sum that overflowed is caught here. The item's splats go
        // in as they are checked, and come out again if one is not finite.
        const size_t splats_before = range.splats.size();
        bool finite = c[3] >= 0 && std::isfinite(c[0]) && std::isfinite(c[1]) && std::isfinite(c[2]);
        for (int k = 0; k < splat_slots_ && finite; ++k) {
            const SplatRecord& r = splats[k];
            if (r.pixel < 0) continue;
            finite = std::isfinite(r.r) && std::isfinite(r.g) && std::isfinite(r.b);
            range.splats.push_back(r);
        }
        if (!finite) {
            range.splats.resize(splats_before);
            range.dropped.push_back(i);
            // Every item is written: the result's buffers may be reused ones, not zeroed.
            dst[0] = dst[1] = dst[2] = 0.0f;
            if (rays_dst) rays_dst[i] = 0.0f;
            continue;
        }
        dst[0] = c[0];
        dst[1] = c[1];
        dst[2] = c[2];
        rays += uint32_t(c[3]);  // a whole number of rays, far below 2^24
        if (rays_dst) rays_dst[i] = c[3];
    }
    range.rays = rays;
}

void Renderer::collect(RenderedItems& out, const PassSpec& pass, const LaunchSlot& slot, int first_item,
                       int item_count) {
    // Item i of this launch is item first_item - out.first_item + i of `out`.
    const int offset = first_item - out.first_item;
    float* camera_dst = &out.camera[size_t(offset) * 3];
    float* rays_dst = out.rays.empty() ? nullptr : &out.rays[size_t(offset)];
    // Ranges of the launch's items are collected by threads of their own where there are
    // several (a GPU's launches; a CPU device's cores are busy rendering), each into its own
    // splat list; the lists are joined in item order, so the result does not depend on it.
    const int min_items = options_.collect_threads > 0 ? 1 : kMinItemsPerCollectThread;  // as asked (tests)
    const int threads = std::min(collect_threads_, std::max(1, item_count / min_items));
    // The ranges' lists keep their memory from launch to launch, rather than each launch's
    // threads allocating theirs afresh (on an H200, with reused result buffers too, bdpt's
    // collection took 24-26 ns a sample against 39: docs/throughput.md, "a third lease").
    ranges_.resize(size_t(threads));
    for (CollectedRange& r : ranges_) {
        r.splats.clear();
        r.dropped.clear();
        r.rays = 0;
    }
    if (threads == 1) {
        ranges_[0].splats.swap(out.splats);  // appended to in place
        collect_range(ranges_[0], camera_dst, rays_dst, slot, 0, item_count);
        ranges_[0].splats.swap(out.splats);
    } else {
        std::vector<std::thread> workers;
        for (int t = 0; t < threads; ++t) {
            const int begin = int(int64_t(item_count) * t / threads), end = int(int64_t(item_count) * (t + 1) / threads);
            workers.emplace_back(
                [&, t, begin, end] { collect_range(ranges_[size_t(t)], camera_dst, rays_dst, slot, begin, end); });
        }
        for (std::thread& w : workers) w.join();
        // The lists are joined in item order, each copied by a thread of its own.
        size_t joined = out.splats.size();
        out.splats.resize(joined + std::accumulate(ranges_.begin(), ranges_.end(), size_t(0),
                                                   [](size_t n, const CollectedRange& r) { return n + r.splats.size(); }));
        workers.clear();
        for (const CollectedRange& r : ranges_) {
            if (!r.splats.empty())
                workers.emplace_back([&r, dst = out.splats.data() + joined] {
                    std::memcpy(static_cast<void*>(dst), r.splats.data(), sizeof(SplatRecord) * r.splats.size());
                });
            joined += r.splats.size();
        }
        for (std::thread& w : workers) w.join();
    }
    for (const CollectedRange& r : ranges_) {
        out.counts.rays += r.rays;
        for (int i : r.dropped) {
            const int run_item = first_item + i;
            const int pixel = run_item_pixel(run_item, scene_.camera.width, scene_.camera.height, pass.pixel_stride,
                                             pass.run_pixel, pass.run_length, pass.run_pixels.get());
            // A run's items go through its pixels once per sample (PassSpec::run_length).
            const uint32_t run_sample = pass.run_length > 0 ? uint32_t(run_item / pass.run_length) : 0u;
            drop_sample(out, slot, i, pixel, pass.sample_index + run_sample);
            out.dropped_items.push_back(offset + i);
        }
    }
    if (!out.subset_moments.empty()) {
        for (int i = 0; i < item_count; ++i) {
            const cl_float2& m = slot.subset_moments_host[size_t(i)];
            out.subset_moments[size_t(offset + i) * 2] = m.s[0];
            out.subset_moments[size_t(offset + i) * 2 + 1] = m.s[1];
        }
        for (int i : out.dropped_items)  // a dropped sample's moments are not finite either
            if (i >= offset) out.subset_moments[size_t(i) * 2] = out.subset_moments[size_t(i) * 2 + 1] = 0.0f;
    }
    if (strategy_slots_ > 0) {
        auto dropped = std::lower_bound(out.dropped_items.begin(), out.dropped_items.end(), offset);
        for (int i = 0; i < item_count; ++i) {
            if (dropped != out.dropped_items.end() && *dropped == offset + i) {
                ++dropped;
                continue;
            }
            const SplatRecord* records = slot.strategy_host.data() + size_t(i) * strategy_slots_;
            for (int slot = 0; slot < strategy_slots_; ++slot)
                if (records[slot].pixel >= 0) out.strategy_splats.push_back({slot, records[slot]});
        }
    }
    out.counts.samples += uint64_t(item_count);
}

void Renderer::limit_launch_size(double seconds, int item_count) {
    // Only a full-sized launch says how long one takes; the image does not depend on the
    // launch size (the host adds items in pixel order whatever the batches).
    if (seconds <= kMaxLaunchSeconds || item_count < launch_items_) return;
    const int granule = std::max(local_size_, 1);
    // Aim at half the limit, so that launches near it do not shrink again and again.
    const int shorter = int(double(launch_items_) * 0.5 * kMaxLaunchSeconds / seconds) / granule * granule;
    launch_items_ = std::max(shorter, std::min(launch_items_, kMinLaunchGroups * granule));
}

void Renderer::render_passes(Film& film, uint32_t first_sample, int count) {
    for (int k = 0; k < count; ++k) {
        PassSpec pass;
        pass.sample_index = pass.position_sample_index = first_sample + uint32_t(k);
        pass.seed = pass.position_seed = options_.seed;
        render_pass(film, pass);
    }
}

namespace {

// Resizes a reused buffer without copying or zeroing what it held where it is large enough.
template <class T>
void resize_reused(std::vector<T>& v, size_t n) {
    if (v.capacity() < n) v.clear();  // growing would copy the old values first
    v.resize(n);
}

}  // namespace

RenderedItems Renderer::render_items(const PassSpec& pass, int first_item, int item_count,
                                    const std::function<bool()>& cancelled, RenderedItems reuse) {
    if (pass.pixel_stride < 1) throw Error("pixel stride must be at least 1");
    RenderedItems out;
    out.sample_index = pass.sample_index;
    out.first_item = first_item;
    out.item_count = item_count;
    out.pixel_stride = pass.pixel_stride;
    out.run_pixel = pass.run_pixel;
    out.run_length = pass.run_length;
    out.run_pixels = pass.run_pixels;
    if (pass.run_pixels && pass.run_pixels != run_pixels_list_) {
        // The list travels once per render_items call that brings a new one.
        try {
            const std::vector<int>& list = *pass.run_pixels;
            run_pixels_ = cl::Buffer(device_.context(), CL_MEM_READ_ONLY, sizeof(cl_int) * std::max<size_t>(1, list.size()));
            if (!list.empty())
                device_.queue().enqueueWriteBuffer(run_pixels_, CL_TRUE, 0, sizeof(cl_int) * list.size(), list.data());
        } catch (const cl::Error& e) {
            throw rendering_failure(e);
        }
        run_pixels_list_ = pass.run_pixels;
    }
    const auto buffers_start = std::chrono::steady_clock::now();
    // Every item's camera value and rays are written when its launch is collected.
    out.camera = std::move(reuse.camera);
    resize_reused(out.camera, size_t(item_count) * 3);
    out.rays = std::move(reuse.rays);
    resize_reused(out.rays, size_t(item_count));
    out.splats = std::move(reuse.splats);
    out.splats.clear();
    out.dropped_items = std::move(reuse.dropped_items);
    out.dropped_items.clear();
    out.strategy_splats = std::move(reuse.strategy_splats);
    out.strategy_splats.clear();
    if (pass.subset_moments && options_.integrator == Integrator::Bdpt) out.subset_moments.assign(size_t(item_count) * 2, 0.0f);
    // Light subpaths leave a few splats each (measured: 2-4 at max depth 5 on the bundled
    // scenes); reserving them saves most of the vector's regrowth.
    if (splat_slots_ > 0) out.splats.reserve(size_t(item_count) * std::min(splat_slots_, 4));
    stats_.profile.buffers_seconds +=
        std::chrono::duration<double>(std::chrono::steady_clock::now() - buffers_start).count();
    out.strategy_slots = strategy_slots_;
    out.strategy_stride = strategy_slots_ > 0 ? options_.max_depth + 3 : 0;
    // Launch k + 1 is enqueued before launch k is collected, so the device does not wait for
    // the host; the items are still collected in order.
    std::optional<InFlight> in_flight;
    int next_slot = 0;
    try {
        for (int first = first_item, count, end = first_item + item_count; first < end; first += count) {
            if (cancelled && cancelled()) break;
            count = std::min(launch_items_, end - first);
            if (options_.debug_fail_after_launches >= 0 && launches_ >= options_.debug_fail_after_launches)
                throw Error("OpenCL: launch failed (injected by --debug-fail-device) while rendering on " +
                            device_.entry().name);
            ++launches_;
            enqueue_launch(slots_[next_slot], batch_params(pass, first, count), count);
            if (in_flight) finish_launch(out, pass, *in_flight);
            in_flight = InFlight{next_slot, first, count};
            next_slot = 1 - next_slot;
        }
        if (in_flight) finish_launch(out, pass, *in_flight);
    } catch (...) {
        // A launch may still be writing into a slot's host copies: let it end first.
        try {
            device_.queue().finish();
        } catch (const cl::Error&) {
        }
        throw;
    }
    return out;
}

void Renderer::render_pass(Film& film, const PassSpec& pass) {
    const int items = render_item_count(scene_.camera.width, scene_.camera.height, pass.pixel_stride);
    const RenderedItems rendered = render_items(pass, 0, items);
    add_to_film(film, rendered);
    stats_.add_counts(rendered.counts);
    ++film.spp;
}

}  // namespace clbdpt
