// Drives the render kernel: uploads the device scene, runs one launch per batch of pixels and
// sample index (two in flight: the device renders one while the host collects the other), and
// adds the camera contributions and t = 1 splat records into double-precision sums on the host
// in a fixed order, so the same scene, seed and spp on the same device give the same image bit
// for bit however the work is batched.
#pragma once

#include <chrono>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "device/opencl.h"
#include "device/pinned_host_array.h"
#include "film/film.h"
#include "film/rendered_items.h"
#include "render/caustic_photons.h"
#include "render/device_scene.h"
#include "render/features.h"
#include "render/scene_buffers.h"
#include "util/error.h"

namespace clbdpt {

struct RenderOptions {
    Integrator integrator = Integrator::Bdpt;
    SamplerKind sampler = SamplerKind::Sobol;
    int spp = 16;
    double time_budget = 0;  // seconds; > 0: render whole passes until spent (spp is then ignored)
    int max_depth = 5;
    // The strategy mix of the bdpt integrator (cl/strategies.h): light subpaths per pixel
    // sample (0 .. 1) and whether s >= 2, t >= 2 connections are made. pt and lt ignore it.
    float light_subpaths = 1.0f;
    bool inner_connections = true;
    // Russian roulette's first bounce in camera and in light subpaths (render/features.h,
    // cl/russian_roulette.h; kRouletteOff: none). The light subpaths' is part of the strategy
    // mix: the pilot chooses it with the rest.
    int roulette_camera_from = kRouletteCameraFrom;
    int roulette_light_from = kRouletteOff;
    // Whether the strategy pilot may choose roulette in the light subpaths of its bdpt mix
    // (render/strategy_pilot.h); the main render takes roulette_light_from from its choice.
    bool roulette_light_by_pilot = true;
    LightSampling light_sampling = LightSampling::Auto;  // how light samples choose lights
    uint32_t seed = 0;
    bool all_features = false;  // build the unspecialised kernel
    int batch_items = 0;        // work items per launch; 0 = automatic
    int local_size = 0;         // work-group size; 0 = automatic (small on CPUs, the driver's choice elsewhere)
    int collect_threads = 0;    // host threads that collect a launch's outputs; 0 = automatic (1 on CPUs)
    enum class StrategyImages { Off, Weighted, Unweighted };
    StrategyImages strategy_images = StrategyImages::Off;  // also record each (s, t) apart
    // A sample with a non-finite value (a bug) throws clbdpt::Error by default, so tests fail on
    // it; with drop_non_finite the sample (its pixel value and its splats) is left out and
    // counted in RenderStats instead, so a long render survives it (the command line).
    bool drop_non_finite = false;
    // bdpt: caustics seen through mirrors and glass, which only s = 0 samples (none where a
    // delta light casts them), estimated from each pass's caustic photons instead
    // (cl/caustic_merging.h), where the scene has them (scene_has_merged_caustics) and strategy
    // images are off; the merge radius in pixel footprints at the scene's centre
    // (render/caustic_photons.h).
    bool caustic_merging = false;
    double merge_radius = 1.0;
    // Tests and benchmarks only: the path tracer built as bdpt builds its strategies, from a
    // stored camera subpath (cl/kernels/render.cl, PT_FROM_SUBPATHS), instead of one vertex at
    // a time. The two give the same image bit for bit on PoCL (tests/path_tracer_test.cpp).
    bool pt_from_subpaths = false;
    // Tests only: the strategy pilot runs every candidate, the mixes between the ends too where
    // pt or lt leads clearly (render/strategy_pilot.h): that lead is measured with pass times,
    // which a loaded machine skews, and a test of the predicted errors must not depend on it.
    bool pilot_every_candidate = false;
    // Tests only: pixel whose sample 0 gets a NaN contribution (-1: none).
    int debug_nan_pixel = -1;
    // Tests only: launches after which this renderer's launches fail, as a driver's would
    // (-1: never).
    int debug_fail_after_launches = -1;
    // Benchmarks only: this renderer waits (factor - 1) times each launch's duration after it,
    // as a device `factor` times slower would take, leaving its cores to the others (> 1: on).
    double debug_slowdown = 1;
    // Keep each pixel's sum of squared sample values and its rays (Film::camera_sq,
    // camera_rays), which adaptive sampling plans from (render/adaptive.h).
    bool track_variance = false;
    // Called now and then from the rendering thread: passes done, passes planned (0 if
    // time-bound), seconds so far.
    std::function<void(int, int, double)> progress;
};

// Where a render's time goes (--profile): the render kernel and the read-back of its outputs
// from OpenCL profiling events, the host's work from a clock. On a GPU the host's work is what
// the device waits for, so each of its steps has a figure of its own.
struct RenderProfile {
    double kernel_seconds = 0;
    double transfer_seconds = 0;
    double accumulate_seconds = 0;  // a device thread collecting its launches' outputs
    double buffers_seconds = 0;     // a device thread making a run's result buffers
    double film_add_seconds = 0;    // the adding thread adding results to the film
    double backlog_wait_seconds = 0;  // device threads waiting for the adding thread
    void add(const RenderProfile& other) {
        kernel_seconds += other.kernel_seconds;
        transfer_seconds += other.transfer_seconds;
        accumulate_seconds += other.accumulate_seconds;
        buffers_seconds += other.buffers_seconds;
        film_add_seconds += other.film_add_seconds;
        backlog_wait_seconds += other.backlog_wait_seconds;
    }
};

struct RenderStats {
    double seconds = 0;           // wall time of the passes (excluding the kernel build)
    double first_pass_seconds = 0; // wall time until the first pass was done
    RenderProfile profile;
    void add(const RenderStats& other) {
        profile.add(other.profile);
        add_counts(ItemCounts{other.samples, other.rays, other.dropped_samples, other.first_dropped});
        build_seconds += other.build_seconds;
    }
    void add_counts(const ItemCounts& counts) {
        samples += counts.samples;
        rays += counts.rays;
        dropped_samples += counts.dropped_samples;
        for (const DroppedSample& d : counts.first_dropped)
            if (first_dropped.size() < kFirstDropped) first_dropped.push_back(d);
    }
    double build_seconds = 0;     // kernel build or cache load
    bool program_from_cache = false;
    uint64_t samples = 0;         // pixel samples (one camera + one light subpath each)
    uint64_t rays = 0;            // closest-hit and shadow rays traced
    uint64_t dropped_samples = 0; // samples left out for a non-finite value (drop_non_finite)
    static constexpr size_t kFirstDropped = ItemCounts::kFirstDropped;
    std::vector<DroppedSample> first_dropped;  // the first few of them
    std::vector<std::string> defines;
    // Devices that failed during the render and left it, their passes going to the others:
    // "device name: what failed".
    std::vector<std::string> dropped_devices;
    // Each device's part of a render on several (render_image): what it added to the image,
    // what it rendered in vain (a run another device delivered first), and its busy time.
    struct DeviceShare {
        std::string name;
        uint64_t samples = 0;
        uint64_t wasted_samples = 0;
        double busy_seconds = 0;
    };
    std::vector<DeviceShare> device_shares;
};

// One pass: one sample of every pixel (or, with pixel_stride k > 1, of every k-th pixel of every
// k-th row), its pixel positions drawn by sample position_sample_index of seed position_seed.
// On CPU devices PoCL runs a work-group's items in one thread and keeps every item's private
// path vertices on that thread's stack, so a large work-group at a large max depth overflows
// it (observed: a crash at max depth 7 with the driver's choice). Small groups cost nothing
// there (measured: the same samples/s at 1, 4 and 16 as with the driver's choice at depth 5).
// The renderer's work-group size on CPU devices, unless --local-size gives one.
constexpr int kCpuLocalSize = 16;

struct PassSpec {
    uint32_t sample_index = 0;
    uint32_t seed = 0;
    uint32_t position_sample_index = 0;
    uint32_t position_seed = 0;
    int pixel_stride = 1;
    // run_length > 0: the items are many samples of the pixels run_pixel .. run_pixel +
    // run_length - 1 instead: item i is pixel run_pixel + i % run_length at sample (and
    // position sample) index + i / run_length (adaptive sampling, render/adaptive.h).
    int run_pixel = 0;
    int run_length = 0;
    // Set: the run's pixels are (*run_pixels)[run_pixel + j], j < run_length, instead of
    // run_pixel + j (adaptive sampling's refined pixels, scattered over the film: one launch
    // for all of them rather than one per stretch of neighbours).
    std::shared_ptr<const std::vector<int>> run_pixels;
    // Only the camera image is kept (adaptive sampling's extra samples): a bdpt mix without inner
    // connections then traces no light subpaths (RenderParams::camera_image_only).
    bool camera_image_only = false;
    // bdpt: each item's subset moments are returned too (RenderedItems::subset_moments; the
    // strategy pilot's passes of full bdpt).
    bool subset_moments = false;
};

// Whether bdpt uses the (1,1) strategy, a light point joined straight to the lens, in `scene`:
// with a thin lens or media (cl/strategies.h).
bool uses_light_to_lens(const DeviceScene& scene);

class Renderer {
public:
    // buffers: the scene already uploaded to this device by another renderer (shared, so a
    // pilot's renderers and the main render hold one copy); null uploads it.
    Renderer(DeviceContext& device, const DeviceScene& scene, const RenderOptions& options,
             std::shared_ptr<SceneBuffers> buffers = nullptr);

