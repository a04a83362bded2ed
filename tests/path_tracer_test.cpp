// The path tracer made one vertex at a time (cl/path_tracer.h) gives the image
// of the path tracer made as bdpt makes its strategies, from a stored camera
// subpath (cl/connect.h, cl/mis.h): bit for bit, on every bundled scene (media
// and grids included), on media behind index-matched boundaries and inside glass,
// and on every light kind, from max depth 0 (emitters seen directly) up.
// The generic route's weights are checked against a brute force elsewhere
// (mis_brute_force_test.cpp) and its images against bdpt and lt
// (scene_agreement_test.cpp), so this equality carries those checks over.
// Textured scenes: textures_test.cpp.
#include <gtest/gtest.h>

#include "test_scenes.h"

namespace clbdpt::test {
namespace {

constexpr int kFilm = 24;
constexpr int kPasses = 4;

class PathTracerRoutesOnScene : public ::testing::TestWithParam<const char*> {};

TEST_P(PathTracerRoutesOnScene, SameImageAsFromStoredSubpaths) {
    const DeviceScene scene = build_device_scene(load_scene(scene_path(GetParam())), kFilm, kFilm);
    for (int max_depth : {1, 5})
        expect_pt_routes_agree(scene, max_depth, kPasses,
                               std::string(GetParam()) + " depth " + std::to_string(max_depth));
    // Russian roulette from the second bounce on (cl/russian_roulette.h): both routes end the
    // same paths, from the same draw.
    expect_pt_routes_agree(scene, 5, kPasses, std::string(GetParam()) + " depth 5, roulette from bounce 1", 1);
}

// Glass and mirrors (cornell-specular), glossy plates and lights of four sizes
// (veach-mis), point and spot lights (point-spot), an environment map (sky),
// light arriving indirectly (lamp-ceiling), fog filling a room around the camera
// (cornell-fog; fog-spot with a point and a spot light in it) and a density grid
// behind an index-matched box (smoke).
INSTANTIATE_TEST_SUITE_P(BundledScenes, PathTracerRoutesOnScene,
                         ::testing::Values("cornell-box", "cornell-specular", "lamp-ceiling", "veach-mis", "point-spot",
                                           "sky", "cornell-fog", "fog-spot", "smoke"),
                         [](const ::testing::TestParamInfo<const char*>& info) {
                             std::string name = info.param;
                             for (char& c : name)
                                 if (c == '-') c = '_';
                             return name;
                         });

// Point, spot, directional and environment-map lights at once on a floor that
// fills the view, seen through a thin lens.
TEST(PathTracerRoutes, SameImageWithEveryLightKindAndAThinLens) {
    Scene loaded = load_scene(std::string(CLBDPT_TEST_DATA_DIR) + "/all_lights.json");
    loaded.camera.eye = Vec3(0, 1.5f, -1.0f);
    loaded.camera.target = Vec3(0, 0, 0.2f);
    loaded.camera.focus_distance = 1.8f;
    const DeviceScene scene = build_device_scene(loaded, kFilm, kFilm);
    for (int max_depth : {0, 3})
        expect_pt_routes_agree(scene, max_depth, kPasses, "all lights depth " + std::to_string(max_depth));
}

// A room with a mirror on its back wall (paths that reach the light through a
// delta vertex: weight 1 on s = 0), a glass block and a smooth-shaded coarse
// sphere (shading normals, and directions across its terminator bands that only
// some strategies can make).
TEST(PathTracerRoutes, SameImageThroughDeltaVerticesAndShadingNormals) {
    SceneBuilder b;
    RoomMaterials m = room_materials(b);
    room_walls(b, m, /*with_block=*/false);
    ceiling_light(b, {0, 1.999f, 0.3f}, 0.3f, m.light);
    const int mirror = b.material(mirror_material({0.9f, 0.9f, 0.9f}), "mirror");
    const int glass = b.material(glass_material(1.5f), "glass");
    b.quad({-0.9f, 0.1f, 0.99f}, {-0.9f, 1.2f, 0.99f}, {0.9f, 1.2f, 0.99f}, {0.9f, 0.1f, 0.99f}, mirror);
    b.box({-0.6f, 0.0f, 0.1f}, {-0.2f, 0.5f, 0.5f}, /*inward=*/false, glass);
    b.uv_sphere({0.4f, 0.3f, 0.3f}, 0.3f, 12, 6, /*smooth=*/true, m.white);
    room_camera(b);
    const DeviceScene scene = build_device_scene(b.scene, kFilm, kFilm);
    expect_pt_routes_agree(scene, 8, kPasses, "mirror, glass and a smooth sphere");
}

// Media the camera enters and leaves: a scattering ball behind an index-matched
// boundary (segments that cross boundaries without a vertex), a glass sphere
// with an absorbing, scattering interior (transmittance through glass's medium)
// and a spot light in a vacuum bubble inside fog that fills the room.
TEST(PathTracerRoutes, SameImageThroughMediaBehindBoundariesAndGlass) {
    SceneBuilder b;
    lit_room(b, /*with_block=*/false);
    const int cloud = add_medium(b.scene, "cloud", {0.5f, 1.0f, 1.5f}, {7.0f, 7.0f, 6.0f}, 0.5f);
    b.sphere({-0.5f, 0.5f, 0.3f}, 0.35f, 3, /*inward=*/false, b.material(interface_material(cloud), "cloud boundary"));
    const int tint = add_medium(b.scene, "tint", {0.5f, 2.0f, 3.0f}, {0.5f, 0.5f, 0.5f}, 0.0f);
    Material glass = glass_material(1.5f);
    glass.interior_medium = tint;
    b.sphere({0.45f, 0.4f, 0.2f}, 0.3f, 3, /*inward=*/false, b.material(glass, "tinted glass"));
    const DeviceScene scene = build_device_scene(b.scene, kFilm, kFilm);
    EXPECT_TRUE(scene.warnings.empty()) << scene.warnings.front();
    expect_pt_routes_agree(scene, 8, kPasses, "cloud ball and tinted glass");

    SceneBuilder f;
    RoomMaterials m = room_materials(f);
    room_walls(f, m, /*with_block=*/true);
    room_camera(f);
    ceiling_light(f, {0, 1.999f, 0.3f}, 0.3f, m.light);
    LightDesc spot = spot_light({0.3f, 1.8f, 0.3f}, {0.0f, 0.0f, 0.2f}, {3, 3, 3}, 20, 5);
    f.scene.lights.push_back(spot);
    const int fog = add_medium(f.scene, "fog", {0.1f, 0.1f, 0.1f}, {0.4f, 0.4f, 0.4f}, 0.2f);
    fill_with(f.scene, fog);
    f.sphere(spot.position, 0.1f, 2, /*inward=*/false, f.material(interface_material(0, fog), "bubble"));
    const DeviceScene fogged = build_device_scene(f.scene, kFilm, kFilm);
    ASSERT_EQ(fogged.info.camera_medium, fog);
    expect_pt_routes_agree(fogged, 5, kPasses, "spot in a bubble in fog");
}

}  // namespace
}  // namespace clbdpt::test
