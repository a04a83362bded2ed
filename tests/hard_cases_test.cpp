// Hard cases: scenes that stress the numerics and the bookkeeping of the BDPT kernels. Each
// must render with no non-finite sample (the renderer throws clbdpt::Error on one, which fails
// the test with its message) and must match an easy twin within stated standard errors:
//   - scene scale: the Cornell box at 1e-4 and 1e4 times its size gives the same image;
//   - light size: a light 1e-6 of the room's size (radiance scaled to keep its power) gives
//     the image of a small light of the same power; a light filling the ceiling gives the
//     image of the same light cut into 512 triangles; bdpt, pt and lt agree on both;
//   - grazing: camera and light rays at 89.9 degrees to a floor match the analytic radiance,
//     and a light seen and shining almost edge-on gives the same image under every integrator;
//   - specular chains: a caustic through a glass sphere seen in a mirror (paths bdpt can only
//     sample with s = 0) comes out the same from bdpt and pt;
//   - degenerate input: zero-area and duplicated triangles change nothing, coincident surfaces
//     stay between their twins, an emitter seen from behind is black, a scene whose only
//     emitter has no area renders black;
//   - long paths: max depth 64 in a closed box of mirrors and diffuse walls;
//   - an emitter that the BVH's spatial splits cut into several references is still one light.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>

#include "test_scenes.h"
#include "util/error.h"

