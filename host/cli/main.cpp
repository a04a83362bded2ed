// clbdpt command line: `clbdpt devices` and `clbdpt render SCENE [options]`.
// Every failure ends as one line "clbdpt: error: ..." on stderr and exit status 1; nothing is
// written unless the render finished.
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <chrono>
#include <filesystem>
#include <cstdio>
#include <memory>
#include <iostream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "cli/interrupt.h"
#include "device/opencl.h"
#include "film/checkpoint.h"
#include "film/image_io.h"
#include "film/image_io_process.h"
#include "mpi/cluster.h"
#include "render/adaptive.h"
#include "render/aov.h"
#include "render/automatic_view.h"
#include "render/device_scene.h"
#include "render/features.h"
#include "render/render_loop.h"
#include "render/renderer.h"
#include "render/scene_fingerprint.h"
#include "render/strategy_pilot.h"
#include "scene/scene.h"
#include "util/atomic_file.h"
#include "util/error.h"

namespace clbdpt {
namespace {

struct RenderArgs {
    std::string scene;
    std::string output;
    int spp = -1;
    double time_budget = 0;
    int max_depth = -1;
    long long seed = -1;
    std::string device;
    int width = 0;
    int height = 0;
    std::string stats;
    std::string integrator = "auto";
    float light_subpaths = -1;  // < 0: not given
    std::string connections;    // "on", "off" or empty
    std::string light_samples = "auto";
    std::string russian_roulette = "auto";  // auto, off or a bounce
    std::string sampler;  // empty: sobol
    std::string adaptive = "on";
    std::string caustic_merging = "auto";
    double merge_radius = 1.0;
    std::string aov;
    std::string strategy_images;
    bool unweighted = false;
    int local_size = 0;
    bool profile = false;
    bool verbose = false;
    bool all_features = false;
    // Camera overrides (pbrt's LookAt order: eye, target, up).
    std::vector<float> lookat;
    std::vector<float> eye, target, up;
    float fov = 0;
    bool no_default_light = false;
    int debug_nan_pixel = -1;  // hidden: tests of the dropped-sample path
    std::string debug_fail_device;  // hidden: "K:N", device K's launches fail after N
    int batch_items = 0;            // hidden: work items per launch at most
    int collect_threads = 0;        // hidden: host threads collecting a launch (benchmarks)
    std::string checkpoint;         // --checkpoint FILE
    double checkpoint_every = 60;   // seconds
    std::string resume;             // --resume FILE
    std::string debug_exit_process; // hidden: "R:N", MPI process R ends abruptly after N runs
    std::string debug_slow_device;  // hidden: "K:F", device K runs F times slower (benchmarks)
    bool debug_pt_from_subpaths = false;  // hidden: the generic path tracer (benchmarks)
};

// Applies the command line's camera overrides. Where the scene's camera was automatic and only
// the field of view changes, the bounds are framed again for the new angle.
void apply_camera_overrides(const RenderArgs& args, Scene* scene) {
    auto vec = [](const std::vector<float>& v, size_t at) { return Vec3(v[at], v[at + 1], v[at + 2]); };
    CameraDesc& camera = scene->camera;
    const bool aimed = !args.lookat.empty() || !args.eye.empty() || !args.target.empty();
    if (args.fov > 0) {
        if (scene->camera_is_automatic && !aimed) camera = frame_bounds(scene->bounds, args.fov);
        camera.fov_degrees = args.fov;
    }
    if (!args.lookat.empty()) {
        camera.eye = vec(args.lookat, 0);
        camera.target = vec(args.lookat, 3);
        camera.up = vec(args.lookat, 6);
    }
    if (!args.eye.empty()) camera.eye = vec(args.eye, 0);
    if (!args.target.empty()) camera.target = vec(args.target, 0);
    if (!args.up.empty()) camera.up = vec(args.up, 0);
    if (aimed || !args.up.empty()) {
        scene->camera_is_automatic = false;
        const Vec3 view = camera.target - camera.eye;
        if (!(length(view) > 0.0f)) throw Error("camera: the target must differ from the eye");
        if (!(length(camera.up) > 0.0f) || !(length(cross(normalize(view), normalize(camera.up))) > 1e-6f))
            throw Error("camera: 'up' must be non-zero and not parallel to the viewing direction");
        camera.focus_distance = length(view);
    }
}

std::string human_bytes(uint64_t b) {
    char buf[64];
    if (b >= (uint64_t(1) << 30)) std::snprintf(buf, sizeof buf, "%.1f GiB", double(b) / double(uint64_t(1) << 30));
    else std::snprintf(buf, sizeof buf, "%.0f MiB", double(b) / double(1 << 20));
    return buf;
}

int run_devices() {
    std::vector<DeviceEntry> devices = list_devices();
    if (devices.empty()) throw Error("no OpenCL device found (is pocl-opencl-icd installed?)");
    std::printf("%-5s %-40s %-6s %5s  %-14s %s\n", "index", "name", "type", "units", "OpenCL C", "global memory");
    for (const DeviceEntry& d : devices)
        std::printf("%-5d %-40s %-6s %5u  %-14s %s   [%s]\n", d.index, d.name.c_str(), d.type.c_str(), d.compute_units,
                    d.opencl_c_version.c_str(), human_bytes(d.global_memory).c_str(), d.platform_name.c_str());
    return 0;
}

std::string default_output(const std::string& scene_path) {
    std::string name = scene_path.substr(scene_path.find_last_of('/') + 1);
    size_t dot = name.find_last_of('.');
    if (dot != std::string::npos) name = name.substr(0, dot);
    return name + ".png";
}

class ProgressBar {
public:
    explicit ProgressBar(bool enabled) : enabled_(enabled) {}
    void update(int done, int total, double seconds, uint64_t pixels) {
        if (!enabled_) return;
        double sps = seconds > 0 ? double(done) * double(pixels) / seconds : 0;
        char line[160];
        if (total > 0) {
            const int width = 30;
            int filled = int(double(width) * done / total);
            double eta = done > 0 ? seconds * (total - done) / done : 0;
            std::snprintf(line, sizeof line, "\r[%.*s%*s] %d/%d spp  %.2f M samples/s  ETA %.0f s ", filled,
                          "##############################", width - filled, "", done, total, sps * 1e-6, eta);
        } else {
            std::snprintf(line, sizeof line, "\r%d spp  %.2f M samples/s  %.1f s ", done, sps * 1e-6, seconds);
        }
        std::fputs(line, stderr);
        std::fflush(stderr);
        shown_ = true;
    }
    void finish() {
        if (shown_) std::fputs("\n", stderr);
    }

private:
    bool enabled_;
    bool shown_ = false;
};

// One EXR per (s, t) with s + t - 2 <= max_depth: DIR/s<s>_t<t>.exr (pbrt's
// visualizestrategies). Strategies an integrator does not use come out black.
void write_strategy_images(const std::string& dir, const Film& film, int max_depth, const ImageMetadata& meta) {
    std::error_code ec;
    std::filesystem::create_directories(dir, ec);
    if (ec) throw Error("cannot create directory '" + dir + "': " + ec.message());
    for (int depth = 0; depth <= max_depth; ++depth)
        for (int t = 1; t <= depth + 2; ++t) {
            int s = depth + 2 - t;
            std::string path = dir + "/s" + std::to_string(s) + "_t" + std::to_string(t) + ".exr";
            write_image(path, film.width, film.height, film.strategy_image(s, t), meta);
        }
}

// The film's double-precision sums live in host memory; a size that cannot fit is refused up
// front with a clear message rather than left to the allocator (or the OOM killer).
void check_film_fits_in_memory(int width, int height, int strategy_depth) {
    const double pixels = double(width) * double(height);
    // camera and light sums, plus per-strategy sums with --strategy-images, 3 doubles each,
    // and the float image written at the end; and adaptive sampling's per-pixel sum of squares
    // (a double), plan (a byte) and extra sample count (4 bytes).
    const double strategies = strategy_depth > 0 ? double(strategy_depth + 2) * (strategy_depth + 3) : 0.0;
    const double bytes = pixels * (3.0 * (8.0 * (2.0 + strategies) + 4.0) + 13.0);
    const double physical = double(sysconf(_SC_PHYS_PAGES)) * double(sysconf(_SC_PAGE_SIZE));
    if (physical > 0 && bytes > 0.8 * physical) {
        char buf[200];
        std::snprintf(buf, sizeof buf, "a %dx%d film needs %.1f GiB of host memory, more than this machine has (%.1f GiB)",
                      width, height, bytes / double(1 << 30), physical / double(1 << 30));
        throw Error(buf);
    }
}

// --integrator auto: runs the efficiency pilot on `device` when the render is long enough for it
// to pay off (render/strategy_pilot.h), sets the chosen mix in `options`, and moves the pilot's
// renderer for the chosen integrator into `renderers` (it goes on to render there). Returns how
// the mix was chosen, for the summary.
std::string choose_strategy_mix(DeviceContext& device, const DeviceScene& ds, RenderOptions* options,
                                bool adaptive, StrategyPilot* pilot, RenderStats* pilot_stats,
                                std::vector<std::unique_ptr<Renderer>>* renderers) {
    // A time budget gets the pilot when it is at least this many seconds.
    constexpr double kPilotMinBudget = 1.0;
    const int width = ds.camera.width, height = ds.camera.height;
    const bool timed = options->time_budget > 0;
    if (options->strategy_images != RenderOptions::StrategyImages::Off) return "bdpt: no pilot with --strategy-images";
    const size_t candidates = strategy_candidates(ds).size();
    if (timed ? options->time_budget < kPilotMinBudget : !strategy_pilot_fits(width, height, options->spp, candidates))
        return "bdpt: too few samples for the pilot to pay off";
    {
        const ImageIoProcessPause paused;
        *pilot = run_strategy_pilot(device, ds, *options, timed ? 0 : options->spp, options->time_budget, adaptive,
                                    pilot_stats);
    }
    const StrategyCandidate& c = pilot->choice();
    options->integrator = c.integrator;
    options->light_subpaths = c.light_subpaths;
    options->inner_connections = c.inner_connections;
    options->roulette_light_from = c.roulette_light_from;
    // A budget the pilot spent still gets one pass (render_image always renders one).
    if (timed) options->time_budget = std::max(1e-9, options->time_budget - pilot->seconds);
    for (auto& r : pilot->renderers)
        if (r->options().integrator == c.integrator) {
            r->set_strategy_mix(c.light_subpaths, c.inner_connections);
            r->set_light_roulette(c.roulette_light_from);
            renderers->push_back(std::move(r));
        }
    char buf[160];
    if (timed)
        std::snprintf(buf, sizeof buf, "chosen by a pilot of %.2f s", pilot->seconds);
    else
        std::snprintf(buf, sizeof buf, "chosen by a pilot of %.2f s (%.0f%% of the render's samples)", pilot->seconds,
                      100.0 * double(pilot->samples) / (double(width) * height * std::max(options->spp, 1)));
    std::string note = buf;
    if (!pilot->skipped.empty()) {
        std::snprintf(buf, sizeof buf, "; the bdpt mixes between not run (%s led the others %.2gx)", c.name.c_str(),
                      pilot->lead_at_ends);
        note += buf;
    }
    const std::string left_out = candidates_left_out(ds);
    if (!left_out.empty()) note += "; " + left_out;
    const std::string passed_over = light_tracing_passed_over(pilot->candidates, pilot->chosen);
    return passed_over.empty() ? note : note + "; " + passed_over;
}

// The settings besides the scene that change the image, as one line of key=value pairs: a
// checkpoint is resumed only under the same ones. spp and --time do not count (a render may
// be resumed to more samples), except with zsobol, whose sample order depends on spp.
std::string image_settings(const RenderArgs& args, const RenderOptions& options) {
    std::ostringstream line;
    line << "integrator=" << args.integrator << " light_subpaths=" << args.light_subpaths
         << " connections=" << args.connections << " light_samples=" << light_sampling_name(options.light_sampling)
         << " russian_roulette=" << args.russian_roulette
         << " sampler=" << sampler_name(options.sampler)
         << " max_depth=" << options.max_depth << " seed=" << options.seed << " all_features=" << options.all_features
         << " strategy_images=" << int(options.strategy_images) << " debug_nan_pixel=" << options.debug_nan_pixel;
    // Only where set: checkpoints written before caustic merging existed still resume.
    if (args.caustic_merging != "auto" || args.merge_radius != 1.0)
        line << " caustic_merging=" << args.caustic_merging << " merge_radius=" << args.merge_radius;
    if (options.sampler == SamplerKind::ZSobol) line << " spp=" << options.spp;
    return line.str();
}

// --resume: reads the checkpoint and checks that it belongs to this render and fits its spp.
Checkpoint read_checkpoint_to_resume(const std::string& path, const CheckpointInfo& render, const RenderOptions& options,
                                     int width, int height) {
    Checkpoint c = read_checkpoint(path);
    if (c.film.width != width || c.film.height != height)
        throw Error("checkpoint '" + path + "' is of a " + std::to_string(c.film.width) + "x" +
                    std::to_string(c.film.height) + " film, this render's is " + std::to_string(width) + "x" +
                    std::to_string(height));
    const std::vector<std::string> differences = settings_differences(c.info.settings, render.settings);
    if (!differences.empty()) {
        std::string list;
        for (const std::string& d : differences) list += (list.empty() ? "" : ", ") + d;
        throw Error("checkpoint '" + path + "' is of a render with other settings (" + list +
                    "); resume with the ones it was started with");
    }
    if (c.info.scene_fingerprint != render.scene_fingerprint)
        throw Error("checkpoint '" + path +
                    "' is of another scene (its meshes, materials, lights, media or camera differ from this one's)");
    if (options.time_budget <= 0 && c.film.spp > options.spp)
        throw Error("checkpoint '" + path + "' holds " + std::to_string(c.film.spp) + " spp, more than --spp " +
                    std::to_string(options.spp));
    if (c.info.integrator < int(Integrator::Bdpt) || c.info.integrator > int(Integrator::Lt) ||
        !(c.info.light_subpaths >= 0.0f && c.info.light_subpaths <= 1.0f) || c.info.roulette_light_from < 0)
        throw Error("checkpoint '" + path + "' is not usable: its strategy mix is damaged");
    return c;
}

// Under mpirun (mpi/cluster.h) every process runs this: the leader (process 0) as a whole render
// whose work units also go to the other processes' devices; the others load the scene, build
// their kernels for the leader's plan and render what it sends them, writing and printing
// nothing unless they fail.
int run_render(const RenderArgs& args, Cluster& cluster) {
    install_interrupt_handlers();
    const bool leader = cluster.leader();
    // OpenImageIO loads in a process of its own while the scene loads, OpenCL starts and the
    // kernels load here; it reads the scene's images and writes the render's.
    if (leader) start_image_io_process();
    LoadOptions load_options;
    load_options.default_light = !args.no_default_light;
    using Clock = std::chrono::steady_clock;
    const Clock::time_point start = Clock::now();
    auto seconds_since = [](Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); };
    Scene scene = load_scene(args.scene, load_options);
    const double load_seconds = seconds_since(start);
    apply_camera_overrides(args, &scene);
    if (leader)
        for (const std::string& w : scene.warnings) std::fprintf(stderr, "clbdpt: warning: %s\n", w.c_str());

