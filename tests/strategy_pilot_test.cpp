// The strategy pilot's sparse grid (render_item_pixel with a stride; render/strategy_pilot.h),
// without OpenCL: which pixels a sparse pass visits, which renders get a pilot, which scenes have
// light tracing among the candidates, and how the pilot chooses.
#include <gtest/gtest.h>

#include <cmath>
#include <set>

#include "render/strategy_pilot.h"
#include "render_test_util.h"
#include "shared/types.h"
#include "test_scenes.h"

namespace clbdpt {
namespace {

// Stride 1 is the film in row order; a stride k > 1 visits one pixel of each k x k block, blocks
// cut at the film's right and bottom edges included, and no pixel twice.
TEST(SparseGrid, OnePixelOfEachBlock) {
    for (int i = 0; i < 37 * 23; ++i) ASSERT_EQ(render_item_pixel(i, 37, 23, 1), i);
    for (int stride : {2, 3, 5, 8}) {
        const int width = 37, height = 23, columns = (width + stride - 1) / stride;
        const int items = render_item_count(width, height, stride);
        ASSERT_EQ(items, columns * ((height + stride - 1) / stride));
        std::set<int> pixels;
        for (int i = 0; i < items; ++i) {
            const int p = render_item_pixel(i, width, height, stride);
            const int x = p % width, y = p / width;
            ASSERT_LT(y, height) << "stride " << stride << " item " << i;
            EXPECT_EQ(x / stride, i % columns) << "stride " << stride << " item " << i;
            EXPECT_EQ(y / stride, i / columns) << "stride " << stride << " item " << i;
            pixels.insert(p);
        }
        EXPECT_EQ(int(pixels.size()), items) << "stride " << stride;
    }
}

// The pixel's place in its block varies from block to block, so the grid does not line up with
// a scene's axis-aligned edges (a light's outline): over a 256 x 256 film at stride 5, every
// column and every row of the blocks is used, each by roughly a fifth of the blocks (within 30%:
// 2 704 blocks, about 540 per offset, a binomial standard deviation of 21).
TEST(SparseGrid, PlaceInTheBlockVaries) {
    const int width = 256, height = 256, stride = 5;
    const int items = render_item_count(width, height, stride);
    int column_count[5] = {}, row_count[5] = {};
    for (int i = 0; i < items; ++i) {
        const int p = render_item_pixel(i, width, height, stride);
        if ((p % width) / stride == width / stride || (p / width) / stride == height / stride) continue;  // cut blocks
        ++column_count[(p % width) % stride];
        ++row_count[(p / width) % stride];
    }
    const int full_blocks = (width / stride) * (height / stride);
    for (int k = 0; k < stride; ++k) {
        EXPECT_NEAR(column_count[k], full_blocks / stride, 0.3 * full_blocks / stride) << "column offset " << k;
        EXPECT_NEAR(row_count[k], full_blocks / stride, 0.3 * full_blocks / stride) << "row offset " << k;
    }
}

// The pilot runs when a grid of at least 1024 pixels (or the whole film) costs at most a tenth
// of the render's samples, at 9 passes per candidate: a 128 x 128 film of 64 spp gets one (a
// coarser grid than a long render's), 4 spp are too few for a 128 x 128 film, and a 32 x 32 film
// (all of it the grid) needs 360 spp.
TEST(SparseGrid, WhichRendersGetAPilot) {
    EXPECT_TRUE(strategy_pilot_fits(256, 256, 64, 4));
    EXPECT_TRUE(strategy_pilot_fits(256, 256, 8, 4));
    EXPECT_TRUE(strategy_pilot_fits(128, 128, 64, 4));
    EXPECT_TRUE(strategy_pilot_fits(32, 32, 360, 4));
    EXPECT_FALSE(strategy_pilot_fits(32, 32, 160, 4));
    EXPECT_FALSE(strategy_pilot_fits(32, 32, 4, 4));
    EXPECT_FALSE(strategy_pilot_fits(128, 128, 4, 4));
    EXPECT_FALSE(strategy_pilot_fits(64, 64, 1, 4));
    EXPECT_FALSE(strategy_pilot_fits(256, 256, 0, 4));
    // A fifth candidate (lt) costs a fifth more: 32x32 x 9 passes x 5 = 46080 samples, more
    // than a tenth of 400 spp (40960), where four candidates' 36864 fit.
    EXPECT_TRUE(strategy_pilot_fits(32, 32, 400, 4));
    EXPECT_FALSE(strategy_pilot_fits(32, 32, 400, 5));
}

// A timed render's grid follows its budget: the full grid (about 3072 pixels) from 10 s on, down
// to 1024 pixels or the whole film for short budgets.
TEST(SparseGrid, TimedPilotGridFollowsTheBudget) {
    EXPECT_EQ(timed_pilot_stride(256, 256, 10.0), 5);
    EXPECT_EQ(timed_pilot_stride(256, 256, 60.0), 5);
    for (double budget : {1.0, 1.5, 3.0, 5.0}) {
        const int items = render_item_count(256, 256, timed_pilot_stride(256, 256, budget));
        EXPECT_GE(items, std::max(1024, int(3072 * budget / 10.0))) << budget;
        EXPECT_LT(items, 3072 * budget / 10.0 * 1.6 + 1024) << budget;
    }
    EXPECT_LT(render_item_count(256, 256, timed_pilot_stride(256, 256, 1.5)),
              render_item_count(256, 256, timed_pilot_stride(256, 256, 10.0)));
    EXPECT_EQ(timed_pilot_stride(128, 128, 1.5), 4);  // 1024 pixels where the whole film was the grid
    EXPECT_EQ(timed_pilot_stride(32, 32, 1.5), 1);    // a film of 1024 pixels: all of it
}

// Every bdpt mix, with or without pt and lt.
CandidateScope scope_with(bool path_tracing, bool light_tracing) {
    CandidateScope scope;
    scope.path_tracing = path_tracing;
    scope.light_tracing = light_tracing;
    return scope;
}

// Light tracing is a candidate where it renders every path and has no tails a sparse pilot
// misses: diffuse materials only, no environment, no medium. Among the bundled scenes that is
// the Cornell box, lamp-ceiling and point-spot; the others have a mirror or glass
// (cornell-specular, cornell-fog), glossy plates (veach-mis), an environment (sky) or media
// (fog-spot, smoke).
TEST(StrategyCandidates, LightTracingOnlyInDiffuseScenes) {
    for (const char* name : {"cornell-box", "lamp-ceiling", "point-spot", "cornell-specular", "cornell-fog", "veach-mis",
                             "sky", "fog-spot", "smoke"}) {
        const std::string n = name;
        const bool expected = n == "cornell-box" || n == "lamp-ceiling" || n == "point-spot";
        const DeviceScene scene = build_device_scene(load_scene(test::scene_path(n)), 16, 16);
        EXPECT_EQ(light_tracing_is_a_candidate(scene), expected) << n;
        // fog-spot's point and spot lights are in its fog (PathTracingWhereItRendersEveryPath).
        const bool with_pt = n != "fog-spot";
        EXPECT_EQ(candidate_scope(scene).path_tracing, with_pt) << n;
        EXPECT_TRUE(candidate_scope(scene).without_inner_connections) << n << ": no delta light meets a mirror";
        const std::vector<StrategyCandidate> c = strategy_candidates(scene);
        ASSERT_EQ(c.size(), 3u + (with_pt ? 1 : 0) + (expected ? 1 : 0)) << n;
        EXPECT_EQ(c.back().integrator, expected ? Integrator::Lt : (with_pt ? Integrator::Pt : Integrator::Bdpt)) << n;
        for (size_t i = 0; i + 1 < c.size(); ++i) EXPECT_NE(c[i].integrator, Integrator::Lt) << n;
    }
}

// A path tracer is a candidate only where it renders every path, with a bounded variance: not
// where a delta light shines on a mirror or glass (the light it brings by way of them is out of
// a path tracer's reach: its image would lack it; bdpt without inner connections misses that
// light where it is seen by way of a mirror or glass, so it is left out too), nor with a point or
// spot light inside a medium (unbounded variance near the light). An area light or an
// environment seen through glass is hit by camera paths, so pt renders it; a delta light with
// only diffuse and glossy surfaces is reached by light samples.
TEST(StrategyCandidates, PathTracingWhereItRendersEveryPath) {
    using namespace test;
    auto room = [](bool with_mirror, bool with_glass) {
        SceneBuilder b;
        RoomMaterials m = room_materials(b);
        room_walls(b, m);
        room_camera(b);
        if (with_mirror) b.quad({-0.9f, 0.2f, 0.9f}, {-0.5f, 0.2f, 0.9f}, {-0.5f, 0.6f, 0.9f}, {-0.9f, 0.6f, 0.9f},
                                b.material(mirror_material({0.9f, 0.9f, 0.9f}), "mirror"));
        if (with_glass) b.sphere({0.5f, 0.3f, 0.4f}, 0.25f, 2, false, b.material(glass_material(1.5f), "glass"));
        return b;
    };
    auto with_light = [](SceneBuilder b, LightDesc::Kind kind) {
        LightDesc l;
        l.kind = kind;
        l.position = {0.2f, 1.8f, 0.1f};
        l.target = {0.2f, 0.0f, 0.1f};
        l.direction = {0.1f, -1.0f, 0.2f};
        l.color = {2, 2, 2};
        if (kind == LightDesc::Kind::Environment) add_environment(b.scene, {1, 1, 1});
        else b.scene.lights.push_back(l);
        return b;
    };
    auto names = [](const DeviceScene& scene) {
        std::string all;
        for (const StrategyCandidate& c : strategy_candidates(scene)) all += c.name + "; ";
        return all;
    };
    const std::string every_mix = "bdpt, 1 light subpath per sample; bdpt, 0.5 light subpaths per sample; "
                                  "bdpt, 1 light subpath per sample, no inner connections; ";
    using K = LightDesc::Kind;
    for (K kind : {K::Point, K::Spot, K::Directional}) {
        const int k = int(kind);
        const DeviceScene diffuse = build_device_scene(with_light(room(false, false), kind).scene, 16, 16);
        EXPECT_FALSE(delta_light_meets_specular(diffuse)) << k;
        EXPECT_EQ(path_tracing_shortfall(diffuse), "") << k;
        EXPECT_EQ(candidates_left_out(diffuse), "") << k;
        EXPECT_EQ(names(diffuse), every_mix + "pt; lt; ") << k << ": diffuse surfaces only";
        // A mirror and a glass material that no triangle uses (an exporter's MTL file often
        // defines such) do not change the candidates.
        SceneBuilder unused = with_light(room(false, false), kind);
        unused.material(mirror_material({0.9f, 0.9f, 0.9f}), "unused_mirror");
        unused.material(glass_material(1.5f), "unused_glass");
        const DeviceScene with_unused = build_device_scene(unused.scene, 16, 16);
        EXPECT_FALSE(delta_light_meets_specular(with_unused)) << k;
        EXPECT_EQ(names(with_unused), every_mix + "pt; lt; ") << k << ": unused mirror and glass materials";
        for (auto [mirror, glass] : {std::pair{true, false}, std::pair{false, true}}) {
            const DeviceScene scene = build_device_scene(with_light(room(mirror, glass), kind).scene, 16, 16);
            EXPECT_TRUE(delta_light_meets_specular(scene)) << k;
            EXPECT_NE(path_tracing_shortfall(scene).find("mirror or glass"), std::string::npos) << k;
            EXPECT_NE(candidates_left_out(scene).find("pt and bdpt without inner connections left out"),
                      std::string::npos)
                << k;
            EXPECT_EQ(names(scene), "bdpt, 1 light subpath per sample; bdpt, 0.5 light subpaths per sample; ") << k;
        }
    }
    // An area light (the room's ceiling light) and an environment: camera paths hit them.
    SceneBuilder area = room(true, true);
    ceiling_light(area, {0, 1.999f, 0.2f}, 0.5f, area.material(diffuse_material({0, 0, 0}, {10, 10, 10}), "lamp"));
    const DeviceScene lamp = build_device_scene(area.scene, 16, 16);
    EXPECT_EQ(path_tracing_shortfall(lamp), "");
    EXPECT_EQ(names(lamp), every_mix + "pt; ");
    const DeviceScene sky = build_device_scene(with_light(room(true, true), K::Environment).scene, 16, 16);
    EXPECT_EQ(path_tracing_shortfall(sky), "");
    EXPECT_EQ(names(sky), every_mix + "pt; ");
    // A point light in fog: every path is there, only pt's variance is unbounded.
    SceneBuilder fog = with_light(room(false, false), K::Point);
    fill_with(fog.scene, add_medium(fog.scene, "fog", {0.01f, 0.01f, 0.01f}, {0.1f, 0.1f, 0.1f}, 0.0f));
    const DeviceScene foggy = build_device_scene(fog.scene, 16, 16);
    EXPECT_FALSE(delta_light_meets_specular(foggy));
    EXPECT_NE(path_tracing_shortfall(foggy).find("inside a medium"), std::string::npos);
    EXPECT_EQ(candidates_left_out(foggy), "pt left out: " + path_tracing_shortfall(foggy));
    EXPECT_EQ(names(foggy), every_mix);
}

// The lead that lets the pilot's candidates at the ends decide alone (kClearLeadMargin): the
// chosen candidate's efficiency over the next best's, and for lt over its rival's transport alone
// too, which lt must beat to be chosen at all.
TEST(StrategyCandidates, ChoiceMarginIsTheLeadOverTheNext) {
    std::vector<StrategyCandidate> c = strategy_candidates(scope_with(true, true));
    for (size_t i = 0; i < c.size(); ++i) c[i].efficiency = c[i].efficiency_transport_only = 100.0 * double(i + 1);
    c[3].efficiency = 1000;  // pt
    EXPECT_DOUBLE_EQ(choice_margin(c, 3), 2.0) << "lt's 500 is the next";
    EXPECT_DOUBLE_EQ(choice_margin(c, 4), 0.5);
    c[4].efficiency = 3000;  // lt
    c[4].efficiency_transport_only = 3000;
    c[3].efficiency_transport_only = 2000;
    EXPECT_DOUBLE_EQ(choice_margin(c, 4), 1.5) << "pt's transport alone, 2000, is lt's bar";
    for (size_t i = 0; i < c.size(); ++i)
        if (i != 4) c[i].efficiency = c[i].efficiency_transport_only = 0;
    EXPECT_TRUE(std::isinf(choice_margin(c, 4)));
}

// Light roulette fixed on the command line (--russian-roulette N) goes with every candidate that
// traces light subpaths, and their names say so; pt's name does not (it traces none).
TEST(StrategyCandidates, CarryTheLightRoulette) {
    std::string all;
    for (const StrategyCandidate& c : strategy_candidates(scope_with(true, true), 3)) {
        EXPECT_EQ(c.roulette_light_from, 3) << c.name;
        all += c.name + "; ";
    }
    EXPECT_EQ(all,
              "bdpt, 1 light subpath per sample, Russian roulette from light bounce 3; "
              "bdpt, 0.5 light subpaths per sample, Russian roulette from light bounce 3; "
              "bdpt, 1 light subpath per sample, no inner connections, Russian roulette from light bounce 3; "
              "pt; lt, Russian roulette from light bounce 3; ");
    for (const StrategyCandidate& c : strategy_candidates(scope_with(true, true)))
        EXPECT_EQ(c.roulette_light_from, kRouletteOff) << c.name;
}

// The highest efficiency wins; light tracing only where it also beats every other candidate's
// efficiency without v_pixel (the most that stratified samples and adaptive sampling might
// credit a camera candidate with).
TEST(StrategyCandidates, LightTracingMustBeatTheOthersTransportAlone) {
    std::vector<StrategyCandidate> c = strategy_candidates(scope_with(true, true));
    auto set = [&](size_t i, double efficiency, double transport_only) {
        c[i].efficiency = efficiency;
        c[i].efficiency_transport_only = transport_only;
    };
    set(0, 300, 310);  // full bdpt
    set(1, 170, 175);
    set(2, 250, 255);
    set(3, 5, 5);  // pt
    set(4, 480, 480);  // lt
    EXPECT_EQ(choose_strategy_candidate(c), 4) << "lamp-ceiling: lt beats bdpt's transport alone";
    EXPECT_EQ(light_tracing_passed_over(c, 4), "");
    set(3, 1400, 4800);  // pt with a large v_pixel
    set(4, 1600, 1600);
    EXPECT_EQ(choose_strategy_candidate(c), 3) << "Cornell box: pt's transport alone beats lt";
    EXPECT_EQ(light_tracing_passed_over(c, 3),
              "lt passed over: its efficiency 1.6e+03 does not beat pt's 4.8e+03 without v_pixel");
    set(3, 1400, 1500);
    EXPECT_EQ(choose_strategy_candidate(c), 4);
    set(4, 1450, 1450);
    EXPECT_EQ(choose_strategy_candidate(c), 3) << "lt above pt's efficiency but below its transport alone";
    EXPECT_NE(light_tracing_passed_over(c, 3), "");
    set(4, 1300, 1300);
    EXPECT_EQ(light_tracing_passed_over(c, 3), "") << "lt below the chosen candidate's own efficiency";
    set(4, 0, 0);
    EXPECT_EQ(choose_strategy_candidate(c), 3);
    std::vector<StrategyCandidate> black = strategy_candidates(scope_with(true, false));
    EXPECT_EQ(choose_strategy_candidate(black), 0) << "a black image: full bdpt";
}

// Adaptive sampling's extra samples are path-traced only for a chosen bdpt mix, without the (1,1)
// strategy, and where pt's efficiency is at least kPathTracedExtrasMinShare of the mix's.
TEST(StrategyCandidates, PathTracedExtraSamplesWherePtIsClose) {
    std::vector<StrategyCandidate> c = strategy_candidates(scope_with(true, false));
    for (size_t i = 0; i < c.size(); ++i) c[i].efficiency = 100;
    c[2].efficiency = 120;  // bdpt without inner connections, chosen
    c[3].efficiency = 0.85 * 120;  // pt (veach-mis, seed 1)
    ASSERT_EQ(c[3].integrator, Integrator::Pt);
    ASSERT_EQ(choose_strategy_candidate(c), 2);
    EXPECT_TRUE(path_traced_extra_samples(c, 2, false));
    EXPECT_FALSE(path_traced_extra_samples(c, 2, true)) << "a thin lens or media: (1,1) carries what pt misses";
    c[3].efficiency = kPathTracedExtrasMinShare * 120;
    EXPECT_TRUE(path_traced_extra_samples(c, 2, false));
    c[3].efficiency = 0.99 * kPathTracedExtrasMinShare * 120;
    EXPECT_FALSE(path_traced_extra_samples(c, 2, false)) << "pt too far behind the mix";
    c[3].efficiency = 200;
    EXPECT_FALSE(path_traced_extra_samples(c, 3, false)) << "pt chosen: its own extra samples";
    std::vector<StrategyCandidate> with_lt = strategy_candidates(scope_with(true, true));
    for (StrategyCandidate& x : with_lt) x.efficiency = 100;
    EXPECT_FALSE(path_traced_extra_samples(with_lt, 4, false)) << "lt chosen: it has no camera image to refine";
    std::vector<StrategyCandidate> without_pt = strategy_candidates(scope_with(false, false));
    for (StrategyCandidate& x : without_pt) x.efficiency = 100;
    EXPECT_FALSE(path_traced_extra_samples(without_pt, 2, false)) << "pt is no candidate: it cannot take them either";
}

// The same large sample in every camera candidate is left out of the prediction; a candidate's
// own large samples, and shared terms below the largest 1% of pixels, stay.
TEST(StrategyCandidates, SharedTailIsWhatEveryCameraCandidateHasAlike) {
    const size_t items = 1000;
    std::vector<double> pt(items), bdpt(items), mix(items);
    for (size_t i = 0; i < items; ++i) pt[i] = bdpt[i] = mix[i] = 0.01 + 1e-5 * double(i % 7);  // alike, small
    pt[10] = 60.0, bdpt[10] = 60.2, mix[10] = 59.9;  // one path, sampled alike by all three
    pt[20] = 24.0, bdpt[20] = 24.0, mix[20] = 24.0;
    pt[30] = 50.0;                                   // pt's own firefly
    pt[40] = 9.0, bdpt[40] = 12.0, mix[40] = 9.0;    // large in all, but not alike (beyond 5%)
    const std::vector<double> shared = shared_tail_terms({&pt, &bdpt, &mix});
    ASSERT_EQ(shared.size(), items);
    EXPECT_DOUBLE_EQ(shared[10], 59.9);
    EXPECT_DOUBLE_EQ(shared[20], 24.0);
    EXPECT_EQ(shared[30], 0.0);
    EXPECT_EQ(shared[40], 0.0);
    // 1% of 1000 pixels: the 10 largest shared terms and those tied with the 10th, here the two
    // fireflies and the largest of the small alike terms (i % 7 == 6, 141 pixels).
    int left_out = 0;
    for (size_t i = 0; i < items; ++i) left_out += shared[i] > 0 ? 1 : 0;
    EXPECT_GE(left_out, 10);
    EXPECT_LE(left_out, int(items / 7) + 2);
    for (size_t i = 0; i < items; ++i) {
        if (i != 10 && i != 20 && shared[i] > 0) {
            EXPECT_GE(shared[i], 0.01 + 6e-5) << i;
        }
    }
    // One camera candidate (pt beside lt): nothing to compare with.
    for (double v : shared_tail_terms({&pt})) EXPECT_EQ(v, 0.0);
    // Nothing alike: nothing left out.
    std::vector<double> other(items, 1.0);
    for (double v : shared_tail_terms({&pt, &other})) EXPECT_EQ(v, 0.0);
}

// A pixel where every camera candidate's term is at least kRarePathFactor times its own mean is
// a rare path that all of them met: left out of each. Where one candidate's term there is
// ordinary (pt's own firefly, which the mixes render smoothly), the pixel stays.
TEST(StrategyCandidates, RareSharedPixelsAreRareInEveryCameraCandidate) {
    const size_t items = 2000;
    std::vector<double> pt(items, 0.01), mix(items, 0.02);
    pt[5] = 300.0, mix[5] = 60.0;   // one rare path, weighted 5x apart: rare in both
    pt[6] = 300.0, mix[6] = 0.5;    // pt's own firefly: the mix's term 2.5x its mean, not 100x
    pt[7] = 0.5, mix[7] = 300.0;    // the mix's own
    // The means: pt (1997 x 0.01 + 600.5) / 2000 = 0.31, the mix 0.20; 100x of them: 31 and 20.
    const std::vector<bool> rare = rare_shared_pixels({&pt, &mix});
    ASSERT_EQ(rare.size(), items);
    EXPECT_TRUE(rare[5]);
    EXPECT_FALSE(rare[6]);
    EXPECT_FALSE(rare[7]);
    size_t count = 0;
    for (bool r : rare) count += r ? 1 : 0;
    EXPECT_EQ(count, 1u);
    // The mix's term at pixel 5 at 0.99 and 1.01 of the factor times its mean (which that term
    // is part of: x = F (rest + x) / n at x = F rest / (n - F)).
    std::vector<double> mix_at = mix;
    double rest = 0;
    for (size_t i = 0; i < items; ++i) rest += i == 5 ? 0.0 : mix[i];
    const double at_factor = kRarePathFactor * rest / (double(items) - kRarePathFactor);
    mix_at[5] = 0.99 * at_factor;
    EXPECT_FALSE(rare_shared_pixels({&pt, &mix_at})[5]);
    mix_at[5] = 1.01 * at_factor;
    EXPECT_TRUE(rare_shared_pixels({&pt, &mix_at})[5]);
    // One camera candidate (pt beside lt): nothing to compare with; a black image: nothing rare.
    for (bool r : rare_shared_pixels({&pt})) EXPECT_FALSE(r);
    std::vector<double> black(items, 0.0);
    for (bool r : rare_shared_pixels({&black, &black})) EXPECT_FALSE(r);
}

TEST(StrategyCandidates, CommonSharedVarianceIsTheLeastTermAtRarePixels) {
    const size_t items = 1000;
    std::vector<double> pt(items, 0.01), mix(items, 0.02);
    std::vector<double> shared_tail(items, 0.0);
    std::vector<bool> rare(items, false);
    shared_tail[3] = 50.0, shared_tail[4] = 20.0;     // terms every candidate has alike
    rare[10] = true, pt[10] = 300.0, mix[10] = 60.0;  // a rare path, weighted apart: 60 is common
    // Per pixel and channel, as the candidates' variances are.
    EXPECT_DOUBLE_EQ(common_shared_variance(shared_tail, rare, {&pt, &mix}), 130.0 / (3.0 * items));
    // Nothing shared, or no camera candidate to share it: nothing.
    EXPECT_EQ(common_shared_variance(std::vector<double>(items, 0.0), std::vector<bool>(items, false), {&pt, &mix}),
              0.0);
    EXPECT_EQ(common_shared_variance(shared_tail, rare, {}), 0.0);
}

}  // namespace
}  // namespace clbdpt