namespace clbdpt::test {
namespace {

// Tolerance for every comparison here: 4.5 combined standard errors, each per-region
// standard error estimated from independent one-sample-per-pixel passes. There are about 30
// comparisons of 17 values (16 regions and the image mean): under a normal model a correct
// renderer fails one with probability ~500 * 6.8e-6 = 3e-3, and the seeds are fixed, so a
// pass stays a pass. Where one side is (nearly) deterministic, a 1e-5 relative floor on the
// standard error covers float rounding (1e-4 for the paired scale comparisons, see there).
constexpr double kSigmas = 4.5;
constexpr int kBlocks = 4;
constexpr int kFilm = 32;
// One depth for most scenes, so scenes with the same features share compiled kernels.
constexpr int kDepth = 5;

RegionStats render(const DeviceScene& scene, Integrator integrator, int depth, uint32_t seed, int passes,
                   const std::string& what) {
    return render_regions(scene, integrator, depth, seed, passes, what, kBlocks);
}

// ---- Scene scale ---------------------------------------------------------------------------

// Radiance is invariant under scaling the whole scene (lengths cancel between areas, solid
// angles and squared distances), so every pixel must stay the same. At 1e-4 the Cornell box is
// 0.055 units wide; at 1e4 its coordinates are ~5e6, where
// a float ULP is 0.5. Densities along a path change by 1e8 per vertex in both cases, which the
// ratio form of the MIS weight must absorb.
class SceneScaleTest : public ::testing::TestWithParam<float> {};

TEST_P(SceneScaleTest, CornellBoxImageDoesNotDependOnScale) {
    const float scale = GetParam();
    Scene base = load_scene(scene_path("cornell-box"));
    Scene scaled = base;
    scale_scene(scaled, scale);
    DeviceScene ref_scene = build_device_scene(base, kFilm, kFilm);
    DeviceScene scaled_scene = build_device_scene(scaled, kFilm, kFilm);
    for (Integrator integrator : {Integrator::Bdpt, Integrator::Pt, Integrator::Lt}) {
        std::string name = integrator_name(integrator);
        // Independent renders (different seeds): the plain claim, same image within noise.
        RegionStats ref = render(ref_scene, integrator, kDepth, 31, 64, name + " scale 1");
        RegionStats st = render(scaled_scene, integrator, kDepth, 32, 64, name + " scaled");
        ASSERT_GT(ref.image_mean, 0.01);
        expect_agree(st, ref, kSigmas, name + " scaled vs scale 1");
        // Paired renders (same seed, pass by pass): the same random numbers trace mostly the
        // same paths at both scales, so the difference is far less noisy than either image and
        // a scale-dependent bias of a fraction of a percent (a light leak through offset ray
        // origins, a density that under- or overflows) stands out.
        try {
            PairedStats paired = render_paired(scaled_scene, ref_scene, make_options(integrator, kDepth, 33),
                                               scaled_passes(64), kBlocks);
            // Floor of 1e-4 relative: float rounding alone leaves systematic differences of
            // 1e-6..1e-5 (measured at 1e4; the ray offsets scale with each point's own error
            // bound, cl/ray.h). Anything above 1e-4 is a scale bug.
            expect_same_paired(paired, kSigmas, name + " scaled vs scale 1 paired", 1e-4);
        } catch (const std::exception& e) {
            ADD_FAILURE() << name << " paired render failed: " << e.what();
        }
    }
}

INSTANTIATE_TEST_SUITE_P(Scales, SceneScaleTest, ::testing::Values(1e-4f, 1e4f),
                         [](const ::testing::TestParamInfo<float>& info) {
                             return info.param < 1 ? std::string("tiny_1e_minus_4") : std::string("huge_1e4");
                         });

// ---- Far from the origin ---------------------------------------------------------------------

// The Cornell box scaled to 0.556 units and moved 1e4 box widths from the origin (to x = 5560,
// where a float ULP is 5e-4, 1/1100 of the box) renders the image it renders at the origin.
// Ray origins must leave a surface by the error bound of the hit point, a few ULPs, and shadow
// rays must stop at the far surface by its own bound: offsets of a fixed fraction of |p|
// (256 ULPs, 0.12 units there: a fifth of the box) or a shadow ray shortened by 1e-4 of its
// length darken or leak. Measured before: 27% darker at 1e4 units.
TEST(HardCases, SmallBoxFarFromTheOriginMatchesItAtTheOrigin) {
    Scene base = load_scene(scene_path("cornell-box"));
    scale_scene(base, 1e-3f);
    Scene far = base;
    translate_scene(far, {5560.0f, 0.0f, 0.0f});
    DeviceScene near_scene = build_device_scene(base, kFilm, kFilm);
    DeviceScene far_scene = build_device_scene(far, kFilm, kFilm);
    for (Integrator integrator : {Integrator::Bdpt, Integrator::Pt, Integrator::Lt}) {
        std::string name = integrator_name(integrator);
        RegionStats ref = render(near_scene, integrator, kDepth, 151, 64, name + " at the origin");
        RegionStats st = render(far_scene, integrator, kDepth, 152, 64, name + " far away");
        ASSERT_GT(ref.image_mean, 0.01);
        expect_agree(st, ref, kSigmas, name + " far vs at the origin");
    }
}

// A 1 x 1 light 100 units above a floor, sealed in a closed box whose bottom face is 0.004 below
// the light (a lamp with a cover): nothing can leave the box, so every integrator renders exactly
// black. A shadow ray shortened by 1e-4 of its length (pbrt-v3's ShadowEpsilon) stops 0.01
// before the light, above the cover: before the far end was bounded by its own error instead,
// pt lit the floor through it.
TEST(HardCases, LightSealedInABoxLeaksNothing) {
    SceneBuilder b;
    int floor = b.material(diffuse_material({0.8f, 0.8f, 0.8f}), "floor");
    int cover = b.material(diffuse_material({0.5f, 0.5f, 0.5f}), "cover");
    int light = b.material(diffuse_material({0, 0, 0}, {50, 50, 50}), "light");
    b.quad({-50, 0, -50}, {-50, 0, 50}, {50, 0, 50}, {50, 0, -50}, floor);  // facing up
    ceiling_light(b, {0, 100, 0}, 1.0f, light);
    b.box({-0.6f, 99.996f, -0.6f}, {0.6f, 100.01f, 0.6f}, /*inward=*/false, cover);
    b.camera({0, 50, -60}, {0, 0, 0}, 60.0f);
    DeviceScene scene = build_device_scene(b.scene, kFilm, kFilm);
    for (Integrator integrator : {Integrator::Bdpt, Integrator::Pt, Integrator::Lt}) {
        Renderer renderer(test_device(), scene, make_options(integrator, kDepth, 161));
        Film film(kFilm, kFilm);
        ASSERT_NO_THROW(renderer.render_passes(film, 0, 16)) << integrator_name(integrator);
        double sum = 0;
        for (float v : film.image()) sum += v;
        EXPECT_EQ(sum, 0.0) << integrator_name(integrator) << ": light leaked out of the sealed box";
        report_stat(std::string("sealed ") + integrator_name(integrator) + " sum", sum, 0, sum == 0.0);
    }
}

// ---- Light size ------------------------------------------------------------------------------

// A square light of side 2e-6 (1e-6 of the room's size) with radiance 6e10 times that of the
// 0.5-wide reference, and a 0.02-wide light of the same power. The irradiance of a small light
// differs from that of a point source of its power by O((side / distance)^2), 4e-4 relative
// for the 0.02 light, far below the noise, so the two images must agree. The tiny light's
// pdf_pos is 2.5e11 and its radiance 7.5e11: products of those must not overflow or cancel.
TEST(HardCases, TinyLightMatchesSmallLightOfTheSamePower) {
    DeviceScene tiny = build_device_scene(room_scene(2e-6f), kFilm, kFilm);
    DeviceScene small = build_device_scene(room_scene(0.02f), kFilm, kFilm);
    RegionStats ref = render(small, Integrator::Bdpt, kDepth, 41, 64, "small bdpt");
    RegionStats bdpt = render(tiny, Integrator::Bdpt, kDepth, 42, 64, "tiny bdpt");
    RegionStats pt = render(tiny, Integrator::Pt, kDepth, 43, 64, "tiny pt");
    RegionStats lt = render(tiny, Integrator::Lt, kDepth, 44, 64, "tiny lt");
    ASSERT_GT(ref.image_mean, 0.01);
    expect_agree(bdpt, ref, kSigmas, "tiny bdpt vs small bdpt");
    expect_agree(pt, bdpt, kSigmas, "tiny pt vs tiny bdpt");
    expect_agree(lt, bdpt, kSigmas, "tiny lt vs tiny bdpt");
}

// The whole ceiling emits (two triangles, 2 x 2 units, that every light subpath starts on and
// the camera sees). The twin is the same ceiling cut into a 16 x 16 grid of 512 emitting
// triangles: light selection and sampling change, the radiance field does not.
Scene ceiling_light_room(int grid) {
    SceneBuilder b;
    RoomMaterials m = room_materials(b);
    int emitter = b.material(diffuse_material({0.73f, 0.73f, 0.73f}, {2.0f, 1.8f, 1.5f}), "ceiling");
    b.box({-1, 0, -1}, {1, 2, 1}, /*inward=*/true, {m.red, m.green, m.white, -1, m.white, m.white});
    // The box's +y face is replaced by the emitting ceiling below (its material -1 is dropped).
    Scene& s = b.scene;
    for (size_t i = 0; i < s.infos.size();) {
        if (s.infos[i].material < 0) {
            s.infos.erase(s.infos.begin() + long(i));
            s.triangles.erase(s.triangles.begin() + long(i));
        } else {
            ++i;
        }
    }
    for (size_t i = 0; i < s.infos.size(); ++i) s.infos[i].source_index = int(i);
    b.box({-0.55f, 0, -0.1f}, {0.0f, 0.6f, 0.45f}, /*inward=*/false, m.white);
    const float step = 2.0f / float(grid);
    for (int i = 0; i < grid; ++i)
        for (int j = 0; j < grid; ++j) {
            float x0 = -1 + step * float(i), z0 = -1 + step * float(j);
            float x1 = i + 1 == grid ? 1.0f : x0 + step, z1 = j + 1 == grid ? 1.0f : z0 + step;
            b.quad({x0, 2, z0}, {x1, 2, z0}, {x1, 2, z1}, {x0, 2, z1}, emitter);  // facing down
        }
    // This camera sees the ceiling: emitters seen directly are part of the test.
    b.camera({0, 1.2f, -0.95f}, {0, 1.1f, 1}, 70.0f);
    return b.scene;
}

TEST(HardCases, CeilingFillingLightMatchesItsTessellation) {
    DeviceScene whole = build_device_scene(ceiling_light_room(1), kFilm, kFilm);
    DeviceScene grid = build_device_scene(ceiling_light_room(16), kFilm, kFilm);
    RegionStats ref = render(grid, Integrator::Bdpt, kDepth, 51, 64, "grid bdpt");
    RegionStats bdpt = render(whole, Integrator::Bdpt, kDepth, 52, 64, "whole bdpt");
    RegionStats pt = render(whole, Integrator::Pt, kDepth, 53, 64, "whole pt");
    RegionStats lt = render(whole, Integrator::Lt, kDepth, 54, 64, "whole lt");
    ASSERT_GT(ref.image_mean, 0.1);
    expect_agree(bdpt, ref, kSigmas, "whole bdpt vs grid bdpt");
    expect_agree(pt, bdpt, kSigmas, "whole pt vs whole bdpt");
    expect_agree(lt, bdpt, kSigmas, "whole lt vs whole bdpt");
}

// An emitter that the BVH's spatial splits cut: a long slanted emitting quad across the room,
// whose box overlaps the small triangles of the walls, seen by the camera. The BVH then
// references it more than once; it must stay one light (one selection probability, the same
// for sampling and for MIS at every copy), and bdpt, pt and lt must agree on the image.
TEST(HardCases, EmitterCutBySpatialSplitsIsOneLight) {
    SceneBuilder b;
    RoomMaterials m = room_materials(b);
    // The room's six faces, each cut into 12 x 12 quads: small triangles all around the beam's
    // box, which a build cannot separate from the beam without cutting it.
    const int n = 12;
    const Vec3 corner[6] = {{-1, 0, -1}, {1, 0, -1}, {-1, 0, -1}, {-1, 2, -1}, {-1, 0, -1}, {-1, 0, 1}};
    const Vec3 u_axis[6] = {{0, 2, 0}, {0, 2, 0}, {2, 0, 0}, {2, 0, 0}, {2, 0, 0}, {2, 0, 0}};
    const Vec3 v_axis[6] = {{0, 0, 2}, {0, 0, 2}, {0, 0, 2}, {0, 0, 2}, {0, 2, 0}, {0, 2, 0}};
    const int face_material[6] = {m.red, m.green, m.white, m.white, m.white, m.white};
    for (int f = 0; f < 6; ++f)
        for (int i = 0; i < n; ++i)
            for (int j = 0; j < n; ++j) {
                auto at = [&](int a, int c) { return corner[f] + u_axis[f] * (float(a) / n) + v_axis[f] * (float(c) / n); };
                b.quad(at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1), face_material[f]);
            }
    int emitter = b.material(diffuse_material({0.5f, 0.5f, 0.5f}, {3.0f, 2.7f, 2.2f}), "beam");
    // Facing down toward the floor, across the room from corner to corner.
    b.triangle({-0.95f, 1.9f, -0.9f}, {0.9f, 1.3f, 0.95f}, {0.95f, 1.35f, 0.85f}, emitter);
    b.triangle({-0.95f, 1.9f, -0.9f}, {0.95f, 1.35f, 0.85f}, {-0.9f, 1.95f, -0.95f}, emitter);
    b.camera({0, 1.0f, -0.95f}, {0, 1.2f, 1}, 75.0f);
    DeviceScene scene = build_device_scene(b.scene, kFilm, kFilm);