    const std::string output = args.output.empty() ? default_output(args.scene) : args.output;
    if (!is_supported_output(output))
        throw Error("unsupported output format '" + output + "' (use .exr, .png, .jpg or .tif)");
    // Every file the render will write, checked before it starts.
    if (leader)
        for (const std::string& path : {output, args.stats, args.checkpoint.empty() ? args.resume : args.checkpoint})
            if (!path.empty()) check_can_write(path);
    const int width = args.width > 0 ? args.width : scene.width;
    const int height = args.height > 0 ? args.height : scene.height;
    check_film_fits_in_memory(width, height, args.strategy_images.empty() ? 0 : (args.max_depth >= 0 ? args.max_depth : scene.render.max_depth));

    RenderOptions options;
    // auto: bdpt whose strategy mix (or plain pt or lt) a pilot render picks (render/strategy_pilot.h).
    const bool automatic = args.integrator == "auto";
    options.integrator = automatic ? Integrator::Bdpt : parse_integrator(args.integrator);
    const bool mix_by_hand = args.light_subpaths >= 0 || !args.connections.empty();
    if (mix_by_hand && options.integrator != Integrator::Bdpt)
        throw Error("--light-subpaths and --connections apply to bdpt, not " + args.integrator);
    if (args.light_subpaths >= 0) options.light_subpaths = args.light_subpaths;
    if (!args.connections.empty()) options.inner_connections = args.connections == "on";
    options.light_sampling = parse_light_sampling(args.light_samples);
    // Russian roulette (render/features.h): auto = camera subpaths after 3 bounces, light
    // subpaths as the pilot chooses (else none); off; both subpaths from bounce N; or each its own.
    const RouletteSetting roulette = parse_russian_roulette(args.russian_roulette);
    options.roulette_light_by_pilot = roulette.light_by_pilot;
    options.roulette_camera_from = roulette.camera_from;
    options.roulette_light_from = roulette.light_from;
    // Padded Sobol by default, by measurement (README "Samplers"): ZSobol lowers bdpt's error
    // where the light image dominates (the Cornell box) but costs more per sample than it gains
    // where light subpaths and connections carry the image (lamp-ceiling), and pt gains nothing.
    options.sampler = args.sampler.empty() ? SamplerKind::Sobol : parse_sampler(args.sampler);
    options.spp = args.spp >= 0 ? args.spp : scene.render.spp;
    options.time_budget = args.time_budget;
    options.max_depth = args.max_depth >= 0 ? args.max_depth : scene.render.max_depth;
    options.seed = args.seed >= 0 ? uint32_t(args.seed) : scene.render.seed;
    // A non-finite sample is a bug, but an hours-long render must not die of one: it is left
    // out, counted, and reported at the end (with exit status 1).
    options.drop_non_finite = true;
    options.debug_nan_pixel = args.debug_nan_pixel;
    options.pt_from_subpaths = args.debug_pt_from_subpaths;
    options.all_features = args.all_features;
    options.local_size = args.local_size;
    options.collect_threads = args.collect_threads;
    options.batch_items = args.batch_items;
    if (!args.strategy_images.empty())
        options.strategy_images = args.unweighted ? RenderOptions::StrategyImages::Unweighted
                                                  : RenderOptions::StrategyImages::Weighted;
    else if (args.unweighted)
        throw Error("--unweighted needs --strategy-images DIR");
    if (options.spp < 1 && options.time_budget <= 0) throw Error("--spp must be at least 1");
    int aov = args.aov.empty() ? -1 : parse_aov(args.aov);