    // Changes the bdpt strategy mix for the passes that follow (the efficiency pilot).
    void set_strategy_mix(float light_subpaths, bool inner_connections);
    // The same for Russian roulette's first bounce in light subpaths (kRouletteOff: none).
    void set_light_roulette(int from_bounce);
    const std::shared_ptr<SceneBuffers>& scene_buffers() const { return scene_buffers_; }
    const RenderOptions& options() const { return options_; }

    // Renders samples [first_sample, first_sample + count) of every pixel into film.
    void render_passes(Film& film, uint32_t first_sample, int count);
    void render_pass(Film& film, const PassSpec& pass);
    // Renders work items [first_item, first_item + item_count) of a pass and returns their
    // values, not yet added to any film (add_to_film), and not counted in stats() but for the
    // profile. cancelled, polled between launches: true abandons the items (the result is then
    // incomplete and the caller discards it). reuse: a result whose buffers (grown, not zeroed
    // where they are large enough) hold the new one (RenderedItemsPool).
    RenderedItems render_items(const PassSpec& pass, int first_item, int item_count,
                               const std::function<bool()>& cancelled = {}, RenderedItems reuse = {});

    const RenderStats& stats() const { return stats_; }
    // Zeroes samples, rays, dropped samples, profile and build time (the kernel flags and cache
    // flag stay).
    void reset_counters();
    const DeviceContext& device() const { return device_; }
    const DeviceScene& scene() const { return scene_; }
    // The caustic photons this renderer merges with; null without caustic merging.
    const CausticPhotons* caustic_photons() const { return caustic_photons_.get(); }

private:
    // One launch's outputs: its device buffers, their host copies, and the events that say
    // they are in. There are two, so that the device renders launch k + 1 while the host
    // collects launch k.
    struct LaunchSlot {
        cl::Buffer camera_out, splats, strategy_out;
        PinnedHostArray<cl_float4> camera_host;
        PinnedHostArray<SplatRecord> splats_host, strategy_host;
        cl::Event kernel_done, camera_read, splats_read, strategies_read;
        // Made at the first launch that asks for subset moments (PassSpec::subset_moments).
        cl::Buffer subset_moments;
        PinnedHostArray<cl_float2> subset_moments_host;
        cl::Event subset_moments_read;
        bool with_subset_moments = false;  // the launch in this slot asked for them
        std::chrono::steady_clock::time_point enqueued;
    };
    // A launch in flight: its slot and its items.
    struct InFlight {
        int slot;
        int first_item, item_count;
    };