    ASSERT_GT(scene.bvh_spatial_splits, 0);
    int emitting_copies = 0;
    for (size_t i = 0; i < scene.triangles.size(); ++i) {
        const int light = scene.infos[i].light;
        ASSERT_EQ(light >= 0, scene.infos[i].material == emitter);
        if (light < 0) continue;
        ++emitting_copies;
        // The light is this very triangle (a copy of it: the same corners bit for bit).
        const Triangle& own = scene.triangles[size_t(scene.lights[size_t(light)].triangle)];
        EXPECT_EQ(std::memcmp(&own, &scene.triangles[i], sizeof(Triangle)), 0);
    }
    EXPECT_EQ(scene.lights.size(), 2u);
    EXPECT_GT(emitting_copies, 2) << "the emitters were not cut: the test would not test the dedupe";

    RegionStats bdpt = render(scene, Integrator::Bdpt, kDepth, 61, 64, "bdpt");
    RegionStats pt = render(scene, Integrator::Pt, kDepth, 62, 64, "pt");
    RegionStats lt = render(scene, Integrator::Lt, kDepth, 63, 64, "lt");
    ASSERT_GT(bdpt.image_mean, 0.02);
    expect_agree(pt, bdpt, kSigmas, "pt vs bdpt");
    expect_agree(lt, bdpt, kSigmas, "lt vs bdpt");
}

// ---- Spot cones ------------------------------------------------------------------------------

// A spot light under the ceiling of the room aimed at the floor, with a cone of 0.018 degrees
// across (half angle 0.009: 1 - cos = 1.2e-8, which a float cosine rounds to 0, so a cone kept
// as a cosine has an infinite density and a falloff of 0/0) and one of 90 degrees (half angle
// 90: a hemisphere), both of the same power. The narrow spot lights a dot of 3e-4 on the
// floor, far below a pixel, whose bounce lights the room. bdpt and lt must agree on both (pt
// too on the wide one), and both must be lit. Before the cone was kept as 1 - cos, the narrow
// spot rendered black.
Scene spot_room(float cone_angle) {
    SceneBuilder b;
    RoomMaterials m = room_materials(b);
    room_walls(b, m);
    LightDesc spot;
    spot.kind = LightDesc::Kind::Spot;
    spot.position = {0.2f, 1.9f, 0.3f};
    spot.target = {0.3f, 0.0f, 0.5f};
    spot.cone_angle = cone_angle;
    spot.cone_delta = 0.5f * cone_angle;
    // Intensity for a power of 3 whatever the cone: power = pi (1 - cos falloff + 1 - cos total) I.
    auto one_minus_cos = [](double degrees) { return 2 * std::pow(std::sin(0.5 * degrees * 3.14159265358979 / 180), 2); };
    const float intensity = float(3.0 / (3.14159265358979 * (one_minus_cos(cone_angle) + one_minus_cos(0.5 * cone_angle))));
    spot.color = {intensity, intensity, intensity};
    b.scene.lights.push_back(spot);
    room_camera(b);
    return b.scene;
}

class SpotConeTest : public ::testing::TestWithParam<float> {};

TEST_P(SpotConeTest, IntegratorsAgree) {
    const float cone = GetParam();
    DeviceScene scene = build_device_scene(spot_room(cone), kFilm, kFilm);
    RegionStats bdpt = render(scene, Integrator::Bdpt, kDepth, 181, 64, "spot bdpt");
    RegionStats lt = render(scene, Integrator::Lt, kDepth, 183, 64, "spot lt");
    ASSERT_GT(bdpt.image_mean, 0.01) << "the spot lights nothing";
    expect_agree(lt, bdpt, kSigmas, "spot lt vs bdpt");
    // pt reaches the narrow spot's light only through camera paths that land in its dot (a
    // chance of ~1e-8 per vertex): it cannot render that scene in any affordable time.
    if (cone < 1) return;
    RegionStats pt = render(scene, Integrator::Pt, kDepth, 182, 64, "spot pt");
    expect_agree(pt, bdpt, kSigmas, "spot pt vs bdpt");
}

INSTANTIATE_TEST_SUITE_P(Cones, SpotConeTest, ::testing::Values(0.009f, 90.0f),
                         [](const ::testing::TestParamInfo<float>& info) {
                             return info.param < 1 ? std::string("narrow_0_018_degrees") : std::string("hemisphere");
                         });

// ---- Light samples of every light group -------------------------------------------------------

// The room lit by two ceiling lights of one material and different sizes (one light group, whose
// sample picks one of its four triangles by power), a point light by a wall and a spot aimed at
// the floor with the edge of its cone in view: 3 light groups, so light samples take one of each
// (NEE_EVERY_LIGHT, cl/lights.h). The light tracer takes no light samples, so pt (light samples
// weighted against emitter hits) and bdpt (weighted against light subpaths too) must agree with
// it: a pick probability that is not the one sampled with biases pt's and bdpt's images (a
// uniform 1/4 for the four triangles put pt up to 12 standard errors off). The MIS weights' own
// use of it cannot bias them while they sum to 1; the brute-force MIS test checks their values.
TEST(HardCases, LightSamplesOfEveryGroupAgreeWithTheLightTracer) {
    SceneBuilder b;
    RoomMaterials m = room_materials(b);
    room_walls(b, m);
    ceiling_light(b, {-0.4f, 1.999f, 0.3f}, 0.5f, m.light);
    ceiling_light(b, {0.5f, 1.999f, -0.2f}, 0.25f, m.light);
    b.scene.lights = {point_light({0.7f, 1.2f, 0.6f}, {1.5f, 1.5f, 1.5f}),
                      spot_light({-0.3f, 1.9f, -0.5f}, {-0.2f, 0.0f, 0.4f}, {4, 3, 2}, 30, 5)};
    room_camera(b);
    ASSERT_TRUE(kernel_has_define(b.scene, "NEE_EVERY_LIGHT"));
    DeviceScene scene = build_device_scene(b.scene, kFilm, kFilm);
    RegionStats lt = render(scene, Integrator::Lt, kDepth, 191, 64, "every light lt");
    RegionStats pt = render(scene, Integrator::Pt, kDepth, 192, 64, "every light pt");
    RegionStats bdpt = render(scene, Integrator::Bdpt, kDepth, 193, 64, "every light bdpt");
    ASSERT_GT(lt.image_mean, 0.01);
    expect_agree(pt, lt, kSigmas, "every light pt vs lt");
    expect_agree(bdpt, lt, kSigmas, "every light bdpt vs lt");
    expect_agree(pt, bdpt, kSigmas, "every light pt vs bdpt");
}

// ---- Grazing geometry ------------------------------------------------------------------------

// A diffuse floor (albedo rho) lit by a directional light travelling 0.1 degrees below the
// horizon and seen by a camera looking 0.1 degrees down (field of view 0.1 degrees): every
// camera ray meets the floor at 89.85-89.95 degrees from its normal and every light ray at
// 89.9. Nothing else is in the scene, so each pixel is exactly rho / pi * E * sin(0.1 deg).
// lt is left out: its light subpaths start on the scene's bounding disk, of which the floor's
// visible strip intercepts ~1e-6, so a few hundred thousand samples see nothing.
TEST(HardCases, GrazingCameraAndLightRaysOnAFloor) {
    const double kDeg = 3.14159265358979323846 / 180.0;
    const float rho = 0.5f, irradiance = 1000.0f;
    const double elevation = 0.1 * kDeg;
    SceneBuilder b;
    int floor = b.material(diffuse_material({rho, rho, rho}), "floor");
    b.quad({-50, 0, -600}, {-50, 0, 1200}, {50, 0, 1200}, {50, 0, -600}, floor);  // facing up
    LightDesc sun;
    sun.kind = LightDesc::Kind::Directional;
    sun.direction = {0, -float(std::sin(elevation)), float(std::cos(elevation))};
    sun.color = {irradiance, irradiance, irradiance};
    b.scene.lights.push_back(sun);
    // Looking 0.1 degrees down from height 1: the view centre meets the floor 573 away and the
    // top edge (0.05 degrees) 1146 away, inside the floor.
    b.camera({0, 1, float(-1.0 / std::tan(elevation))}, {0, 0, 0}, 0.1f);
    DeviceScene scene = build_device_scene(b.scene, kFilm, kFilm);
    const double expected = rho / 3.14159265358979323846 * irradiance * std::sin(elevation);
    RegionStats bdpt = render(scene, Integrator::Bdpt, kDepth, 61, 32, "grazing bdpt");
    RegionStats pt = render(scene, Integrator::Pt, kDepth, 62, 32, "grazing pt");
    // pt is deterministic here (next-event estimation of a delta light at every camera hit);
    // rounding of the float cosine sin(0.1 deg) is ~1e-7 relative, below the 1e-5 floor.
    expect_matches(bdpt, expected, kSigmas, "grazing bdpt vs analytic");
    expect_matches(pt, expected, kSigmas, "grazing pt vs analytic");
}

// A square light hanging near the ceiling, its plane tilted 0.1 degrees from vertical so it
// shines almost edge-on at the floor below it and is seen almost edge-on by the camera (whose
// eye is 0.1 degrees off the light's plane). No analytic answer; bdpt, pt and lt must agree.
TEST(HardCases, AlmostEdgeOnLight) {
    const double kDeg = 3.14159265358979323846 / 180.0;
    SceneBuilder b;
    RoomMaterials m = room_materials(b);
    room_walls(b, m);
    // Plane through (0.3, 1.8, 0.2) with normal (cos t, -sin t, 0), t = 0.1 degrees: facing +x,
    // tipped slightly down. Corners spanned by the in-plane axes u = (sin t, cos t, 0), v = z.
    const float t = float(0.1 * kDeg);
    const Vec3 c{0.3f, 1.8f, 0.2f}, u{std::sin(t), std::cos(t), 0}, v{0, 0, 1};
    const float hu = 0.15f, hv = 0.3f;
    Vec3 p00 = c - u * hu - v * hv, p10 = c + u * hu - v * hv, p11 = c + u * hu + v * hv, p01 = c - u * hu + v * hv;
    // Counter-clockwise seen from +x: normal = cross(p10 - p00, p01 - p00) = cross(u, v) ~ +x.
    b.quad(p00, p10, p11, p01, m.light);
    // The eye 0.1 degrees off the light's plane (on its front side), looking across the room.
    const float d = 1.1f;  // the eye at z = -0.9, inside the room
    const Vec3 eye = c + Vec3{std::cos(t), -std::sin(t), 0} * (d * std::sin(t)) + Vec3{0, 0, -1} * (d * std::cos(t));
    b.camera(eye, {0.1f, 0.8f, 1.0f}, 70.0f);
    DeviceScene scene = build_device_scene(b.scene, kFilm, kFilm);
    RegionStats bdpt = render(scene, Integrator::Bdpt, kDepth, 71, 64, "edge-on bdpt");
    RegionStats pt = render(scene, Integrator::Pt, kDepth, 72, 64, "edge-on pt");
    RegionStats lt = render(scene, Integrator::Lt, kDepth, 73, 64, "edge-on lt");
    ASSERT_GT(bdpt.image_mean, 0.001);
    expect_agree(pt, bdpt, kSigmas, "edge-on pt vs bdpt");
    expect_agree(lt, bdpt, kSigmas, "edge-on lt vs bdpt");
}

// ---- Shading normals -------------------------------------------------------------------------

// A coarse smooth-shaded sphere (12 x 6 segments, exact sphere normals at the corners: up to 15
// degrees between shading and geometric normal) in a white room, lit from the side by a small
// light, so the camera looks at the terminator and indirect light reaches the sphere at grazing
// angles everywhere. Directions exist there that lie above the geometric normal and below the
// shading one: the BSDF must be 0 wherever its density is (else the estimators that sample it
// miss paths that light sampling and connections find), and the ratio MIS must not count a
// strategy that cannot produce a path (a density 0 that is not a delta's). Measured (image
// mean, 128 passes): with pbrt-v3's rules pt and bdpt agreed because both lost the same energy
// (lt +2.2% +- 0.9%); with the MIS fixed alone, pt - bdpt = -1.04% (6.1 standard errors); with
// the BSDF's support fixed too, pt - bdpt +0.01% (0.3 standard errors over 1024 passes),
// lt - pt +0.4% (0.7).
Scene terminator_scene() {
    SceneBuilder b;
    int white = b.material(diffuse_material({0.8f, 0.8f, 0.8f}), "white");
    int light = b.material(diffuse_material({0, 0, 0}, {20, 20, 20}), "light");
    b.box({-2, 0, -2}, {2, 3, 2}, /*inward=*/true, white);
    b.uv_sphere({0, 1, 0}, 0.5f, 12, 6, /*smooth=*/true, white);
    // A 0.4 x 0.4 light near the +x wall at the sphere's height, facing -x.
    const float x = 1.9f, y = 1.0f, z = 0.0f, h = 0.2f;
    b.quad({x, y - h, z - h}, {x, y - h, z + h}, {x, y + h, z + h}, {x, y + h, z - h}, light);
    b.camera({0, 1, -1.3f}, {0, 1, 0}, 40.0f);
    return b.scene;
}

TEST(HardCases, SmoothShadedLowPolySphereTerminator) {
    DeviceScene scene = build_device_scene(terminator_scene(), kFilm, kFilm);
    RegionStats bdpt = render(scene, Integrator::Bdpt, kDepth, 141, 128, "terminator bdpt");
    RegionStats pt = render(scene, Integrator::Pt, kDepth, 142, 128, "terminator pt");
    RegionStats lt = render(scene, Integrator::Lt, kDepth, 143, 128, "terminator lt");
    ASSERT_GT(bdpt.image_mean, 0.01);
    expect_agree(pt, bdpt, kSigmas, "terminator pt vs bdpt");
    expect_agree(lt, bdpt, kSigmas, "terminator lt vs bdpt");
    expect_agree(lt, pt, kSigmas, "terminator lt vs pt");
}

// ---- Specular chains -------------------------------------------------------------------------

// An open box: a light above a glass sphere that focuses it onto a diffuse floor, and a mirror
// wall in which the camera sees the floor and its caustic. Camera -> mirror -> floor -> glass
// -> glass -> light: the mirror makes every camera vertex before the floor specular and the
// glass every light vertex before it, so the floor cannot be joined to either side and only
// s = 0 (the camera subpath finding the light by itself) samples these paths. MIS must give it
// the whole weight, the other strategies nothing (not garbage): bdpt and pt must agree.
Scene caustic_in_mirror_scene() {
    SceneBuilder b;
    int white = b.material(diffuse_material({0.7f, 0.7f, 0.7f}), "white");
    int mirror = b.material(mirror_material({0.9f, 0.9f, 0.9f}), "mirror");
    int glass = b.material(glass_material(1.5f), "glass");
    int light = b.material(diffuse_material({0, 0, 0}, {20, 18, 15}), "light");
    // Floor facing up.
    b.quad({-2, 0, -2}, {-2, 0, 2}, {2, 0, 2}, {2, 0, -2}, white);
    // Mirror wall at z = 1.5 facing -z (counter-clockwise seen from -z).
    b.quad({-2, 0, 1.5f}, {-2, 2.5f, 1.5f}, {2, 2.5f, 1.5f}, {2, 0, 1.5f}, mirror);
    // Back wall at x = -2 facing +x, so light bouncing around has something to land on.
    b.quad({-2, 0, -2}, {-2, 2.5f, -2}, {-2, 2.5f, 2}, {-2, 0, 2}, white);
    b.sphere({0, 0.9f, 0.5f}, 0.4f, 3, /*inward=*/false, glass);
    ceiling_light(b, {0, 2.2f, 0.5f}, 0.3f, light);
    // The camera looks at the mirror from the open side and off to the sphere's side, so it
    // sees the caustic on the floor directly (bottom right) and in the mirror, past the
    // sphere's reflection (left).
    b.camera({1.4f, 1.6f, -1.2f}, {0.1f, 0.35f, 1.5f}, 45.0f);
    return b.scene;
}

TEST(HardCases, CausticSeenInAMirror) {
    DeviceScene scene = build_device_scene(caustic_in_mirror_scene(), kFilm, kFilm);
    RegionStats bdpt = render(scene, Integrator::Bdpt, kDepth, 81, 256, "caustic bdpt");
    RegionStats pt = render(scene, Integrator::Pt, kDepth, 82, 256, "caustic pt");
    ASSERT_GT(bdpt.image_mean, 0.01);
    expect_agree(bdpt, pt, kSigmas, "caustic bdpt vs pt");
}

// ---- Degenerate input ----------------------------------------------------------------------

// The room lit by its ceiling light and by a one-sided panel hanging between the camera and the
// room, its emitting front facing away from the camera (black reflectance, so its back is
// exactly black), covering the right quarter of the image.
struct DegenerateOptions {
    bool zero_area = false;   // collinear and point-like triangles, diffuse and emissive
    bool duplicates = false;  // the floor and the block twice, the same triangles
    int overlay = -1;         // a quad coincident with the floor: -1 none, else its albedo x 10
    float floor_albedo = 0.73f;
};

Scene degenerate_room(const DegenerateOptions& o) {
    SceneBuilder b;
    RoomMaterials m = room_materials(b);
    int floor = b.material(diffuse_material({o.floor_albedo, o.floor_albedo, o.floor_albedo}), "floor");
    b.box({-1, 0, -1}, {1, 2, 1}, /*inward=*/true, {m.red, m.green, floor, m.white, m.white, m.white});
    b.box({-0.55f, 0, -0.1f}, {0.0f, 0.6f, 0.45f}, /*inward=*/false, m.white);
    ceiling_light(b, {0, 1.999f, 0.2f}, 0.5f, m.light);
    int panel = b.material(diffuse_material({0, 0, 0}, {3, 3, 3}), "panel");
    // Plane z = -0.5, x in [-1, -0.1], y in [0.6, 1.4]; counter-clockwise seen from +z.
    b.quad({-1, 0.6f, -0.5f}, {-0.1f, 0.6f, -0.5f}, {-0.1f, 1.4f, -0.5f}, {-1, 1.4f, -0.5f}, panel);
    if (o.zero_area) {
        int glow = b.material(diffuse_material({0.5f, 0.5f, 0.5f}, {50, 50, 50}), "zero-area emitter");
        b.triangle({0.2f, 0.3f, 0.5f}, {0.6f, 0.3f, 0.5f}, {0.4f, 0.3f, 0.5f}, m.white);  // collinear
        b.triangle({0.5f, 1.0f, 0.0f}, {0.5f, 1.0f, 0.0f}, {0.5f, 1.0f, 0.0f}, m.white);  // a point
        b.triangle({-0.3f, 1.5f, 0.6f}, {0.3f, 1.5f, 0.6f}, {0.0f, 1.5f, 0.6f}, glow);     // emissive, collinear
        b.triangle({0.7f, 0.2f, 0.7f}, {0.7f, 0.2f, 0.7f}, {0.7f, 0.2f, 0.7f}, glow);     // emissive point
    }
    if (o.duplicates) {
        const size_t n = b.scene.triangles.size();
        for (size_t i = 0; i < n; ++i) {
            const TriangleInfo info = b.scene.infos[i];
            if (info.material != floor && info.material != m.white) continue;
            const Triangle t = b.scene.triangles[i];
            b.triangle(vec3_of(t.p0), vec3_of(t.p1), vec3_of(t.p2), info.material);
        }
    }
    if (o.overlay >= 0) {
        float a = 0.1f * float(o.overlay);
        int over = b.material(diffuse_material({a, a, a}), "overlay");
        // Coincident with the floor over x in [0, 1], z in [-1, 1] (same plane, facing up).
        b.quad({0, 0, -1}, {0, 0, 1}, {1, 0, 1}, {1, 0, -1}, over);
    }
    b.camera({0, 1, -0.9f}, {0, 1, 1}, 60.0f);
    return b.scene;
}

// Zero-area triangles (never hit, never picked as lights: their power is 0) and exact
// duplicates (hit instead of their twin with the same material) change nothing.
TEST(HardCases, ZeroAreaAndDuplicateTrianglesChangeNothing) {
    DeviceScene clean = build_device_scene(degenerate_room({}), kFilm, kFilm);
    DegenerateOptions o;
    o.zero_area = true;
    o.duplicates = true;
    DeviceScene degenerate = build_device_scene(degenerate_room(o), kFilm, kFilm);
    RegionStats ref = render(clean, Integrator::Bdpt, kDepth, 91, 64, "clean bdpt");
    ASSERT_GT(ref.image_mean, 0.01);
    for (Integrator integrator : {Integrator::Bdpt, Integrator::Pt, Integrator::Lt}) {
        std::string name = integrator_name(integrator);
        RegionStats st = render(degenerate, integrator, kDepth, 92 + uint32_t(integrator), 64, name + " degenerate");
        expect_agree(st, ref, kSigmas, "degenerate " + name + " vs clean bdpt");
    }
}

// A quad coincident with half the floor, albedo 0.1 on a floor of 0.7: which of the two a ray
// hits is up to rounding, so the image is not defined, but every path's contribution lies
// between the one with all floor vertices dark and all bright (both are diffuse, so densities
// agree whichever is hit): the image must lie between the two twins, and be finite.
TEST(HardCases, CoincidentSurfacesStayBetweenTheirTwins) {
    DegenerateOptions o;
    o.floor_albedo = 0.7f;
    o.overlay = 1;
    DeviceScene mixed = build_device_scene(degenerate_room(o), kFilm, kFilm);
    DegenerateOptions dark = o, bright = o;
    dark.floor_albedo = 0.1f;  // the overlay everywhere it is, and the floor too
    bright.overlay = 7;        // the overlay as bright as the floor
    DeviceScene lo_scene = build_device_scene(degenerate_room(dark), kFilm, kFilm);
    DeviceScene hi_scene = build_device_scene(degenerate_room(bright), kFilm, kFilm);
    RegionStats lo = render(lo_scene, Integrator::Bdpt, kDepth, 101, 64, "dark twin");
    RegionStats hi = render(hi_scene, Integrator::Bdpt, kDepth, 102, 64, "bright twin");
    for (Integrator integrator : {Integrator::Bdpt, Integrator::Pt}) {
        std::string name = integrator_name(integrator);
        RegionStats st = render(mixed, integrator, kDepth, 103 + uint32_t(integrator), 64, name + " coincident");
        double worst = 0;
        for (size_t r = 0; r <= st.mean.size(); ++r) {
            bool image = r == st.mean.size();
            double v = image ? st.image_mean : st.mean[r], se = image ? st.image_std_error : st.std_error[r];
            double l = image ? lo.image_mean : lo.mean[r], lse = image ? lo.image_std_error : lo.std_error[r];
            double h = image ? hi.image_mean : hi.mean[r], hse = image ? hi.image_std_error : hi.std_error[r];
            double below = (l - v) / std::sqrt(se * se + lse * lse + 1e-20);
            double above = (v - h) / std::sqrt(se * se + hse * hse + 1e-20);
            double z = std::max({0.0, below, above});
            if (std::isnan(v)) z = INFINITY;
            worst = std::max(worst, z);
            EXPECT_LE(z, kSigmas) << name << (image ? " image" : " region " + std::to_string(r)) << ": " << v
                                  << " not within [" << l << ", " << h << "]";
        }
        report_stat("coincident " + name + " between twins", worst, kSigmas, worst <= kSigmas);
    }
}

// The hanging panel's back faces the camera: one-sided emission and black reflectance make
// those pixels exactly 0 for every integrator (a light-traced splat cannot reach them either,
// the panel hides everything behind it).
TEST(HardCases, EmitterSeenFromBehindIsBlack) {
    DeviceScene scene = build_device_scene(degenerate_room({}), kFilm, kFilm);
    // Screen right is cross(forward, up) = -x, so the panel (x in [-1, -0.1] at distance 0.4)
    // is on the right: its inner edge projects to raster x = (1 + 0.25 / tan 30) * W / 2 =
    // 0.72 W, its top and bottom lie outside the view. The last quarter of the columns see it.
    const int first_column = kFilm - kFilm / 4;
    for (Integrator integrator : {Integrator::Bdpt, Integrator::Pt, Integrator::Lt}) {
        Renderer renderer(test_device(), scene, make_options(integrator, kDepth, 111));
        Film film(kFilm, kFilm);
        ASSERT_NO_THROW(renderer.render_passes(film, 0, 8)) << integrator_name(integrator);
        std::vector<float> image = film.image();
        double behind = 0, elsewhere = 0;
        for (int y = 0; y < kFilm; ++y)
            for (int x = 0; x < kFilm; ++x)
                for (int c = 0; c < 3; ++c) {
                    float v = image[(size_t(y) * kFilm + x) * 3 + c];
                    (x >= first_column ? behind : elsewhere) += v;
                }
        EXPECT_EQ(behind, 0.0) << integrator_name(integrator) << ": the back of a one-sided emitter is not black";
        EXPECT_GT(elsewhere, 0.0) << integrator_name(integrator);
        report_stat(std::string("behind ") + integrator_name(integrator) + " sum", behind, 0, behind == 0.0);
    }
}

// The only emitter is a zero-area triangle: the scene emits nothing. It must render black
// (or be refused with an error that says why) but never produce a non-finite sample.
TEST(HardCases, OnlyEmitterHasZeroAreaRendersBlack) {
    SceneBuilder b;
    RoomMaterials m = room_materials(b);
    room_walls(b, m);
    int glow = b.material(diffuse_material({0.5f, 0.5f, 0.5f}, {50, 50, 50}), "zero-area emitter");
    b.triangle({-0.3f, 1.5f, 0.6f}, {0.3f, 1.5f, 0.6f}, {0.0f, 1.5f, 0.6f}, glow);
    room_camera(b);
    DeviceScene scene = build_device_scene(b.scene, kFilm, kFilm);
    for (Integrator integrator : {Integrator::Bdpt, Integrator::Pt, Integrator::Lt}) {
        try {
            Renderer renderer(test_device(), scene, make_options(integrator, kDepth, 121));
            Film film(kFilm, kFilm);
            renderer.render_passes(film, 0, 4);
            double sum = 0;
            for (float v : film.image()) sum += v;
            EXPECT_EQ(sum, 0.0) << integrator_name(integrator);
            report_stat(std::string("zero-area only ") + integrator_name(integrator) + " sum", sum, 0, sum == 0.0);
        } catch (const Error& e) {
            std::string what = e.what();
            EXPECT_EQ(what.find("non-finite"), std::string::npos) << integrator_name(integrator) << ": " << what;
            report_stat(std::string("zero-area only ") + integrator_name(integrator) + " finite", 0, 0,
                        what.find("non-finite") == std::string::npos);
        }
    }
}

// ---- A bad sample ---------------------------------------------------------------------------

// A non-finite sample (injected at one pixel's sample 0) fails a render by default, so every
// test here fails on one, naming the pixel and the strategy; with drop_non_finite (the command
// line) that sample alone is left out and counted, and the image stays finite.
TEST(HardCases, NonFiniteSampleThrowsOrIsDropped) {
    DeviceScene scene = build_device_scene(room_scene(0.5f), kFilm, kFilm);
    const int pixel = (kFilm / 2) * kFilm + kFilm / 2;
    RenderOptions options = make_options(Integrator::Bdpt, kDepth, 171);
    options.debug_nan_pixel = pixel;
    {
        Renderer renderer(test_device(), scene, options);
        Film film(kFilm, kFilm);
        try {
            renderer.render_passes(film, 0, 2);
            ADD_FAILURE() << "a NaN sample did not fail the render";
        } catch (const Error& e) {
            EXPECT_NE(std::string(e.what()).find("non-finite radiance at pixel (16, 16) sample 0 from strategy s="),
                      std::string::npos)
                << e.what();
        }
    }
    options.drop_non_finite = true;
    Film one_thread_film(kFilm, kFilm);
    // Collected by one host thread (a CPU device's way) and by three (a GPU's): the same.
    for (int threads : {1, 3}) {
        options.collect_threads = threads;
        Renderer renderer(test_device(), scene, options);
        Film film(kFilm, kFilm);
        ASSERT_NO_THROW(renderer.render_passes(film, 0, 2));
        EXPECT_EQ(renderer.stats().dropped_samples, 1u);
        ASSERT_EQ(renderer.stats().first_dropped.size(), 1u);
        const DroppedSample& d = renderer.stats().first_dropped[0];
        EXPECT_EQ(d.x, kFilm / 2);
        EXPECT_EQ(d.y, kFilm / 2);
        EXPECT_EQ(d.sample, 0u);
        EXPECT_GE(d.t, 1);
        EXPECT_GE(d.s, 0);
        for (float v : film.image()) ASSERT_TRUE(std::isfinite(v));
        if (threads == 1) {
            one_thread_film = film;
        } else {
            EXPECT_EQ(film.camera_sum, one_thread_film.camera_sum);
            EXPECT_EQ(film.light_sum, one_thread_film.light_sum);
        }
    }
}

// ---- Long paths ---------------------------------------------------------------------------

// A closed box whose floor, ceiling and back wall are 0.95 mirrors and whose other walls are
// diffuse, lit by a small ceiling light, at max depth 64: subpaths of 65 vertices, light
// bouncing between parallel mirrors, about 2000 connections per bdpt sample. Finite, and bdpt and pt
// agree.
TEST(HardCases, MaxDepth64BetweenMirrors) {
    SceneBuilder b;
    int white = b.material(diffuse_material({0.8f, 0.8f, 0.8f}), "white");
    int red = b.material(diffuse_material({0.7f, 0.2f, 0.15f}), "red");
    int mirror = b.material(mirror_material({0.95f, 0.95f, 0.95f}), "mirror");
    int light = b.material(diffuse_material({0, 0, 0}, {15, 14, 12}), "light");
    b.box({-1, 0, -1}, {1, 2, 1}, /*inward=*/true, {red, white, mirror, mirror, white, mirror});
    ceiling_light(b, {0.3f, 1.99f, 0.2f}, 0.3f, light);
    b.camera({0.2f, 0.9f, -0.95f}, {-0.2f, 1.0f, 1.0f}, 75.0f);
    const int film = 16;
    DeviceScene scene = build_device_scene(b.scene, film, film);
    auto run = [&](Integrator integrator, uint32_t seed) {
        return render_stats_or_fail(scene, make_options(integrator, 64, seed), scaled_passes(24), kBlocks,
                                    std::string("depth 64 ") + integrator_name(integrator));
    };
    RegionStats bdpt = run(Integrator::Bdpt, 131);
    RegionStats pt = run(Integrator::Pt, 132);
    ASSERT_GT(bdpt.image_mean, 0.01);
    expect_agree(pt, bdpt, kSigmas, "depth 64 pt vs bdpt");
}

}  // namespace
}  // namespace clbdpt::test