    std::vector<DeviceEntry> entries = select_devices(args.device);
    std::vector<std::unique_ptr<DeviceContext>> devices;
    std::string device_names;
    for (const DeviceEntry& e : entries) {
        devices.push_back(std::make_unique<DeviceContext>(e, args.profile));
        device_names += (device_names.empty() ? "" : " + ") + e.name;
    }
    DeviceContext& device = *devices.front();
    const Clock::time_point device_scene_start = Clock::now();
    // Only an explicit --integrator lt renders with the light tracer alone: the pilot never picks
    // it where there is an environment, and a resumed render keeps its --integrator
    // (image_settings).
    DeviceScene ds = build_device_scene(scene, width, height, environment_sampling_for(options.integrator));
    const double device_scene_seconds = seconds_since(device_scene_start);
    if (leader) {
        for (const std::string& w : ds.warnings) std::fprintf(stderr, "clbdpt: warning: %s\n", w.c_str());
        // The default leaves these out of such scenes itself (render/strategy_pilot.h).
        // (auto has not chosen yet: options hold what the command line fixed.)
        if (options.integrator == Integrator::Pt && delta_light_meets_specular(ds))
            std::fprintf(stderr, "clbdpt: warning: --integrator pt: it %s; its image lacks that light (bdpt renders it)\n",
                         kDeltaLightSpecularShortfall);
        if (options.integrator == Integrator::Bdpt && !options.inner_connections && delta_light_meets_specular(ds))
            std::fprintf(stderr,
                         "clbdpt: warning: --connections off: bdpt without inner connections %s where it is seen by "
                         "way of mirror or glass; its image lacks that light\n",
                         kDeltaLightSpecularShortfall);
    }
    if (scene.camera_is_automatic) {
        const AutomaticView view = choose_automatic_view(scene.camera, scene.bounds, ds);
        if (view.moved_inside) {
            ds.camera = make_camera(view.camera, width, height);
            std::fprintf(stderr, "clbdpt: note: %s\n", view.note.c_str());
        }
    }
    const uint64_t texture_bytes = uint64_t(ds.texels.size()) * sizeof(uint32_t) +
                                   uint64_t(ds.textures.size()) * sizeof(TextureInfo) +
                                   uint64_t(ds.uvs.size()) * sizeof(TriangleUV);
    if (args.verbose)
        std::fprintf(stderr,
                     "clbdpt: device %s; scene loaded in %.3f s, device scene in %.3f s; %zu triangles, %zu BVH nodes "
                     "and %zu triangle references (%d spatial splits; %.3f s), %zu lights, %zu textures (%.1f MiB)\n",
                     device_names.c_str(), load_seconds, device_scene_seconds, ds.source_triangles, ds.nodes.size(),
                     ds.triangles.size(), ds.bvh_spatial_splits, ds.bvh_build_seconds, ds.lights.size(),
                     ds.textures.size(), double(texture_bytes) / double(1 << 20));

