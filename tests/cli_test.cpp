// The command line as a user meets it: bad input of every kind gives one clear error line,
// a non-zero exit and no output file; a good render writes the image and the stats JSON.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <array>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>

#include "cli_test_util.h"
#include "film/image_io.h"
#include "render/strategy_pilot.h"

namespace {

using namespace clbdpt_cli_test;

namespace fs = std::filesystem;

struct BadInput {
    const char* name;
    std::string args;      // after "render"
    const char* expected;  // a piece of the error message
};

TEST_F(CliTest, BadInputGivesOneErrorLineAndNoOutput) {
    const std::string tiny = " --spp 1 --width 8 --height 8";
    const BadInput cases[] = {
        {"truncated OBJ", data("truncated_face.obj") + tiny, "truncated_face.obj:"},
        {"truncated vertex", data("truncated_vertex.obj") + tiny, "truncated_vertex.obj:"},
        {"NaN vertex", data("nan_vertex.obj") + tiny, "nan_vertex.obj:"},
        {"only degenerate triangles", data("degenerate_only.obj") + tiny, "no triangles with a non-zero area"},
        {"camera eye at its target", data("frame.obj") + tiny + " --lookat 1 1 1 1 1 1 0 1 0", "target must differ"},
        {"out-of-range face", data("out_of_range.obj") + tiny, "out_of_range.obj:"},
        {"empty OBJ", data("empty.obj") + tiny, "empty.obj"},
        {"bad JSON", data("bad_syntax.json") + tiny, "bad_syntax.json:"},
        {"unknown key", data("unknown_key.json") + tiny, "fovy"},
        {"missing mesh", data("missing_mesh.json") + tiny, "no_such_mesh.obj"},
        {"missing scene", data("no_such_scene.json") + tiny, "no_such_scene.json"},
        {"unknown device", data("defaults.json") + tiny + " --device no-such-device-xyz", "no-such-device-xyz"},
        {"unknown device index", data("defaults.json") + tiny + " --device 999", "999"},
        {"unsupported output", data("defaults.json") + tiny, "unsupported output"},
        {"film too large for memory", data("defaults.json") + " --spp 1 --width 32768 --height 32768 --strategy-images " +
                                          out("strategies"),
         "host memory"},
        {"binary garbage OBJ", data("garbage.obj") + tiny, "garbage.obj"},
        {"binary garbage JSON", data("garbage.json") + tiny, "garbage.json:"},
        {"index beyond any integer", data("huge_index.obj") + tiny, "huge_index.obj:5:"},
        {"negative index before the first vertex", data("negative_index.obj") + tiny, "negative_index.obj:5:"},
        {"coordinate beyond float range", data("inf_vertex.obj") + tiny, "inf_vertex.obj:2:"},
        {"non-UTF-8 path", data("no_such_\xff\xfe.obj") + tiny, "no_such_\xff\xfe.obj"},
        {"path longer than the system allows", data(std::string(5000, 'a') + ".obj") + tiny, "aaaa.obj"},
        {"a folder as the scene", std::string(CLBDPT_TEST_DATA_DIR) + tiny, "cannot open"},
        {"missing output folder", data("defaults.json") + tiny, "no_such_folder"},
        {"output folder that cannot be written", data("defaults.json") + tiny, "/proc/"},
        {"kernel build failure", data("defaults.json") + tiny, "kernel build failed for kernels/render.cl"},
        // PoCL keeps a work-group's path vertices on one thread's stack: a group this large at this
        // depth (about 14 GiB), or the default group at this depth, would overflow any stack limit
        // (1024 items at max depth 64 crashed with an 8 MiB limit before the check).
        {"work-group too large for a CPU thread's stack", data("defaults.json") + tiny + " --local-size 65536 --max-depth 1000",
         "a CPU work-group of 65536 items (--local-size) at max depth 1000"},
        {"max depth too large for a CPU thread's stack", data("defaults.json") + tiny + " --max-depth 100000",
         "a CPU work-group of 16 items (the default) at max depth 100000"},
    };
    // A kernel source that does not compile, read instead of the embedded one.
    const fs::path broken_kernels = dir_.parent_path() / (dir_.filename().string() + "_kernels");
    fs::create_directories(broken_kernels / "kernels");
    std::ofstream(broken_kernels / "kernels/render.cl") << "#error this kernel is broken on purpose\n";
    for (const BadInput& c : cases) {
        const std::string name = c.name;
        std::string output = name == "unsupported output"     ? out("image.xyz")
                             : name == "missing output folder" ? out("no_such_folder/image.png")
                             : name == "output folder that cannot be written" ? "/proc/clbdpt_test_image.png"
                                                                              : out("image.png");
        // The cache is bypassed so that the build really happens.
        const std::string env = name == "kernel build failure" ? "CLBDPT_KERNEL_DIR=" + broken_kernels.string() +
                                                                     " CLBDPT_CACHE_DIR=" + broken_kernels.string() + " "
                                                               : "";
        CommandResult r = run("render " + c.args + " -o " + output + " --stats " + out("stats.json"), env);
        const size_t log_at = r.output.find("(whole log: ");
        if (log_at != std::string::npos) fs::remove(r.output.substr(log_at + 12, r.output.find(')', log_at) - log_at - 12));
        EXPECT_NE(r.status, 0) << c.name << ": " << r.output;
        EXPECT_NE(r.output.find("clbdpt: error: "), std::string::npos) << c.name << ": " << r.output;
        EXPECT_NE(r.output.find(c.expected), std::string::npos) << c.name << ": " << r.output;
        // One line: the error, nothing after it.
        size_t err = r.output.find("clbdpt: error: ");
        if (err != std::string::npos) {
            EXPECT_EQ(r.output.find('\n', err), r.output.size() - 1) << c.name << ": " << r.output;
        }
        EXPECT_TRUE(dir_is_empty()) << c.name << ": left a file behind";
    }
    fs::remove_all(broken_kernels);
}

TEST_F(CliTest, RenderWritesImageAndStats) {
    CommandResult r = run("render " + data("materials.obj") + " --spp 2 --width 24 --height 16 -o " + out("a.exr") +
                " --stats " + out("s.json"));
    ASSERT_EQ(r.status, 0) << r.output;
    EXPECT_TRUE(fs::exists(out("a.exr")));
    std::ifstream in(out("s.json"));
    nlohmann::json j = nlohmann::json::parse(in);
    for (const char* key : {"spp", "seconds", "samples_per_second", "rays_per_second", "kernel_build_seconds", "device",
                            "triangles"})
        EXPECT_TRUE(j.contains(key)) << key;
    EXPECT_EQ(j["spp"], 2);
    EXPECT_EQ(j["samples"], 2 * 24 * 16);
    EXPECT_EQ(j["dropped_samples"], 0);
    EXPECT_GT(j["rays_per_second"].get<double>(), 0.0);
    EXPECT_GT(j["triangles"].get<int>(), 0);
    // The one-line summary names samples/s and rays/s.
    EXPECT_NE(r.output.find("samples/s"), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("rays/s"), std::string::npos) << r.output;
}

// A sample with a non-finite value (injected: pixel (12, 8)'s sample 0 gets a NaN) does not
// abort a render: it is left out, the image of the rest is written (finite), the stats name it,
// and the exit status is 1 with one error line saying how many and where.
TEST_F(CliTest, NonFiniteSampleIsDroppedNotFatal) {
    CommandResult r = run("render " + data("materials.obj") + " --integrator bdpt --spp 4 --width 24 --height 16 -o " +
                          out("a.exr") + " --stats " + out("s.json") + " --debug-nan-pixel 204");
    EXPECT_EQ(r.status, 1) << r.output;
    EXPECT_NE(r.output.find("clbdpt: error: 1 of 1536 samples had a non-finite value"), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("pixel (12, 8) sample 0 strategy s="), std::string::npos) << r.output;
    int w = 0, h = 0;
    std::vector<float> rgb = clbdpt::read_image_rgb(out("a.exr"), &w, &h);
    ASSERT_EQ(size_t(w) * h * 3, rgb.size());
    for (float v : rgb) ASSERT_TRUE(std::isfinite(v));
    // Three samples remain at that pixel: it is not black.
    const float* p = &rgb[(8 * size_t(w) + 12) * 3];
    EXPECT_GT(p[0] + p[1] + p[2], 0.0f);
    std::ifstream in(out("s.json"));
    nlohmann::json j = nlohmann::json::parse(in);
    EXPECT_EQ(j["dropped_samples"], 1);
    ASSERT_EQ(j["first_dropped_samples"].size(), 1u);
    EXPECT_EQ(j["first_dropped_samples"][0]["pixel"], nlohmann::json({12, 8}));
    EXPECT_EQ(j["first_dropped_samples"][0]["sample"], 0);
    EXPECT_GE(j["first_dropped_samples"][0]["t"].get<int>(), 1);
}

// What real exporters write routinely (a missing MTL, slivers) renders, with one warning line
// each; a model without lights renders lit by the default environment.
TEST_F(CliTest, ExporterQuirksWarnAndRender) {
    struct Quirk {
        const char* file;
        const char* warning;
    };
    const Quirk quirks[] = {{"missing_mtl.obj", "cannot open"}, {"zero_area.obj", "dropped 1 degenerate triangle"}};
    for (const Quirk& q : quirks) {
        CommandResult r = run("render " + data(q.file) + " --spp 1 --width 8 --height 8 -o " + out("q.png"));
        EXPECT_EQ(r.status, 0) << q.file << ": " << r.output;
        EXPECT_TRUE(fs::exists(out("q.png"))) << q.file;
        EXPECT_NE(r.output.find(q.warning), std::string::npos) << q.file << ": " << r.output;
        EXPECT_NE(r.output.find("uniform white environment"), std::string::npos) << q.file << ": " << r.output;
        EXPECT_EQ(r.output.find("error"), std::string::npos) << q.file << ": " << r.output;
        fs::remove(out("q.png"));
    }
}

// The camera can be aimed from the command line (pbrt's LookAt order), and its field of view
// set: frame.obj's triangle (projected area 4 of its 8 x 8 bounds seen from +z) looks tiny from
// 200 units away, and fills a 0.2 degree view aimed at its centroid.
TEST_F(CliTest, CameraOverridesAimTheView) {
    auto coverage = [&](const std::string& camera) {
        CommandResult r = run("render " + data("frame.obj") + " --no-default-light --aov depth --width 32 --height 32 " +
                              camera + " -o " + out("d.exr"));
        EXPECT_EQ(r.status, 0) << camera << ": " << r.output;
        int w = 0, h = 0;
        std::vector<float> rgb = clbdpt::read_image_rgb(out("d.exr"), &w, &h);
        int hit = 0;
        for (size_t i = 0; i < rgb.size(); i += 3) hit += rgb[i] > 0.0f;
        return double(hit) / double(w * h);
    };
    const double framed = coverage("");
    const double far = coverage("--lookat 0 0 200 0 0 0 0 1 0");
    const double narrow = coverage("--eye 0.333 -0.667 200 --target 0.333 -0.667 0 --fov 0.2");
    EXPECT_GT(framed, 0.03);
    EXPECT_LT(far, 0.01);
    EXPECT_GT(narrow, 0.99);
}

// An axis-aligned box [lo, hi] as 12 triangles appended to OBJ text (vertex numbers continue
// from *count).
std::string box_obj(float x0, float y0, float z0, float x1, float y1, float z1, int* count) {
    std::string obj;
    for (int i = 0; i < 8; ++i)
        obj += "v " + std::to_string(i & 1 ? x1 : x0) + " " + std::to_string(i & 2 ? y1 : y0) + " " +
               std::to_string(i & 4 ? z1 : z0) + "\n";
    const int quads[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4}, {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
    for (const auto& q : quads)
        obj += "f " + std::to_string(*count + q[0] + 1) + " " + std::to_string(*count + q[1] + 1) + " " +
               std::to_string(*count + q[2] + 1) + " " + std::to_string(*count + q[3] + 1) + "\n";
    *count += 8;
    return obj;
}

// A model that encloses its content (a room with pillars: from outside, only a wall) gets a
// camera inside, said in one note line; a solid block keeps the outside view.
TEST_F(CliTest, EnclosingModelsAreViewedFromInside) {
    int count = 0;
    std::string room = box_obj(-10, 0, -6, 10, 5, 6, &count);
    for (int i = -2; i <= 2; ++i) room += box_obj(i * 4.0f - 0.4f, 0, -3.4f, i * 4.0f + 0.4f, 5, -2.6f, &count);
    for (int i = -2; i <= 2; ++i) room += box_obj(i * 4.0f - 0.4f, 0, 2.6f, i * 4.0f + 0.4f, 5, 3.4f, &count);
    { std::ofstream(out("room.obj")) << room; }
    count = 0;
    { std::ofstream(out("block.obj")) << box_obj(-1, -1, -1, 1, 1, 1, &count); }

    CommandResult inside = run("render " + out("room.obj") + " --aov depth --width 16 --height 16 -o " + out("r.exr"));
    ASSERT_EQ(inside.status, 0) << inside.output;
    EXPECT_NE(inside.output.find("camera placed inside"), std::string::npos) << inside.output;
    int w = 0, h = 0;
    std::vector<float> depth = clbdpt::read_image_rgb(out("r.exr"), &w, &h);
    // From inside, every pixel sees a wall or a pillar closer than the room is long.
    for (size_t i = 0; i < depth.size(); i += 3) {
        EXPECT_GT(depth[i], 0.0f);
        EXPECT_LT(depth[i], 25.0f);
    }
    CommandResult aimed = run("render " + out("room.obj") + " --lookat 0 2 30 0 2 0 0 1 0 --aov depth --width 8 --height 8 -o " +
                              out("a.exr"));
    ASSERT_EQ(aimed.status, 0) << aimed.output;
    EXPECT_EQ(aimed.output.find("camera placed inside"), std::string::npos) << aimed.output;

    CommandResult block = run("render " + out("block.obj") + " --aov depth --width 8 --height 8 -o " + out("b.exr"));
    ASSERT_EQ(block.status, 0) << block.output;
    EXPECT_EQ(block.output.find("camera placed inside"), std::string::npos) << block.output;
}

TEST_F(CliTest, AovRendersTheFirstHit) {
    CommandResult r = run("render " + data("materials.obj") + " --aov normal --width 16 --height 16 -o " + out("n.exr"));
    ASSERT_EQ(r.status, 0) << r.output;
    EXPECT_TRUE(fs::exists(out("n.exr")));
}

// Two PoCL devices share one render: the work units split between them, and the image is one
// device's bit for bit (results are added in unit order whoever rendered them).
TEST_F(CliTest, TwoDevicesShareOneRender) {
    const std::string scene = " " + std::string(CLBDPT_SCENES_DIR) + "/cornell-box/cornell-box.json --spp 6 --width 24 --height 24";
    CommandResult one = run("render" + scene + " -o " + out("one.exr"));
    ASSERT_EQ(one.status, 0) << one.output;
    CommandResult two = run("render" + scene + " --device all -o " + out("two.exr") + " --stats " + out("two.json"),
                            "POCL_DEVICES='pthread pthread' POCL_MAX_PTHREAD_COUNT=1 ");
    ASSERT_EQ(two.status, 0) << two.output;
    std::ifstream in(out("two.json"));
    nlohmann::json j = nlohmann::json::parse(in);
    EXPECT_EQ(j["devices"], 2);
    expect_same_image(out("one.exr"), out("two.exr"));
}

// Devices of unequal speed (PoCL's pthread device on two threads beside its single-threaded
// basic device), and two basic devices (launches of varying widths from two threads at once
// once tripped an assertion inside PoCL): the image is still one device's bit for bit, at two
// film sizes (one unit per pass, and several units per pass so that passes are split between
// the devices); the summary and --stats report each device's share, which add up to every
// sample once.
TEST_F(CliTest, UnequalDevicesShareOneRenderExactly) {
    for (const char* size : {"--width 24 --height 24 --spp 6", "--width 96 --height 96 --spp 4"})
    for (const char* devices : {"POCL_DEVICES='pthread basic' POCL_MAX_PTHREAD_COUNT=2 ", "POCL_DEVICES='basic basic' "}) {
        const std::string render = "render " + std::string(CLBDPT_SCENES_DIR) +
                                   "/cornell-box/cornell-box.json --integrator bdpt " + size;
        CommandResult one = run(render + " -o " + out("one.exr"));
        ASSERT_EQ(one.status, 0) << one.output;
        CommandResult two = run(render + " --device all -o " + out("two.exr") + " --stats " + out("two.json"), devices);
        ASSERT_EQ(two.status, 0) << devices << two.output;
        EXPECT_NE(two.output.find("% of the samples"), std::string::npos) << two.output;
        expect_same_image(out("one.exr"), out("two.exr"));
        std::ifstream in(out("two.json"));
        const nlohmann::json j = nlohmann::json::parse(in);
        ASSERT_EQ(j["device_shares"].size(), 2u) << j.dump(2);
        uint64_t samples = 0;
        double share = 0;
        for (const nlohmann::json& d : j["device_shares"]) {
            samples += d["samples"].get<uint64_t>();
            share += d["share"].get<double>();
            EXPECT_GE(d["samples_per_second"].get<double>(), 0.0);
        }
        EXPECT_EQ(samples, j["samples"].get<uint64_t>());
        EXPECT_NEAR(share, 1.0, 1e-12);
    }
}

// A device whose launches fail mid-render (injected: device K fails after N launches, here in
// the middle of a pass of 9 launches) leaves the render with one warning; the run it was
// rendering goes to the other device, and the image equals one device's render bit for bit.
// N is below 9 for either device: each device's first run is one pass (its rate is not yet
// measured, render/unit_queue.cpp), and how many launches it gets after that depends on the
// two devices' speeds (on a loaded machine device 0 once got no more, and "0:14" never failed).
// The last device failing fails the render, writing nothing.
TEST_F(CliTest, FailingDeviceLosesNothing) {
    const std::string render = "render " + std::string(CLBDPT_SCENES_DIR) +
                               "/cornell-box/cornell-box.json --integrator bdpt --spp 6 --width 24 --height 24 "
                               "--batch-items 64";
    const std::string two_devices = "POCL_DEVICES='pthread pthread' POCL_MAX_PTHREAD_COUNT=1 ";
    CommandResult one = run(render + " -o " + out("one.exr"));
    ASSERT_EQ(one.status, 0) << one.output;
    for (const char* failing : {"1:5", "0:7"}) {
        CommandResult r = run(render + " --device all --debug-fail-device " + failing + " -o " + out("two.exr") +
                                  " --stats " + out("two.json"),
                              two_devices);
        ASSERT_EQ(r.status, 0) << failing << ": " << r.output;
        EXPECT_NE(r.output.find("clbdpt: warning: device "), std::string::npos) << r.output;
        EXPECT_NE(r.output.find("injected by --debug-fail-device"), std::string::npos) << r.output;
        std::ifstream in(out("two.json"));
        const nlohmann::json j = nlohmann::json::parse(in);
        EXPECT_EQ(j["spp"], 6);
        EXPECT_EQ(j["samples"], 6 * 24 * 24);  // the failed pass's samples do not count
        EXPECT_EQ(j["dropped_devices"].size(), 1u);
        expect_same_image(out("one.exr"), out("two.exr"));
    }
    fs::remove(out("one.exr"));
    fs::remove(out("two.exr"));
    fs::remove(out("two.json"));
    CommandResult alone = run(render + " --debug-fail-device 0:3 -o " + out("alone.exr"));
    EXPECT_EQ(alone.status, 1) << alone.output;
    EXPECT_NE(alone.output.find("clbdpt: error: OpenCL: launch failed (injected"), std::string::npos) << alone.output;
    EXPECT_TRUE(dir_is_empty());
}

// The default integrator (auto) runs the efficiency pilot when the render is long enough for it
// to pay off, reports what it measured and renders with the candidate it predicts best; short
// renders use plain bdpt; --light-subpaths / --connections fix the mix by hand.
// The pilot's candidates at the ends (full bdpt, pt, lt) where they decided alone: pt or lt
// chosen, leading every other by kClearLeadMargin, and the two mixes between named as not run.
void ends_alone_hold(const nlohmann::json& p) {
    ASSERT_EQ(p["not_run"].size(), 2u) << p.dump(2);
    EXPECT_EQ(p["not_run"][0], "bdpt, 0.5 light subpaths per sample");
    EXPECT_EQ(p["not_run"][1], "bdpt, 1 light subpath per sample, no inner connections");
    ASSERT_GE(p["candidates"].size(), 2u);
    EXPECT_EQ(p["candidates"][0]["name"], "bdpt, 1 light subpath per sample");
    const std::string chosen = p["chosen"].get<std::string>();
    EXPECT_TRUE(chosen == "pt" || chosen == "lt") << chosen;
    EXPECT_GE(p["lead_at_ends"].get<double>(), clbdpt::kClearLeadMargin);
    double chosen_efficiency = 0;
    for (const nlohmann::json& c : p["candidates"])
        if (c["name"] == chosen) chosen_efficiency = c["efficiency"].get<double>();
    for (const nlohmann::json& c : p["candidates"]) {
        EXPECT_TRUE(c["name"] == "bdpt, 1 light subpath per sample" || c["name"] == "pt" || c["name"] == "lt")
            << c["name"];
        if (c["name"] != chosen) {
            EXPECT_GE(chosen_efficiency, clbdpt::kClearLeadMargin * c["efficiency"].get<double>());
        }
    }
}

TEST_F(CliTest, AutoChoosesTheStrategyMixByPilot) {
    const std::string scene = " " + std::string(CLBDPT_SCENES_DIR) + "/lamp-ceiling/lamp-ceiling.json --width 64 --height 64";
    CommandResult r = run("render" + scene + " --spp 160 -o " + out("auto.exr") + " --stats " + out("auto.json"));
    ASSERT_EQ(r.status, 0) << r.output;
    std::ifstream in(out("auto.json"));
    nlohmann::json j = nlohmann::json::parse(in);
    ASSERT_TRUE(j.contains("strategy_pilot")) << j.dump(2);
    const nlohmann::json& p = j["strategy_pilot"];
    // Three bdpt mixes, pt and lt: the lamp's room is all diffuse, without media; and where the
    // pilot chose a bdpt mix of them, that mix again with Russian roulette in its light subpaths.
    // Or, where lt led full bdpt and pt by kClearLeadMargin, those three alone (ends_alone_hold).
    if (!p["not_run"].empty()) {
        ends_alone_hold(p);
    } else {
        ASSERT_GE(p["candidates"].size(), 5u);
        ASSERT_LE(p["candidates"].size(), 6u);
        EXPECT_EQ(p["candidates"][4]["name"], "lt");
    }
    if (p["candidates"].size() == 6u) {
        EXPECT_NE(p["candidates"][5]["name"].get<std::string>().find(", Russian roulette from light bounce 2"),
                  std::string::npos)
            << p.dump(2);
    }
    double best_camera = 0;
    for (const nlohmann::json& c : p["candidates"])
        if (c["name"] != "lt") best_camera = std::max(best_camera, c["efficiency_transport_only"].get<double>());
    // The shared part counted is one figure for every camera candidate, a share of what each left
    // out of its own terms; lt's terms were not compared.
    const double counted = p["candidates"][0]["variance_shared_counted"].get<double>();
    for (const nlohmann::json& c : p["candidates"]) {
        if (c["name"] == "lt") {
            EXPECT_EQ(c["variance_shared_counted"].get<double>(), 0.0) << c.dump();
            continue;
        }
        EXPECT_EQ(c["variance_shared_counted"].get<double>(), counted) << c.dump();
        EXPECT_GE(counted, 0.0);
        EXPECT_LE(counted, c["variance_shared_tail"].get<double>() * (1.0 + 1e-9) + 1e-300) << c.dump();
    }
    // What full bdpt's subset moments say a candidate's passes missed: only the mix without
    // inner connections has such a floor.
    for (const nlohmann::json& c : p["candidates"]) {
        const double missed = c["variance_missed"].get<double>();
        if (c["name"].get<std::string>().find("no inner connections") == std::string::npos) {
            EXPECT_EQ(missed, 0.0) << c.dump();
        } else {
            EXPECT_GE(missed, 0.0) << c.dump();
        }
    }
    std::string best;
    double best_efficiency = -1;
    for (const nlohmann::json& c : p["candidates"]) {
        EXPECT_GT(c["efficiency"].get<double>(), 0.0) << c.dump();
        EXPECT_GT(c["seconds_per_pass"].get<double>(), 0.0) << c.dump();
        EXPECT_GE(c["efficiency_transport_only"].get<double>(), c["efficiency"].get<double>()) << c.dump();
        if (c["name"] == "lt" && c["efficiency"].get<double>() <= best_camera) continue;
        if (c["efficiency"].get<double>() > best_efficiency) {
            best_efficiency = c["efficiency"].get<double>();
            best = c["name"].get<std::string>();
        }
    }
    EXPECT_EQ(p["chosen"], best);
    EXPECT_EQ(j["strategy_mix"], best);
    EXPECT_EQ(j["spp"], 160);
    EXPECT_NE(r.output.find(best), std::string::npos) << "the summary names the mix: " << r.output;
    // The lamp lights the room through the ceiling: a path tracer finds its light far less often.
    EXPECT_NE(best, "pt");
    int w = 0, h = 0;
    for (float v : clbdpt::read_image_rgb(out("auto.exr"), &w, &h)) ASSERT_TRUE(std::isfinite(v));

    // point-spot's path tracer leads full bdpt 6-10x on its pilot's grid (seeds 1-6, 64 x 64,
    // 160 spp): the mixes between do not run, and the summary says so.
    const std::string spot = " " + std::string(CLBDPT_SCENES_DIR) + "/point-spot/point-spot.json --width 64 --height 64";
    CommandResult ends = run("render" + spot + " --spp 160 -o " + out("ends.exr") + " --stats " + out("ends.json"));
    ASSERT_EQ(ends.status, 0) << ends.output;
    std::ifstream in_ends(out("ends.json"));
    const nlohmann::json je = nlohmann::json::parse(in_ends);
    ASSERT_TRUE(je.contains("strategy_pilot")) << je.dump(2);
    ends_alone_hold(je["strategy_pilot"]);
    EXPECT_EQ(je["strategy_mix"], "pt");
    EXPECT_NE(ends.output.find("the bdpt mixes between not run (pt led the others"), std::string::npos) << ends.output;

    CommandResult few = run("render" + scene + " --spp 4 -o " + out("few.exr") + " --stats " + out("few.json"));
    ASSERT_EQ(few.status, 0) << few.output;
    std::ifstream in_few(out("few.json"));
    nlohmann::json jf = nlohmann::json::parse(in_few);
    EXPECT_FALSE(jf.contains("strategy_pilot"));
    EXPECT_EQ(jf["strategy_mix"], "bdpt, 1 light subpath per sample");

    CommandResult fixed = run("render" + scene + " --spp 160 --light-subpaths 0.25 --connections off -o " +
                              out("fixed.exr") + " --stats " + out("fixed.json"));
    ASSERT_EQ(fixed.status, 0) << fixed.output;
    std::ifstream in_fixed(out("fixed.json"));
    nlohmann::json jx = nlohmann::json::parse(in_fixed);
    EXPECT_FALSE(jx.contains("strategy_pilot"));
    EXPECT_EQ(jx["strategy_mix"], "bdpt, 0.25 light subpaths per sample, no inner connections");
    EXPECT_EQ(jx["light_subpaths"], 0.25);

    CommandResult wrong = run("render" + scene + " --spp 1 --integrator pt --light-subpaths 0.5 -o " + out("w.exr"));
    EXPECT_NE(wrong.status, 0);
    EXPECT_NE(wrong.output.find("apply to bdpt"), std::string::npos) << wrong.output;
    EXPECT_FALSE(fs::exists(out("w.exr")));
}

// A path tracer cannot render light that a point, spot or directional light sends by way of a
// mirror or glass, and its pilot passes show no variance for what they miss: beside point-spot's
// room with a mirror next to its point light, the default chose pt in every seed and its image
// lacked 13% of the light (render/strategy_pilot.h, delta_light_meets_specular). The default must
// leave pt out (as candidate and as the taker of adaptive sampling's extra samples), and bdpt
// without inner connections, which misses that light where it is seen in a mirror, and agree
// with bdpt; --integrator pt and --connections off warn. Tolerance: 1% of the image mean. Over
// 4 seeds at these settings the default's and bdpt's means spread by 0.03% at most (a standard
// error of about 0.02%), so 1% is some 40 standard errors, and 13 times smaller than the light
// pt misses.
TEST_F(CliTest, AutoLeavesOutPtWhereItMissesLight) {
    const std::string scene = " " + data("point_mirror.json");
    CommandResult r = run("render" + scene + " -o " + out("auto.exr") + " --stats " + out("auto.json"));
    ASSERT_EQ(r.status, 0) << r.output;
    EXPECT_EQ(r.output.find("warning"), std::string::npos) << r.output;
    std::ifstream in(out("auto.json"));
    nlohmann::json j = nlohmann::json::parse(in);
    ASSERT_TRUE(j.contains("strategy_pilot")) << j.dump(2);
    // Full bdpt and half its light subpaths, and the one chosen of the two again with Russian
    // roulette in its light subpaths.
    const nlohmann::json& candidates = j["strategy_pilot"]["candidates"];
    ASSERT_EQ(candidates.size(), 3u) << candidates.dump(2);
    for (const nlohmann::json& c : candidates) {
        EXPECT_EQ(c["name"].get<std::string>().find("bdpt"), 0u) << c.dump();
        EXPECT_EQ(c["name"].get<std::string>().find("no inner connections"), std::string::npos) << c.dump();
    }
    EXPECT_NE(candidates[2]["name"].get<std::string>().find("Russian roulette from light bounce 2"), std::string::npos)
        << candidates.dump(2);
    EXPECT_EQ(j["integrator"], "bdpt");
    EXPECT_EQ(j["inner_connections"], true);
    EXPECT_NE(j["adaptive"]["integrator"], "pt");
    EXPECT_NE(j["strategy_mix_note"].get<std::string>().find("pt and bdpt without inner connections left out"),
              std::string::npos)
        << j.dump(2);

    CommandResult bdpt = run("render" + scene + " --integrator bdpt -o " + out("bdpt.exr"));
    ASSERT_EQ(bdpt.status, 0) << bdpt.output;
    auto image_mean = [&](const std::string& name) {
        int w = 0, h = 0;
        double sum = 0;
        const std::vector<float> rgb = clbdpt::read_image_rgb(out(name), &w, &h);
        for (float v : rgb) sum += v;
        return sum / double(rgb.size());
    };
    const double automatic = image_mean("auto.exr"), reference = image_mean("bdpt.exr");
    ASSERT_GT(reference, 0.1);
    EXPECT_NEAR(automatic / reference, 1.0, 0.01);

    CommandResult pt = run("render" + scene + " --spp 1 --integrator pt -o " + out("pt.exr"));
    ASSERT_EQ(pt.status, 0) << pt.output;
    EXPECT_NE(pt.output.find("warning: --integrator pt: it cannot render light from point, spot or directional lights by "
                             "way of mirror or glass"),
              std::string::npos)
        << pt.output;
    CommandResult off = run("render" + scene + " --spp 1 --connections off -o " + out("off.exr"));
    ASSERT_EQ(off.status, 0) << off.output;
    EXPECT_NE(off.output.find("warning: --connections off: bdpt without inner connections cannot render light"),
              std::string::npos)
        << off.output;
    EXPECT_EQ(bdpt.output.find("warning"), std::string::npos) << bdpt.output;
}

// point-spot has two light groups (a point and a spot light) and no media: by default its light
// samples take every group (NEE_EVERY_LIGHT); --light-samples one takes one light per sample, and
// every takes every group in a scene with one group too (the Cornell box: its two light
// triangles are one group). The stats and the kernel flags say which; an unknown value is one
// error line.
TEST_F(CliTest, LightSamplesOfEveryGroupOrOne) {
    auto render_with = [&](const std::string& scene, const std::string& flags, const std::string& name) {
        CommandResult r = run("render " + std::string(CLBDPT_SCENES_DIR) + "/" + scene + "/" + scene +
                              ".json --width 16 --height 16 --spp 2 --integrator pt " + flags + " -o " +
                              out(name + ".exr") + " --stats " + out(name + ".json"));
        EXPECT_EQ(r.status, 0) << r.output;
        std::ifstream in(out(name + ".json"));
        return nlohmann::json::parse(in);
    };
    auto has_flag = [](const nlohmann::json& j, const std::string& flag) {
        for (const nlohmann::json& d : j["kernel_defines"])
            if (d == flag) return true;
        return false;
    };
    nlohmann::json automatic = render_with("point-spot", "", "auto");
    EXPECT_EQ(automatic["light_samples"], "every");
    EXPECT_TRUE(has_flag(automatic, "NEE_EVERY_LIGHT"));
    nlohmann::json one = render_with("point-spot", "--light-samples one", "one");
    EXPECT_EQ(one["light_samples"], "one");
    EXPECT_FALSE(has_flag(one, "NEE_EVERY_LIGHT"));
    EXPECT_TRUE(has_flag(one, "NEE_CONE_AWARE"));
    EXPECT_EQ(render_with("cornell-box", "", "box")["light_samples"], "one");
    EXPECT_EQ(render_with("cornell-box", "--light-samples every", "box_every")["light_samples"], "every");
    CommandResult wrong = run("render " + std::string(CLBDPT_SCENES_DIR) +
                              "/point-spot/point-spot.json --spp 1 --light-samples all -o " + out("w.exr"));
    EXPECT_NE(wrong.status, 0);
    EXPECT_NE(wrong.output.find("--light-samples"), std::string::npos) << wrong.output;
    EXPECT_FALSE(fs::exists(out("w.exr")));
}

// --russian-roulette: the default starts camera subpaths' roulette at bounce 4 and leaves light
// subpaths to the pilot; off and N fix both kinds (N also for the pilot's candidates, whose
// choice must not undo it); the stats say where each starts; a bad value is one error line.
TEST_F(CliTest, RussianRouletteAsTheCommandLineSays) {
    const std::string scene = std::string(CLBDPT_SCENES_DIR) + "/cornell-specular/cornell-specular.json";
    auto render_with = [&](const std::string& flags, const std::string& name) {
        CommandResult r = run("render " + scene + " --width 32 --height 32 " + flags + " -o " +
                              out(name + ".exr") + " --stats " + out(name + ".json"));
        EXPECT_EQ(r.status, 0) << r.output;
        std::ifstream in(out(name + ".json"));
        return nlohmann::json::parse(in);
    };
    struct Case {
        const char* name;
        const char* flags;
        const char* camera_subpaths;  // what --stats says
        const char* light_subpaths;
    };
    const Case cases[] = {
        {"pt", "--integrator pt", "from bounce 4", "none traced"},
        {"off", "--integrator bdpt --russian-roulette off", "off", "off"},
        {"lt", "--integrator lt --russian-roulette 3", "none traced", "from bounce 3"},
        // Each kind its own: what the pilot's candidate with light roulette renders, forced.
        {"both", "--integrator bdpt --russian-roulette 4,2", "from bounce 4", "from bounce 2"},
        {"light_off", "--integrator bdpt --russian-roulette 0,off", "from bounce 0", "off"},
    };
    for (const Case& c : cases) {
        const nlohmann::json j = render_with(std::string("--spp 16 ") + c.flags, c.name);
        EXPECT_EQ(j["russian_roulette"]["camera_subpaths"], c.camera_subpaths) << c.name << j.dump(2);
        EXPECT_EQ(j["russian_roulette"]["light_subpaths"], c.light_subpaths) << c.name << j.dump(2);
    }
    // Enough samples that the pilot runs (it may take a tenth of them).
    const nlohmann::json fixed = render_with("--spp 400 --russian-roulette 1", "fixed");
    EXPECT_EQ(fixed["russian_roulette"]["camera_subpaths"], "from bounce 1") << fixed.dump(2);
    ASSERT_TRUE(fixed.contains("strategy_pilot")) << fixed.dump(2);
    for (const nlohmann::json& c : fixed["strategy_pilot"]["candidates"]) {
        const std::string name = c["name"].get<std::string>();
        if (name != "pt") {
            EXPECT_NE(name.find("Russian roulette from light bounce 1"), std::string::npos) << name;
        }
    }
    if (fixed["integrator"] != "pt") {
        EXPECT_EQ(fixed["russian_roulette"]["light_subpaths"], "from bounce 1");
    }
    for (const char* bad : {"sometimes", "-1", "2x", "99999", "4,", ",2", "4,2,1", "auto,2", "4:2"}) {
        CommandResult wrong = run("render " + scene + " --spp 1 --russian-roulette " + bad + " -o " + out("w.exr"));
        EXPECT_NE(wrong.status, 0) << bad;
        EXPECT_NE(wrong.output.find("--russian-roulette"), std::string::npos) << wrong.output;
        EXPECT_FALSE(fs::exists(out("w.exr")));
    }
}

TEST_F(CliTest, DevicesListsAtLeastOne) {
    CommandResult r = run("devices");
    ASSERT_EQ(r.status, 0) << r.output;
    EXPECT_NE(r.output.find("0 "), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("CPU"), std::string::npos) << r.output;
}

TEST_F(CliTest, HelpDocumentsTheOptions) {
    CommandResult r = run("render --help");
    EXPECT_EQ(r.status, 0);
    for (const char* opt : {"--output", "--spp", "--time", "--max-depth", "--seed", "--device", "--width", "--height",
                            "--stats", "--integrator", "--aov", "--light-subpaths", "--connections", "--light-samples",
                            "--russian-roulette", "--sampler", "--caustic-merging", "--merge-radius"})
        EXPECT_NE(r.output.find(opt), std::string::npos) << opt;
}

// --caustic-merging (cl/caustic_merging.h): the default merges in cornell-specular's BDPT mix
// (a summary line, --stats' caustic_merging object, the kernel flag), explicit bdpt does not
// unless asked, off does not, the Cornell box (no mirror or glass) never does; a bad value or
// radius is an error and writes nothing.
TEST_F(CliTest, CausticMergingAsTheCommandLineSays) {
    const std::string specular = std::string(CLBDPT_SCENES_DIR) + "/cornell-specular/cornell-specular.json";
    const std::string box = std::string(CLBDPT_SCENES_DIR) + "/cornell-box/cornell-box.json";
    auto render_with = [&](const std::string& scene, const std::string& flags, const std::string& name,
                           CommandResult* result = nullptr) {
        CommandResult r = run("render " + scene + " --width 32 --height 32 --spp 4 " + flags + " -o " +
                              out(name + ".exr") + " --stats " + out(name + ".json"));
        EXPECT_EQ(r.status, 0) << r.output;
        if (result) *result = r;
        std::ifstream in(out(name + ".json"));
        return nlohmann::json::parse(in);
    };
    auto merged = [](const nlohmann::json& j) {
        bool flag = false;
        for (const nlohmann::json& d : j["kernel_defines"]) flag = flag || d == "HAS_CAUSTIC_MERGING";
        EXPECT_EQ(flag, j["caustic_merging"]["enabled"].get<bool>()) << j.dump(2);
        return j["caustic_merging"]["enabled"].get<bool>();
    };
    CommandResult r;
    const nlohmann::json automatic = render_with(specular, "--integrator auto", "auto", &r);
    if (automatic["integrator"] != "pt") {  // a pilot below 4 spp is skipped: the default is bdpt
        EXPECT_TRUE(merged(automatic));
        EXPECT_GT(automatic["caustic_merging"]["photons"].get<uint64_t>(), 0u);
        EXPECT_LE(automatic["caustic_merging"]["radius_smallest"].get<double>(),
                  automatic["caustic_merging"]["radius_first_pass"].get<double>());
        EXPECT_NE(r.output.find("caustic merging:"), std::string::npos) << r.output;
    }
    EXPECT_FALSE(merged(render_with(specular, "--integrator bdpt", "bdpt")));
    EXPECT_TRUE(merged(render_with(specular, "--integrator bdpt --caustic-merging on", "on")));
    EXPECT_FALSE(merged(render_with(specular, "--caustic-merging off", "off")));
    EXPECT_FALSE(merged(render_with(box, "--integrator bdpt --caustic-merging on", "box")));
    for (const char* bad : {"--caustic-merging maybe", "--merge-radius 0"}) {
        CommandResult wrong = run("render " + specular + " --spp 1 " + bad + " -o " + out("w.exr"));
        EXPECT_NE(wrong.status, 0) << bad;
        EXPECT_FALSE(fs::exists(out("w.exr"))) << bad;
    }
}

}  // namespace

// Adaptive sampling (render/adaptive.h) adds samples where neighbours are noisy, on the Cornell
// box the light's outline, and nothing else: a pixel it did not refine is the same as without
// it, bit for bit, and the image stays finite. Off, and where it cannot run (zsobol), the stats
// say so.
TEST_F(CliTest, AdaptiveSamplingRefinesSomePixelsAndLeavesTheRest) {
    const std::string scene =
        " " + std::string(CLBDPT_SCENES_DIR) + "/cornell-box/cornell-box.json --width 48 --height 48 --spp 16 --integrator pt";
    CommandResult on = run("render" + scene + " -o " + out("on.exr") + " --stats " + out("on.json"));
    ASSERT_EQ(on.status, 0) << on.output;
    CommandResult off = run("render" + scene + " --adaptive off -o " + out("off.exr") + " --stats " + out("off.json"));
    ASSERT_EQ(off.status, 0) << off.output;
    std::ifstream in_on(out("on.json")), in_off(out("off.json"));
    const nlohmann::json j_on = nlohmann::json::parse(in_on), j_off = nlohmann::json::parse(in_off);
    ASSERT_TRUE(j_on["adaptive"]["enabled"].get<bool>()) << j_on.dump(2);
    const uint64_t extra = j_on["adaptive"]["extra_samples"].get<uint64_t>();
    const uint64_t refined = j_on["adaptive"]["pixels_refined"].get<uint64_t>();
    EXPECT_GT(refined, 0u);
    EXPECT_LT(refined, 48u * 48u / 4) << "only the light's outline is refined";
    EXPECT_GE(extra, refined * 16u);
    EXPECT_EQ(j_on["samples"].get<uint64_t>(), j_off["samples"].get<uint64_t>() + extra);
    EXPECT_FALSE(j_off["adaptive"]["enabled"].get<bool>());
    EXPECT_EQ(j_on["adaptive"]["integrator"], "pt");
    EXPECT_NE(on.output.find("adaptive sampling"), std::string::npos) << on.output;
    EXPECT_EQ(on.output.find("path-traced"), std::string::npos) << "a pt render's own extra samples";

    int w = 0, h = 0;
    const std::vector<float> a = clbdpt::read_image_rgb(out("on.exr"), &w, &h);
    const std::vector<float> b = clbdpt::read_image_rgb(out("off.exr"), &w, &h);
    ASSERT_EQ(a.size(), b.size());
    size_t changed = 0;
    for (size_t i = 0; i < a.size(); i += 3) {
        ASSERT_TRUE(std::isfinite(a[i]) && std::isfinite(a[i + 1]) && std::isfinite(a[i + 2]));
        changed += a[i] != b[i] || a[i + 1] != b[i + 1] || a[i + 2] != b[i + 2];
    }
    EXPECT_GT(changed, 0u);
    EXPECT_LE(changed, refined) << "a pixel without extra samples is unchanged";

    CommandResult z = run("render" + scene + " --sampler zsobol -o " + out("z.exr") + " --stats " + out("z.json"));
    ASSERT_EQ(z.status, 0) << z.output;
    std::ifstream in_z(out("z.json"));
    EXPECT_FALSE(nlohmann::json::parse(in_z)["adaptive"]["enabled"].get<bool>());
}
