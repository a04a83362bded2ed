// Grid media (cl/medium.h, null-scattering path integral): closed forms and agreement.
//   - a grid of constant density renders what the homogeneous medium of the same coefficients
//     renders, also when a hot voxel far away raises the majorant fivefold, so most
//     tentative collisions are null (their weights and densities are what is tested);
//   - Beer-Lambert through a slab whose density varies along the ray: the closed form of the
//     trilinear grid's optical depth, for bdpt, pt and lt (delta tracking, ratio tracking);
//     and through a chromatic scene-wide grid across index-matched boundaries;
//   - bdpt = pt = lt on a smoke blob behind an index-matched box, lit by the room's ceiling
//     and by a spot light;
//   - HAS_MEDIUM_GRIDS is compiled only for scenes with a grid.
#include <gtest/gtest.h>

#include <cmath>

#include "render/features.h"
#include "test_scenes.h"

namespace clbdpt::test {
namespace {

// As in media_test.cpp: 4.5 combined standard errors over the 17 values (4 x 4 regions and the
// image) of each comparison, 32 x 32 films.
constexpr double kSigmas = 4.5;
constexpr int kFilm = 32;

// Each of bdpt, pt and lt (seeds seed, seed + 1, seed + 2) matches `expected` in every region:
// the closed-form tests, whose set-up (emitter_behind_slab) makes the rays' slant 6e-4 of the
// path length, under the 1e-3 floor.
void expect_closed_form(const DeviceScene& scene, double expected, uint32_t seed, const std::string& name) {
    for (Integrator integrator : {Integrator::Bdpt, Integrator::Pt, Integrator::Lt}) {
        std::string what = name + " " + integrator_name(integrator);
        RegionStats r = render_regions(scene, integrator, 2, seed + uint32_t(integrator), 32, what);
        expect_matches(r, expected, kSigmas, what, 1e-3);
    }
}

// A medium whose density is `grid` placed in the box [lo, hi].
int add_grid_medium(Scene& scene, const std::string& name, Vec3 sigma_a, Vec3 sigma_s, float g, DensityGrid grid,
                    Vec3 lo, Vec3 hi) {
    place_grid_in_box(grid, lo, hi, 0);
    int medium = add_medium(scene, name, sigma_a, sigma_s, g);
    scene.media.back().density = std::make_shared<DensityGrid>(std::move(grid));
    return medium;
}

DensityGrid grid_of(int nx, int ny, int nz, std::vector<float> values) {
    DensityGrid grid;
    grid.size[0] = nx;
    grid.size[1] = ny;
    grid.size[2] = nz;
    grid.values = std::move(values);
    return grid;
}

// A smooth blob with a hollow and a dense knot, 12^3 voxels: density 0 to about 3.
DensityGrid smoke_blob() {
    const int n = 12;
    std::vector<float> v;
    for (int z = 0; z < n; ++z)
        for (int y = 0; y < n; ++y)
            for (int x = 0; x < n; ++x) {
                float px = (x + 0.5f) / n - 0.5f, py = (y + 0.5f) / n - 0.5f, pz = (z + 0.5f) / n - 0.5f;
                float r2 = px * px + py * py + pz * pz;
                float blob = std::exp(-r2 / 0.06f) * (1.0f + 0.8f * std::sin(9.0f * px + 4.0f * pz));
                float knot = 2.0f * std::exp(-((px - 0.15f) * (px - 0.15f) + py * py + pz * pz) / 0.005f);
                v.push_back(std::max(0.0f, blob) + knot);
            }
    return grid_of(n, n, n, v);
}

// ---- Closed forms and the homogeneous case --------------------------------------------------

// The scattering ball of media_test.cpp (chromatic, forward scattering, optical radius ~3),
// once homogeneous and twice as a grid of density 1 over the ball's box: once with the
// majorant equal to the extinction (nulls only in the two weaker channels), once with one
// voxel of density 5 outside the ball (majorant 5x: four tentative collisions in five null).
TEST(MediumGrids, ConstantGridRendersTheHomogeneousMedium) {
    const Vec3 sigma_a{0.5f, 1.0f, 1.5f}, sigma_s{7.0f, 7.0f, 6.0f};
    const Vec3 center{-0.2f, 0.5f, 0.3f};
    const float radius = 0.4f;
    auto ball_scene = [&](int variant) {
        SceneBuilder b;
        lit_room(b, /*with_block=*/false);
        int cloud;
        const Vec3 lo = center - Vec3(0.5f, 0.5f, 0.5f), hi = center + Vec3(0.5f, 0.5f, 0.5f);
        if (variant == 0) {
            cloud = add_medium(b.scene, "cloud", sigma_a, sigma_s, 0.5f);
        } else if (variant == 1) {
            cloud = add_grid_medium(b.scene, "cloud", sigma_a, sigma_s, 0.5f, grid_of(1, 1, 1, {1.0f}), lo, hi);
        } else {
            // 8 voxels 0.2 wide along x from the box's left face: centres at x = -0.6 .. 0.8.
            // The ball (x <= 0.2) lies where the density is 1; only x > 0.6 feels the hot one.
            std::vector<float> v(8, 1.0f);
            v[7] = 5.0f;
            cloud = add_grid_medium(b.scene, "cloud", sigma_a, sigma_s, 0.5f, grid_of(8, 1, 1, v), lo,
                                    {lo.x + 1.6f, hi.y, hi.z});
        }
        b.sphere(center, radius, 3, /*inward=*/false, b.material(interface_material(cloud), "cloud boundary"));
        return build_device_scene(b.scene, kFilm, kFilm);
    };
    DeviceScene homogeneous = ball_scene(0), constant = ball_scene(1), hot = ball_scene(2);
    ASSERT_EQ(constant.media[0].majorant, 8.0f);
    ASSERT_EQ(hot.media[0].majorant, 40.0f);
    RegionStats reference = render_regions(homogeneous, Integrator::Bdpt, 8, 401, 64, "homogeneous bdpt");
    ASSERT_GT(reference.image_mean, 0.01);
    expect_agree(render_regions(constant, Integrator::Bdpt, 8, 402, 64, "constant grid bdpt"), reference, kSigmas,
                 "constant grid bdpt vs homogeneous");
    expect_agree(render_regions(hot, Integrator::Bdpt, 8, 403, 64, "hot grid bdpt"), reference, kSigmas,
                 "grid with a 5x majorant bdpt vs homogeneous");
    expect_agree(render_regions(hot, Integrator::Pt, 8, 404, 64, "hot grid pt"), reference, kSigmas,
                 "grid with a 5x majorant pt vs homogeneous");
    expect_agree(render_regions(hot, Integrator::Lt, 8, 405, 64, "hot grid lt"), reference, kSigmas,
                 "grid with a 5x majorant lt vs homogeneous");
}

// An emitter seen through a purely absorbing slab z in [1, 1.5] (as BeerLambertThroughAnAbsorbingSlab
// in media_test.cpp) whose density varies along z: 4 voxels 0.125 thick, values 0, 3, 0.5, 1 at
// their centres, linear between centres and constant out to the faces. Its optical depth per
// unit sigma is 0.0625 * 0 + 0.125 * ((0 + 3) + (3 + 0.5) + (0.5 + 1)) / 2 + 0.0625 * 1 = 0.5625,
// so each channel is Le_c exp(-0.5625 sigma_c) (1 + O(3e-4) for the slant of the rays).
TEST(MediumGrids, BeerLambertThroughAVaryingDensity) {
    const Vec3 le{2.0f, 1.0f, 0.5f};
    const Vec3 sigma{0.8f, 2.0f, 3.0f};
    SceneBuilder b;
    int ink = add_grid_medium(b.scene, "ink", sigma, {0, 0, 0}, 0.0f, grid_of(1, 1, 4, {0.0f, 3.0f, 0.5f, 1.0f}),
                              {-1.5f, -1.5f, 1.0f}, {1.5f, 1.5f, 1.5f});
    emitter_behind_slab(b, le, b.material(interface_material(ink), "slab"));
    DeviceScene scene = build_device_scene(b.scene, 16, 16);
    double expected = 0;
    for (int c = 0; c < 3; ++c) expected += le[c] * std::exp(-0.5625 * double(sigma[c])) / 3.0;
    expect_closed_form(scene, expected, 411, "Beer-Lambert through a grid");
}

// The scene-wide medium is a chromatic grid of constant density (the camera sits inside it),
// and an index-matched box with the same grid on both sides lies between the camera and an
// emitter 3 units away: each channel is Le_c exp(-3 sigma_c). The majorant is the blue
// extinction, so every null collision zeroes blue and scales red by 0.73: the walk's channel
// choice keeps that estimator's weights bounded. Caught a ratio-tracking draw reused across
// the box's faces (the transmittance came out 3x too high).
TEST(MediumGrids, ChromaticGridAcrossInterfacesMatchesBeerLambert) {
    const Vec3 le{2.0f, 1.0f, 0.5f};
    const Vec3 sigma{0.8f, 2.0f, 3.0f};
    SceneBuilder b;
    int ink = add_grid_medium(b.scene, "ink", sigma, {0, 0, 0}, 0.0f, grid_of(1, 1, 1, {1.0f}), {-4.5f, -4.5f, -1.0f},
                              {4.5f, 4.5f, 4.5f});
    int slab = b.material(interface_material(ink, ink), "slab");
    emitter_behind_slab(b, le, slab);
    fill_with(b.scene, ink);
    DeviceScene scene = build_device_scene(b.scene, 16, 16);
    ASSERT_EQ(scene.info.camera_medium, ink);
    double expected = 0;
    for (int c = 0; c < 3; ++c) expected += le[c] * std::exp(-3.0 * double(sigma[c])) / 3.0;
    expect_closed_form(scene, expected, 441, "chromatic grid across interfaces");
}

// ---- Agreement ----------------------------------------------------------------------------

void expect_estimators_agree(const DeviceScene& scene, int depth, uint32_t seed, int passes, const std::string& name,
                             double min_mean) {
    RegionStats bdpt = render_regions(scene, Integrator::Bdpt, depth, seed, passes, name + " bdpt");
    ASSERT_GT(bdpt.image_mean, min_mean) << name;
    expect_agree(render_regions(scene, Integrator::Pt, depth, seed + 1, passes, name + " pt"), bdpt, kSigmas,
                 name + " pt vs bdpt");
    expect_agree(render_regions(scene, Integrator::Lt, depth, seed + 2, passes, name + " lt"), bdpt, kSigmas,
                 name + " lt vs bdpt");
}

// A smoke blob (grey extinction up to ~18 per unit, albedo 0.8) inside an index-matched box
// standing in the room, lit by the ceiling.
TEST(MediumGrids, SmokeInTheRoomAllEstimatorsAgree) {
    SceneBuilder b;
    lit_room(b, /*with_block=*/false);
    const Vec3 lo{-0.6f, 0.05f, -0.3f}, hi{0.2f, 0.85f, 0.5f};
    int smoke = add_grid_medium(b.scene, "smoke", {1.2f, 1.2f, 1.5f}, {4.8f, 4.8f, 4.5f}, 0.3f, smoke_blob(), lo, hi);
    b.box(lo, hi, /*inward=*/false, b.material(interface_material(smoke), "smoke box"));
    DeviceScene scene = build_device_scene(b.scene, kFilm, kFilm);
    expect_estimators_agree(scene, 6, 421, 64, "smoke", 0.01);
}

// The same blob lit by a spot light from above, in a room whose air is a thin grid medium
// too (the scene-wide medium: the camera and the light are inside a grid, and every ray
// crosses two grids).
TEST(MediumGrids, SpotLightThroughSmokeInHazeAllEstimatorsAgree) {
    SceneBuilder b;
    RoomMaterials m = room_materials(b);
    room_walls(b, m, /*with_block=*/false);  // the block would stand inside the smoke
    room_camera(b);
    LightDesc spot = spot_light({-0.2f, 1.9f, 0.1f}, {-0.2f, 0.0f, 0.1f}, {4, 4, 4}, 25, 5);
    b.scene.lights.push_back(spot);
    int haze = add_grid_medium(b.scene, "haze", {0.05f, 0.05f, 0.05f}, {0.2f, 0.25f, 0.3f}, 0.0f,
                               grid_of(2, 2, 1, {0.2f, 1.0f, 0.6f, 0.1f}), {-1, 0, -1}, {1, 2, 1});
    fill_with(b.scene, haze);
    const Vec3 lo{-0.6f, 0.05f, -0.3f}, hi{0.2f, 0.85f, 0.5f};
    int smoke = add_grid_medium(b.scene, "smoke", {0.6f, 0.6f, 0.6f}, {2.4f, 2.4f, 2.4f}, 0.5f, smoke_blob(), lo, hi);
    b.box(lo, hi, /*inward=*/false, b.material(interface_material(smoke, haze), "smoke box"));
    DeviceScene scene = build_device_scene(b.scene, kFilm, kFilm);
    ASSERT_EQ(scene.info.camera_medium, haze);
    ASSERT_EQ(scene.lights.back().medium, haze);
    expect_estimators_agree(scene, 5, 431, 64, "spot through smoke in haze", 0.001);
}

TEST(MediumGrids, CompiledOnlyWhereUsed) {
    SceneBuilder b;
    lit_room(b);
    fill_with(b.scene, add_medium(b.scene, "fog", {0.1f, 0.1f, 0.1f}, {0.1f, 0.1f, 0.1f}, 0.0f));
    EXPECT_FALSE(kernel_has_define(b.scene, "HAS_MEDIUM_GRIDS"));
    add_grid_medium(b.scene, "smoke", {0, 0, 0}, {1, 1, 1}, 0.0f, smoke_blob(), {0, 0, 0}, {1, 1, 1});
    EXPECT_TRUE(kernel_has_define(b.scene, "HAS_MEDIUM_GRIDS"));
}

}  // namespace
}  // namespace clbdpt::test