    ImageMetadata meta;
    meta.strings.push_back({"clbdpt:scene", args.scene});
    meta.strings.push_back({"clbdpt:device", device_names});

    if (aov >= 0 && !(args.checkpoint.empty() && args.resume.empty()))
        throw Error("--checkpoint and --resume apply to renders, not to --aov");
    // A resumed render goes on checkpointing into the file it came from unless told otherwise.
    const std::string checkpoint_path = !args.checkpoint.empty() ? args.checkpoint : args.resume;
    CheckpointInfo checkpoint_info;
    if (!checkpoint_path.empty()) {
        checkpoint_info.scene_fingerprint = scene_fingerprint(ds);
        checkpoint_info.settings = image_settings(args, options);
    }
    std::unique_ptr<Checkpoint> resumed;
    if (!args.resume.empty() && leader) {
        resumed = std::make_unique<Checkpoint>(
            read_checkpoint_to_resume(args.resume, checkpoint_info, options, width, height));
        // The passes go on with the strategy mix they were rendered with (no pilot).
        options.integrator = Integrator(resumed->info.integrator);
        options.light_subpaths = resumed->info.light_subpaths;
        options.inner_connections = resumed->info.inner_connections != 0;
        options.roulette_light_from = resumed->info.roulette_light_from;
    }

    if (aov >= 0) {
        if (!leader) return 0;  // a debug image: the leader renders it alone
        std::vector<float> rgb = render_aov(device, ds, aov);
        meta.strings.push_back({"clbdpt:aov", args.aov});
        write_image(output, width, height, rgb, meta);
        std::fprintf(stderr, "clbdpt: %s AOV %dx%d, wrote %s\n", args.aov.c_str(), width, height, output.c_str());
        return 0;
    }

    const bool tty = ::isatty(STDERR_FILENO);
    ProgressBar bar(tty);
    const uint64_t pixels = uint64_t(width) * uint64_t(height);
    options.progress = [&](int done, int total, double seconds) { bar.update(done, total, seconds, pixels); };
    std::vector<std::unique_ptr<Renderer>> renderers;
    std::vector<Renderer*> renderer_list;

