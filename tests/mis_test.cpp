// MIS weights of every strategy that can produce a path sum to 1 (cl/kernels/mis_test.cl),
// for paths traced by the real random walk in the bundled scenes, for each strategy set.
#include <gtest/gtest.h>

#include <filesystem>

#include "render/features.h"
#include "render/renderer.h"
#include "render/scene_buffers.h"
#include "render_test_util.h"
#include "test_scenes.h"

namespace clbdpt::test {
namespace {

struct MisSums {
    float worst = 0;   // largest |sum of weights - 1|
    long paths = 0;    // paths checked
};

MisSums mis_sums(const Scene& scene, Integrator integrator, int max_depth, int size, int passes,
                 float light_subpaths = 1.0f, bool inner_connections = true, bool light_to_lens = true) {
    DeviceScene ds = build_device_scene(scene, size, size, environment_sampling_for(integrator));
    DeviceContext& device = test_device();
    const ProgramBuild& build = device.program("kernels/mis_test.cl", kernel_defines(ds, integrator, max_depth));
    SceneBuffers buffers(device.context(), ds);
    cl::Kernel kernel(build.program, "mis_weight_sums");
    buffers.set_args(kernel);
    const int pixels = size * size;
    cl::Buffer out(device.context(), CL_MEM_WRITE_ONLY, sizeof(cl_float2) * pixels);
    std::vector<cl_float2> host(pixels);
    MisSums result;
    for (int pass = 0; pass < passes; ++pass) {
        RenderParams params{};
        params.width = size;
        params.height = size;
        params.pixel_count = pixels;
        params.sample_index = uint32_t(pass);
        params.light_subpaths = light_subpaths;
        params.inner_connections = inner_connections ? 1 : 0;
        params.light_to_lens = light_to_lens ? 1 : 0;
        kernel.setArg(SceneBuffers::kSceneArgCount, params);
        kernel.setArg(SceneBuffers::kSceneArgCount + 1, out);
        // Work-groups of the renderer's CPU size (kCpuLocalSize, render/renderer.h): PoCL keeps a
        // group's path vertices on one thread's stack, which a large group overflows at a large
        // max depth (the driver's choice crashed at max depth 20).
        device.queue().enqueueNDRangeKernel(kernel, cl::NullRange, cl::NDRange(size_t(pixels)),
                                            cl::NDRange(size_t(kCpuLocalSize)));
        device.queue().enqueueReadBuffer(out, CL_TRUE, 0, sizeof(cl_float2) * pixels, host.data());
        for (const cl_float2& v : host) {
            result.worst = std::max(result.worst, v.s[0]);
            result.paths += long(v.s[1]);
        }
    }
    return result;
}

// Float ratios over at most max_depth + 2 vertices: each weight is 1 / (1 + sum of ratios),
// good to a few float ulps; 1e-4 leaves room for ~100 ulps of accumulated rounding.
constexpr float kTolerance = 1e-4f;

// min_paths: how many emitter-ending paths the 64x64x4 camera samples must find for the test
// to mean something (the lamp's emitter hides in its shade, so few camera paths reach it).
void check_scene(const Scene& scene, const std::string& name, int max_depth, long min_paths = 100) {
    for (Integrator integrator : {Integrator::Bdpt, Integrator::Pt, Integrator::Lt}) {
        // bdpt with and without strategy (1,1) (a pinhole in vacuum goes without).
        for (bool light_to_lens : {true, false}) {
            if (!light_to_lens && integrator != Integrator::Bdpt) continue;
            MisSums sums = mis_sums(scene, integrator, max_depth, 64, 4, 1.0f, true, light_to_lens);
            EXPECT_GE(sums.paths, min_paths) << name << " " << integrator_name(integrator);
            EXPECT_LT(sums.worst, kTolerance) << name << " " << integrator_name(integrator) << " light_to_lens "
                                              << light_to_lens << ": " << sums.paths << " paths";
        }
    }
}

void check_scene(const std::string& name, int max_depth, long min_paths = 100) {
    if (!std::filesystem::exists(scene_path(name))) GTEST_SKIP() << name << " is not bundled";
    check_scene(load_scene(scene_path(name)), name, max_depth, min_paths);
}

TEST(MisWeights, SumToOneCornellBox) { check_scene("cornell-box", 5); }

TEST(MisWeights, SumToOneThinLens) {
    Scene scene = load_scene(scene_path("cornell-box"));
    scene.camera.lens_radius = 25.0f;
    scene.camera.focus_distance = 700.0f;
    check_scene(scene, "cornell-box with a thin lens", 5);
}
TEST(MisWeights, SumToOneCornellSpecular) { check_scene("cornell-specular", 8); }
TEST(MisWeights, SumToOneVeachMis) { check_scene("veach-mis", 5); }
TEST(MisWeights, SumToOneSky) { check_scene("sky", 5); }
TEST(MisWeights, SumToOneLampCeiling) { check_scene("lamp-ceiling", 6, 20); }

// Paths through media (cl/medium.h): medium vertices, index-matched boundaries, distance
// densities on both sides of every connection. A fog-filled room; a scattering ball behind an
// interface beside a glass sphere with a scattering interior, lit by the ceiling; the camera
// inside a ball under the environment (escaped rays end on an infinite light).
TEST(MisWeights, SumToOneInMedia) {
    {
        SceneBuilder b;
        lit_room(b);
        fill_with(b.scene, add_medium(b.scene, "fog", {0.05f, 0.05f, 0.1f}, {0.5f, 0.6f, 0.7f}, 0.4f));
        check_scene(b.scene, "fog-filled room", 5);
    }
    {
        SceneBuilder b;
        lit_room(b, /*with_block=*/false);
        int cloud = add_medium(b.scene, "cloud", {0.5f, 1.0f, 1.5f}, {4.0f, 4.0f, 3.0f}, -0.3f);
        b.sphere({-0.4f, 0.5f, 0.3f}, 0.35f, 2, /*inward=*/false, b.material(interface_material(cloud), "cloud"));
        Material glass = glass_material(1.5f);
        glass.interior_medium = add_medium(b.scene, "milk", {0.1f, 0.1f, 0.1f}, {2, 2, 2}, 0.6f);
        b.sphere({0.45f, 0.4f, 0.2f}, 0.3f, 2, /*inward=*/false, b.material(glass, "milky glass"));
        check_scene(b.scene, "scattering ball and milky glass", 8);
    }
    {
        SceneBuilder b;
        int white = add_medium(b.scene, "white", {0, 0, 0}, {1, 1, 1}, 0.5f);
        b.sphere({0, 0, 0}, 1.0f, 3, /*inward=*/false, b.material(interface_material(white), "ball"));
        b.camera({0, 0, 0}, {0.3f, 0.2f, 1}, 90.0f);
        add_environment(b.scene, {1, 1, 1});
        check_scene(b.scene, "inside a ball under the sky", 6);
    }
}

// bdpt under each mix (light subpaths per sample, inner connections): the weights of every path
// found sum to 1.
void check_mixes(const Scene& scene, int max_depth, std::initializer_list<std::pair<float, bool>> mixes) {
    for (auto [light_subpaths, connections] : mixes) {
        MisSums sums = mis_sums(scene, Integrator::Bdpt, max_depth, 64, 4, light_subpaths, connections);
        EXPECT_GE(sums.paths, 100) << light_subpaths << " " << connections;
        EXPECT_LT(sums.worst, kTolerance) << light_subpaths << " " << connections << ": " << sums.paths << " paths";
    }
}

// Efficiency-aware mixes (cl/strategies.h): the count-weighted balance heuristic still sums to 1
// over the strategies the mix enables.
TEST(MisWeights, SumToOneUnderStrategyMixes) {
    check_mixes(load_scene(scene_path("cornell-specular")), 8, {{0.25f, true}, {0.5f, false}, {0.0f, true}});
}

// Long paths (the Cornell box at max depth 20): each weight's terms beyond the two vertices next
// to the connection come from the subpaths' tails (mis_fill_camera_tails, mis_fill_light_tails in
// cl/mis.h), the others from the recursion's own steps, so a tail that weighed a strategy unlike
// its steps would make the weights of a long path sum to something else than 1.
TEST(MisWeights, SumToOneOnLongPaths) {
    check_mixes(load_scene(scene_path("cornell-box")), 20, {{1.0f, true}, {0.25f, true}, {0.5f, false}});
}

}  // namespace
}  // namespace clbdpt::test