    RenderParams batch_params(const PassSpec& pass, int first_item, int item_count) const;
    // The kernel's pixel list (PassSpec::run_pixels) and the list it holds.
    cl::Buffer run_pixels_;
    // Bound as the kernel's subset_moments where a launch asks for none.
    cl::Buffer no_subset_moments_;
    std::shared_ptr<const std::vector<int>> run_pixels_list_;
    // The error a failed OpenCL call while rendering is reported as.
    Error rendering_failure(const cl::Error& e) const;
    // Enqueues one launch of the render kernel over a batch's items and the read-back of its
    // outputs into `slot`, without waiting for them.
    void enqueue_launch(LaunchSlot& slot, const RenderParams& params, int item_count);
    // Waits for a launch's outputs, shrinks the following launches if it took too long, and
    // collects its outputs into `out`.
    void finish_launch(RenderedItems& out, const PassSpec& pass, const InFlight& launch);
    void limit_launch_size(double seconds, int item_count);
    // What collect_range gathered from a range of a launch's items: their splats in order, the
    // items (launch indices) with a non-finite value, and the rays traced.
    struct CollectedRange {
        std::vector<SplatRecord> splats;
        std::vector<int> dropped;
        uint64_t rays = 0;
    };
    void collect(RenderedItems& out, const PassSpec& pass, const LaunchSlot& slot, int first_item, int item_count);
    // Items [begin, end) of a launch: camera values to camera_dst (indexed by launch item), the
    // rest to `range`.
    void collect_range(CollectedRange& range, float* camera_dst, float* rays_dst, const LaunchSlot& slot, int begin,
                       int end) const;
    // Counts a sample with a non-finite value and leaves it out, or throws (drop_non_finite off).
    void drop_sample(RenderedItems& out, const LaunchSlot& slot, int item, int pixel, uint32_t sample_index) const;

    DeviceContext& device_;
    const DeviceScene& scene_;
    RenderOptions options_;
    RenderStats stats_;
    cl::Kernel kernel_;
    std::shared_ptr<SceneBuffers> scene_buffers_;
    LaunchSlot slots_[2];
    // When the last launch's outputs were in (the device is busy from then on while launches
    // wait in its queue).
    std::chrono::steady_clock::time_point last_done_;
    int batch_items_ = 0;   // work items each slot's output buffers hold
    int launch_items_ = 0;  // work items per launch now (at most batch_items_)
    int launches_ = 0;
    int local_size_ = 0;  // 0 = the driver's choice
    int collect_threads_ = 1;
    // The collecting threads' ranges, kept so that their splat lists' memory is reused.
    std::vector<CollectedRange> ranges_;
    int zsobol_log2_spp_ = 0, zsobol_base4_digits_ = 0;
    int splat_slots_ = 0;
    int strategy_slots_ = 0;
    std::unique_ptr<CausticPhotons> caustic_photons_;  // with caustic merging
};

}  // namespace clbdpt