    // Adaptive sampling (render/adaptive.h) wherever its extra samples can follow the passes:
    // not for a time budget (no sample count to add to), resumed or checkpointed renders (a
    // checkpoint holds whole passes), several processes, zsobol (neighbouring pixels share a
    // sequence) or strategy images; and from 8 spp on, below which a pixel's variance is too
    // rough to plan from.
    const bool adaptive = args.adaptive == "on" && options.time_budget <= 0 && options.spp >= kAdaptiveMinSpp &&
                          !resumed && checkpoint_path.empty() && cluster.size() == 1 &&
                          options.sampler != SamplerKind::ZSobol &&
                          options.strategy_images == RenderOptions::StrategyImages::Off;
    // Caustic merging (cl/caustic_merging.h) in the default's BDPT mixes, the pilot's included
    // (it weighs them with it), or in bdpt where asked for; the renderers of other integrators,
    // and of scenes without such paths, leave it out (Renderer).
    options.caustic_merging = args.caustic_merging == "on" || (args.caustic_merging == "auto" && automatic);
    options.merge_radius = args.merge_radius;
    RenderStats pilot_stats;
    StrategyPilot pilot;
    const std::string mix_note =
        resumed ? "as in checkpoint '" + args.resume + "' (" + std::to_string(resumed->film.spp) + " spp resumed)"
        : automatic && !mix_by_hand && leader
            ? choose_strategy_mix(device, ds, &options, adaptive, &pilot, &pilot_stats, &renderers)
            : "";
    // Every process renders with the leader's integrator and strategy mix.
    RenderPlan plan{int(options.integrator), options.light_subpaths, options.inner_connections ? 1 : 0,
                    options.roulette_light_from};
    cluster.share_plan(&plan);
    options.integrator = Integrator(plan.integrator);
    options.light_subpaths = plan.light_subpaths;
    options.inner_connections = plan.inner_connections != 0;
    options.roulette_light_from = plan.roulette_light_from;
    const bool run_pilot = pilot.seconds > 0;
    int failing_device = -1, fail_after = -1;
    if (!args.debug_fail_device.empty() &&
        std::sscanf(args.debug_fail_device.c_str(), "%d:%d", &failing_device, &fail_after) != 2)
        throw Error("--debug-fail-device takes K:N");
    int slow_device = -1;
    double slowdown = 1;
    if (!args.debug_slow_device.empty() &&
        (std::sscanf(args.debug_slow_device.c_str(), "%d:%lf", &slow_device, &slowdown) != 2 || !(slowdown >= 1)))
        throw Error("--debug-slow-device takes K:F with F >= 1");
    for (size_t i = renderers.size(); i < devices.size(); ++i) {
        RenderOptions device_options = options;
        if (int(i) == failing_device) device_options.debug_fail_after_launches = fail_after;
        if (int(i) == slow_device) device_options.debug_slowdown = slowdown;
        renderers.push_back(std::make_unique<Renderer>(*devices[i], ds, device_options));
    }
    for (size_t i = 0; i < devices.size(); ++i) {
        auto& d = devices[i];
        renderer_list.push_back(renderers[i].get());
        if (args.verbose) {
            const RenderStats& rs = renderers[i]->stats();
            std::string flags;
            for (const std::string& def : rs.defines) flags += " -D" + def;
            std::fprintf(stderr, "clbdpt: kernel flags:%s\nclbdpt: kernel for %s %s in %.2f s\n", flags.c_str(),
                         d->entry().name.c_str(), rs.program_from_cache ? "loaded from cache" : "built", rs.build_seconds);
        }
    }
    if (!leader) {
        cluster.serve(renderer_list, scene_fingerprint(ds));
        return 0;
    }
    std::vector<std::unique_ptr<UnitWorker>> remote_devices;
    std::vector<UnitWorker*> remote_list;
    if (cluster.size() > 1) {
        remote_devices = cluster.connect_remote_devices(scene_fingerprint(ds), width, height);
        for (auto& r : remote_devices) {
            remote_list.push_back(r.get());
            device_names += " + " + r->name();
        }
        for (auto& entry : meta.strings)
            if (entry.first == "clbdpt:device") entry.second = device_names;
    }
    checkpoint_info.integrator = int(options.integrator);
    checkpoint_info.light_subpaths = options.light_subpaths;
    checkpoint_info.inner_connections = options.inner_connections ? 1 : 0;
    checkpoint_info.roulette_light_from = options.roulette_light_from;
    RenderSchedule schedule;
    schedule.resume = resumed ? &resumed->film : nullptr;
    schedule.stop_requested = [] { return interrupt_signal() != 0; };
    if (!checkpoint_path.empty()) {
        schedule.checkpoint_seconds = args.checkpoint_every;
        // A checkpoint that cannot be written is a warning: the render goes on, and the one
        // written at its end says whether the disk has recovered.
        schedule.checkpoint = [&](const Film& snapshot) {
            try {
                write_checkpoint(checkpoint_path, checkpoint_info, snapshot);
            } catch (const Error& e) {
                std::fprintf(stderr, "\nclbdpt: warning: %s\n", e.what());
            }
        };
    }
    schedule.device_dropped = [](const std::string& what) {
        std::fprintf(stderr, "\nclbdpt: warning: device %s; it left the render and its pass went to the others\n",
                     what.c_str());
    };
    options.track_variance = adaptive;
    RenderStats st;
    const double seconds_before_passes = seconds_since(start) - pilot.seconds;
    Film film = render_image(renderer_list, options, &st, schedule, remote_list);
    cluster.release_remote_devices();
    const int interrupted_by = interrupt_signal();
    if (interrupted_by != 0 && film.spp == 0) {
        bar.finish();
        std::fprintf(stderr, "clbdpt: interrupted before the first pass was done: nothing written\n");
        return 128 + interrupted_by;
    }
    AdaptivePlan adaptive_plan;
    double adaptive_seconds = 0;
    Integrator adaptive_integrator = options.integrator;  // of the extra samples
    if (adaptive && interrupted_by == 0) {
        const auto adaptive_start = Clock::now();
        // The pilot's path tracer takes them where it renders about as well as the chosen mix
        // (render/strategy_pilot.h).
        Renderer* extra_renderer = renderer_list.front();
        if (run_pilot && path_traced_extra_samples(pilot.candidates, pilot.chosen, uses_light_to_lens(ds)))
            for (auto& r : pilot.renderers)
                if (r && r->options().integrator == Integrator::Pt) extra_renderer = r.get();
        adaptive_integrator = extra_renderer->options().integrator;
        adaptive_plan = plan_adaptive_samples(film, kAdaptiveMaxTier, kAdaptiveMaxExtraShare,
                                              adaptive_integrator != Integrator::Pt);
        render_adaptive_samples(*extra_renderer, adaptive_plan, film, &st,
                                [] { return interrupt_signal() != 0; });
        adaptive_seconds = seconds_since(adaptive_start);
        st.seconds += adaptive_seconds;
        // The renderers' profiles (--profile) now hold the extra samples' launches too; the
        // adding thread's figures are the passes' (the extra samples are added as they come).
        RenderProfile queue_profile;
        queue_profile.film_add_seconds = st.profile.film_add_seconds;
        queue_profile.backlog_wait_seconds = st.profile.backlog_wait_seconds;
        st.profile = queue_profile;
        for (Renderer* r : renderer_list) st.profile.add(r->stats().profile);
        if (extra_renderer != renderer_list.front()) st.profile.add(extra_renderer->stats().profile);
    }
    if (run_pilot) {
        st.add(pilot_stats);
        st.program_from_cache = st.program_from_cache && pilot_stats.program_from_cache;
        st.seconds += pilot.seconds;
        st.first_pass_seconds += pilot.seconds;
    }
    const std::string strategy_mix = describe_strategy_mix(options.integrator, options.light_subpaths,
                                                           options.inner_connections, options.roulette_light_from);
    // Loading, BVH, kernel builds (or cache loads) and the first pass: what a user waits for.
    const double first_pass_seconds = seconds_before_passes + st.first_pass_seconds;
    bar.finish();

    meta.strings.push_back({"clbdpt:integrator", integrator_name(options.integrator)});
    meta.strings.push_back({"clbdpt:strategy_mix", strategy_mix});
    meta.strings.push_back({"clbdpt:sampler", sampler_name(options.sampler)});
    meta.strings.push_back({"clbdpt:spp", std::to_string(film.spp)});
    if (adaptive)
        meta.strings.push_back({"clbdpt:adaptive_extra_samples", std::to_string(adaptive_plan.extra_samples)});
    if (adaptive && adaptive_integrator != options.integrator)
        meta.strings.push_back({"clbdpt:adaptive_extra_samples_by", integrator_name(adaptive_integrator)});
    meta.strings.push_back({"clbdpt:max_depth", std::to_string(options.max_depth)});
    meta.strings.push_back({"clbdpt:seed", std::to_string(options.seed)});
    meta.strings.push_back({"clbdpt:seconds", std::to_string(st.seconds)});
    write_image(output, width, height, film.image(), meta);
    if (!args.strategy_images.empty()) write_strategy_images(args.strategy_images, film, options.max_depth, meta);
    if (!checkpoint_path.empty()) write_checkpoint(checkpoint_path, checkpoint_info, film);

    const double sps = st.seconds > 0 ? double(st.samples) / st.seconds : 0;
    const double rps = st.seconds > 0 ? double(st.rays) / st.seconds : 0;
    if (!args.stats.empty()) {
        nlohmann::json j;
        j["scene"] = args.scene;
        j["output"] = output;
        j["integrator"] = integrator_name(options.integrator);
        j["strategy_mix"] = strategy_mix;
        j["light_subpaths"] = options.integrator == Integrator::Bdpt ? options.light_subpaths
                              : options.integrator == Integrator::Lt ? 1.0f : 0.0f;
        j["inner_connections"] = options.integrator == Integrator::Bdpt && options.inner_connections;
        // Where Russian roulette starts in each kind of subpath (the integrator traces).
        j["russian_roulette"] = {
            {"camera_subpaths", options.integrator == Integrator::Lt ? "none traced"
                                                                     : roulette_name(options.roulette_camera_from)},
            {"light_subpaths", options.integrator == Integrator::Pt || options.light_subpaths == 0.0f
                                   ? "none traced"
                                   : roulette_name(options.roulette_light_from)}};
        // What the light samples did: a sample of every light group, or one light each.
        j["light_samples"] = std::find(st.defines.begin(), st.defines.end(), "NEE_EVERY_LIGHT") != st.defines.end()
                                 ? "every"
                                 : "one";
        if (!mix_note.empty()) j["strategy_mix_note"] = mix_note;
        if (run_pilot) {
            nlohmann::json p;
            p["seconds"] = pilot.seconds;
            p["samples"] = pilot.samples;
            p["pixel_stride"] = pilot.pixel_stride;
            p["lead_at_ends"] = pilot.lead_at_ends;
            p["not_run"] = pilot.skipped;
            p["chosen"] = pilot.choice().name;
            for (const StrategyCandidate& c : pilot.candidates)
                p["candidates"].push_back({{"name", c.name},
                                           {"variance_transport", c.variance_transport},
                                           {"variance_transport_standard_error", c.variance_transport_standard_error},
                                           {"variance_light_image", c.variance_light_image},
                                           {"variance_transport_stratified", c.variance_transport_stratified},
                                           {"variance_shared_tail", c.variance_shared_tail},
                                           {"variance_shared_counted", c.variance_shared_counted},
                                           {"variance_missed", c.variance_missed},
                                           {"variance_pixel", c.variance_pixel},
                                           {"adaptive_variance_left", c.adaptive_variance_left},
                                           {"adaptive_extra_share", c.adaptive_extra_share},
                                           {"seconds_per_pass", c.seconds_per_pass},
                                           {"predicted_spp", c.predicted_spp},
                                           {"predicted_mse", c.predicted_mse},
                                           {"efficiency", c.efficiency},
                                           {"efficiency_transport_only", c.efficiency_transport_only}});
            j["strategy_pilot"] = p;
        }
        j["sampler"] = sampler_name(options.sampler);
        nlohmann::json a;
        a["enabled"] = adaptive;
        if (adaptive) {
            a["extra_samples"] = adaptive_plan.extra_samples;
            a["pixels_refined"] = adaptive_plan.pixels_refined;
            a["max_tier"] = adaptive_plan.max_tier;
            a["u_mean"] = adaptive_plan.u_mean;
            a["seconds"] = adaptive_seconds;
            a["integrator"] = integrator_name(adaptive_integrator);
        }
        j["adaptive"] = a;
        nlohmann::json merging;
        const CausticPhotons* photons = renderer_list.front()->caustic_photons();
        merging["enabled"] = photons != nullptr;
        if (photons) {
            merging["photons"] = photons->photons();
            merging["passes_traced"] = photons->passes_traced();
            merging["light_subpaths_per_pass"] = photons->paths_per_pass();
            merging["radius_first_pass"] = photons->radius(0);
            merging["radius_smallest"] = photons->smallest_radius(film.spp);
            merging["seconds"] = photons->seconds();
        }
        j["caustic_merging"] = merging;
        j["width"] = width;
        j["height"] = height;
        j["spp"] = film.spp;
        j["resumed_spp"] = resumed ? resumed->film.spp : 0;
        j["interrupted"] = interrupted_by != 0;
        if (!checkpoint_path.empty()) j["checkpoint"] = checkpoint_path;
        j["max_depth"] = options.max_depth;
        j["seed"] = options.seed;
        j["seconds"] = st.seconds;
        j["samples"] = st.samples;
        j["samples_per_second"] = sps;
        j["rays"] = st.rays;
        j["rays_per_second"] = rps;
        j["dropped_samples"] = st.dropped_samples;
        for (const DroppedSample& d : st.first_dropped)
            j["first_dropped_samples"].push_back(
                {{"pixel", {d.x, d.y}}, {"sample", d.sample}, {"s", d.s}, {"t", d.t}});
        j["kernel_build_seconds"] = st.build_seconds;
        j["kernel_from_cache"] = st.program_from_cache;
        j["kernel_defines"] = st.defines;
        j["device"] = device_names;
        j["devices"] = entries.size() + remote_devices.size();
        j["processes"] = cluster.size();
        j["dropped_devices"] = st.dropped_devices;
        for (const RenderStats::DeviceShare& d : st.device_shares)
            j["device_shares"].push_back({{"device", d.name},
                                          {"samples", d.samples},
                                          {"share", st.samples ? double(d.samples) / double(st.samples) : 0.0},
                                          {"samples_per_second", st.seconds > 0 ? double(d.samples) / st.seconds : 0.0},
                                          {"busy_seconds", d.busy_seconds},
                                          {"wasted_samples", d.wasted_samples}});
        j["triangles"] = ds.source_triangles;
        j["bvh_references"] = ds.triangles.size();
        j["load_seconds"] = load_seconds;
        j["device_scene_seconds"] = device_scene_seconds;
        j["bvh_build_seconds"] = ds.bvh_build_seconds;
        j["first_pass_seconds"] = first_pass_seconds;
        j["texture_bytes"] = texture_bytes;
        write_file_atomically(args.stats, j.dump(2) + "\n");
    }
    if (args.profile) {
        const RenderProfile& p = st.profile;
        const double busy = p.kernel_seconds + p.transfer_seconds + p.accumulate_seconds;
        auto row = [&](const char* what, double seconds) {
            std::fprintf(stderr, "clbdpt: profile: %-28s %9.3f s  %5.1f%%\n", what, seconds,
                         busy > 0 ? 100.0 * seconds / busy : 0.0);
        };
        row("render kernel (device)", p.kernel_seconds);
        row("read-back (device)", p.transfer_seconds);
        row("accumulation (host)", p.accumulate_seconds);
        // The host's other steps overlap the rows above (threads of their own, or the device
        // busy meanwhile), so they are shares of the passes' wall time instead.
        auto wall_row = [&](const char* what, double seconds) {
            std::fprintf(stderr, "clbdpt: profile: %-28s %9.3f s  %5.1f%% of wall\n", what, seconds,
                         st.seconds > 0 ? 100.0 * seconds / st.seconds : 0.0);
        };
        wall_row("result buffers (host)", p.buffers_seconds);
        wall_row("adding to the film (host)", p.film_add_seconds);
        wall_row("waiting for the adding", p.backlog_wait_seconds);
        wall_row("render kernel, of wall", p.kernel_seconds);
        std::fprintf(stderr, "clbdpt: profile: kernel time per sample %.3f us, per ray %.3f us\n",
                     st.samples ? 1e6 * p.kernel_seconds / double(st.samples) : 0.0,
                     st.rays ? 1e6 * p.kernel_seconds / double(st.rays) : 0.0);
    }
    if (args.verbose && run_pilot)
        for (const StrategyCandidate& c : pilot.candidates)
            std::fprintf(stderr,
                         "clbdpt: pilot: %-56s variance per sample: transport %.3g +- %.2g (stratified %.3g, "
                         "shared tail %.3g, of which counted %.3g, light image %.3g, missed by its passes %.3g), pixel %.3g; adaptive leaves %.2f for %.1f%% more "
                         "samples; %.3f s/pass; predicted MSE %.3g at %.0f spp; efficiency %.3g%s\n",
                         c.name.c_str(), c.variance_transport, c.variance_transport_standard_error,
                         c.variance_transport_stratified, c.variance_shared_tail, c.variance_shared_counted,
                         c.variance_light_image, c.variance_missed,
                         c.variance_pixel, c.adaptive_variance_left, 100.0 * c.adaptive_extra_share,
                         c.seconds_per_pass, c.predicted_mse, c.predicted_spp, c.efficiency,
                         &c == &pilot.choice() ? "  <- chosen" : "");
    if (interrupted_by != 0) {
        // One line: what was saved. (A non-finite sample, if any, is still reported below.)
        const std::string of_planned = options.time_budget > 0 ? "" : " of " + std::to_string(options.spp);
        std::fprintf(stderr, "clbdpt: interrupted: wrote %s with %d spp%s%s%s\n", output.c_str(), film.spp,
                     of_planned.c_str(), checkpoint_path.empty() ? "" : "; checkpoint ", checkpoint_path.c_str());
    } else {
        std::fprintf(stderr,
                     "clbdpt: %s %d spp %dx%d in %.2f s: %.3f M samples/s, %.2f M rays/s; kernel %s %.2f s; wrote %s\n",
                     strategy_mix.c_str(), film.spp, width, height, st.seconds, sps * 1e-6, rps * 1e-6,
                     st.program_from_cache ? "cached" : "build", st.build_seconds, output.c_str());
        if (!mix_note.empty()) std::fprintf(stderr, "clbdpt: strategy mix %s\n", mix_note.c_str());
        if (const CausticPhotons* photons = renderer_list.front()->caustic_photons())
            std::fprintf(stderr,
                         "clbdpt: caustic merging: %llu photons from %u passes of %u light subpaths, radius %.3g to "
                         "%.3g (%.2f s)\n",
                         (unsigned long long)photons->photons(), photons->passes_traced(), photons->paths_per_pass(),
                         photons->radius(0), photons->smallest_radius(film.spp), photons->seconds());
        if (adaptive_plan.extra_samples > 0)
            std::fprintf(stderr, "clbdpt: adaptive sampling: %.1f%% more samples%s, in %llu pixels (%.2f s)\n",
                         100.0 * double(adaptive_plan.extra_samples) / (double(film.spp) * width * height),
                         adaptive_integrator != options.integrator ? " (path-traced: whole pixel estimates)" : "",
                         (unsigned long long)adaptive_plan.pixels_refined, adaptive_seconds);
        if (st.device_shares.size() > 1)
            for (const RenderStats::DeviceShare& d : st.device_shares)
                std::fprintf(stderr, "clbdpt: %s: %.1f%% of the samples, %.3f M samples/s%s\n", d.name.c_str(),
                             st.samples ? 100.0 * double(d.samples) / double(st.samples) : 0.0,
                             st.seconds > 0 ? 1e-6 * double(d.samples) / st.seconds : 0.0,
                             d.wasted_samples ? (", " + std::to_string(d.wasted_samples) +
                                                 " rendered twice (taken over at the end)")
                                                    .c_str()
                                              : "");
    }
    if (st.dropped_samples > 0) {
        std::string first;
        for (const DroppedSample& d : st.first_dropped) {
            first += first.empty() ? "" : "; ";
            first += "pixel (" + std::to_string(d.x) + ", " + std::to_string(d.y) + ") sample " +
                     std::to_string(d.sample);
            if (d.s >= 0) first += " strategy s=" + std::to_string(d.s) + " t=" + std::to_string(d.t);
        }
        std::fprintf(stderr,
                     "clbdpt: error: %llu of %llu samples had a non-finite value and were left out of %s (a bug: "
                     "please report it with the scene; first: %s)\n",
                     static_cast<unsigned long long>(st.dropped_samples), static_cast<unsigned long long>(st.samples),
                     output.c_str(), first.c_str());
    }
    if (interrupted_by != 0) return 128 + interrupted_by;
    return st.dropped_samples > 0 ? 1 : 0;
}

}  // namespace
}  // namespace clbdpt

int main(int argc, char** argv) {
    using namespace clbdpt;
    Cluster cluster(&argc, &argv);
    CLI::App app{"clbdpt: bidirectional path tracing in OpenCL kernels"};
    app.require_subcommand(1);
    app.set_version_flag("--version", "clbdpt 0.1");

    app.add_subcommand("devices", "List every OpenCL platform and device");

    RenderArgs args;
    CLI::App* render = app.add_subcommand("render", "Render a scene (.json scene file or bare .obj)");
    render->add_option("scene", args.scene, "Scene file (.json) or .obj")->required();
    render->add_option("-o,--output", args.output,
                       "Output image; format by extension: .exr (linear float), .png/.jpg/.tif (tonemapped sRGB). "
                       "Default: <scene name>.png");
    render->add_option("--spp", args.spp,
                       "Samples per pixel (default: the scene's render.spp); adaptive sampling gives the noisiest "
                       "pixels more (--adaptive)");
    render->add_option("--time", args.time_budget, "Render whole passes until this many seconds are spent");
    render->add_option("--max-depth", args.max_depth, "Maximum scattering vertices per path (default: scene's)");
    render->add_option("--seed", args.seed, "Random seed (default: the scene's render.seed)");
    render->add_option("--device", args.device,
                       "Device index or name substring (default: first GPU, else first CPU); several separated "
                       "by commas, or 'all', share the render by their measured speeds, the image the same bit for "
                       "bit (under mpirun -n N, so do every process's devices)");
    render->add_option("--width", args.width, "Film width override")->check(CLI::Range(1, 32768));
    render->add_option("--height", args.height, "Film height override")->check(CLI::Range(1, 32768));
    render->add_option("--stats", args.stats, "Write a JSON summary (spp, seconds, samples/s, rays/s, ...)");
    render->add_option("--integrator", args.integrator,
                       "auto (default: bdpt, pt (not where a point, spot or directional light meets a mirror or "
                       "glass, nor with a point or spot light in a medium) or, in a scene of diffuse surfaces without "
                       "media or environment, lt: whichever strategy mix a short pilot render finds most efficient for "
                       "the scene), bdpt (all strategies), pt (s <= 1) or lt (t = 1)")
        ->check(CLI::IsMember({"auto", "bdpt", "pt", "lt"}));
    render->add_option("--light-subpaths", args.light_subpaths,
                       "bdpt: light subpaths traced per pixel sample, 0 to 1 (a fraction is a probability; MIS "
                       "counts it); fixes what auto would choose")
        ->check(CLI::Range(0.0f, 1.0f));
    render->add_option("--connections", args.connections,
                       "bdpt: on (default) or off: whether subpaths are joined by connections with s >= 2 and t >= 2")
        ->check(CLI::IsMember({"on", "off"}));
    render->add_option("--light-samples", args.light_samples,
                       "auto (default): at each path vertex, a light sample of every light group (the area lights "
                       "together, every other light alone) in a scene without media that has 2 to 8 groups, else "
                       "one light sample; every or one fixes it")
        ->check(CLI::IsMember({"auto", "every", "one"}));
    render->add_option("--russian-roulette", args.russian_roulette,
                       "auto (default): camera subpaths may end by Russian roulette after 3 bounces (pbrt-v3's path "
                       "tracer's rule), light subpaths from their 2nd bounce where the pilot finds it pays, else never; "
                       "off; N: both subpaths from bounce N on (0: the first); or C,L: camera subpaths from bounce C, "
                       "light subpaths from bounce L (each a bounce or off)")
        ->check([](const std::string& v) {
            try {
                parse_russian_roulette(v);
                return std::string();
            } catch (const Error& e) {
                return std::string(e.what());
            }
        });
    render->add_option("--sampler", args.sampler,
                       "sobol (default): padded Owen-scrambled Sobol, every decision stratified over a pixel's "
                       "samples; zsobol: the same points ordered over the image in Morton order, stratified over "
                       "neighbouring pixels too (needs --spp); independent: uniform random numbers")
        ->check(CLI::IsMember({"independent", "sobol", "zsobol"}));
    render->add_option("--adaptive", args.adaptive,
                       "on (default): after the spp passes, up to 16x the samples for the pixels whose neighbours are "
                       "noisiest (at most as many extra samples as the passes had; sobol and independent samplers, "
                       "--spp 8 or more, one process, no --time, --checkpoint or --resume; path-traced where the "
                       "pilot chose a BDPT mix and found pt close); off: spp samples for every pixel")
        ->check(CLI::IsMember({"on", "off"}));
    render->add_option("--caustic-merging", args.caustic_merging,
                       "auto (default): on where --integrator auto chose a BDPT mix; on: with --integrator bdpt too; "
                       "off. Caustics seen through mirrors and glass (paths that only s = 0 samples, or none where a "
                       "point, spot or directional light casts them) are estimated from each pass's caustic photons "
                       "instead, in scenes with a mirror or glass: biased by a blur of about --merge-radius pixels "
                       "that shrinks as passes accumulate")
        ->check(CLI::IsMember({"auto", "on", "off"}));
    render->add_option("--merge-radius", args.merge_radius,
                       "Caustic merging's radius in pixel footprints at the scene's centre, for the first pass "
                       "(default 1; pass q's is (q + 1)^(-1/6) of it)")
        ->check(CLI::Range(1e-3, 1e3));
    render->add_option("--aov", args.aov, "Debug render of the first hit: normal, albedo or depth")
        ->check(CLI::IsMember({"normal", "albedo", "depth"}));
    render->add_option("--strategy-images", args.strategy_images,
                       "Also write each (s,t) strategy's MIS-weighted contribution as DIR/s<s>_t<t>.exr");
    render->add_flag("--unweighted", args.unweighted, "With --strategy-images: write the contributions before MIS");
    render->add_flag("--all-features", args.all_features, "Build the kernel with every feature enabled (benchmarks)");
    render->add_option("--local-size", args.local_size, "OpenCL work-group size (default: 16 on CPU devices, where PoCL keeps a work-group's path vertices on one thread's stack, and larger sizes at large max depths are refused; elsewhere the driver's choice)")
        ->check(CLI::PositiveNumber);
    render->add_flag("--profile", args.profile,
                     "Report time per stage: render kernel and read-back (OpenCL profiling events), the host's collection, "
                     "result buffers and film adding, and waits for the adding (clocks)");
    render->add_option("--lookat", args.lookat,
                       "Camera: eye, target and up as 9 numbers (pbrt's LookAt order: ex ey ez tx ty tz ux uy uz)")
        ->expected(9);
    render->add_option("--eye", args.eye, "Camera position X Y Z")->expected(3);
    render->add_option("--target", args.target, "Point the camera looks at X Y Z")->expected(3);
    render->add_option("--up", args.up, "Camera up direction X Y Z")->expected(3);
    render->add_option("--fov", args.fov, "Field of view in degrees across the shorter image axis")
        ->check(CLI::Range(0.001f, 179.0f));
    render->add_flag("--no-default-light", args.no_default_light,
                     "Do not light a scene without lights by a uniform white environment");
    render->add_option("--checkpoint", args.checkpoint,
                       "Save the render's progress to FILE now and then (--checkpoint-every), at the end and on "
                       "Ctrl-C, atomically; --resume FILE goes on from it");
    render->add_option("--checkpoint-every", args.checkpoint_every, "Seconds between checkpoints (default 60)")
        ->check(CLI::PositiveNumber);
    render->add_option("--resume", args.resume,
                       "Go on from a checkpoint of the same scene and settings up to --spp (or for --time more "
                       "seconds); the image equals an uninterrupted render's without adaptive samples (--checkpoint "
                       "or --adaptive off) bit for bit on the same device. Goes "
                       "on checkpointing into FILE unless --checkpoint names another");
    render->add_flag("-v,--verbose", args.verbose, "Print device, BVH and kernel flags");
    // Tests only (no group: not in --help): that pixel's sample 0 gets a NaN contribution.
    render->add_option("--debug-nan-pixel", args.debug_nan_pixel)->group("");
    // Tests only: device K's launches fail after N launches; work items per launch at most.
    render->add_option("--debug-fail-device", args.debug_fail_device)->group("");
    render->add_option("--batch-items", args.batch_items)->group("")->check(CLI::PositiveNumber);
    render->add_option("--collect-threads", args.collect_threads)->group("")->check(CLI::PositiveNumber);
    // Tests only: under mpirun, process R ends abruptly after rendering N runs.
    render->add_option("--debug-exit-process", args.debug_exit_process)->group("");
    // Benchmarks only: device K runs F times slower (it waits after each launch).
    render->add_option("--debug-slow-device", args.debug_slow_device)->group("");
    // Benchmarks only: pt made from stored subpaths, the way bdpt makes its strategies
    // (cl/kernels/render.cl), instead of one vertex at a time; the same image.
    render->add_flag("--debug-pt-from-subpaths", args.debug_pt_from_subpaths)->group("");

    try {
        app.parse(argc, argv);
    } catch (const CLI::ParseError& e) {
        return app.exit(e);
    }
    try {
        if (app.got_subcommand("devices")) return run_devices();
        int exit_rank = -1, exit_after = -1;
        if (!args.debug_exit_process.empty() &&
            std::sscanf(args.debug_exit_process.c_str(), "%d:%d", &exit_rank, &exit_after) != 2)
            throw Error("--debug-exit-process takes R:N");
        if (exit_rank == cluster.rank()) cluster.debug_exit_after_runs = exit_after;
        return run_render(args, cluster);
    } catch (const Error& e) {
        std::fprintf(stderr, "clbdpt: error: %s\n", e.what());
    } catch (const cl::Error& e) {
        std::fprintf(stderr, "clbdpt: error: OpenCL: %s: %s\n", e.what(), cl_error_name(e.err()));
    } catch (const std::bad_alloc&) {
        std::fprintf(stderr, "clbdpt: error: out of host memory\n");
    } catch (const std::exception& e) {
        std::fprintf(stderr, "clbdpt: error: %s\n", e.what());
    }
    // Under mpirun a failing process ends the others (which may be waiting for it).
    if (cluster.size() > 1) cluster.abort(1);
    return 1;
}
