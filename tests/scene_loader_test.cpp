// Scene loading: the Cornell box, the MTL -> Material mapping, the JSON scene format, and every
// way a scene or mesh file can be wrong (each must fail with file and line or key).
#include <unistd.h>

#include <cctype>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>

#include <gtest/gtest.h>

#include "scene/scene.h"
#include "util/error.h"

namespace clbdpt {
namespace {

namespace fs = std::filesystem;

const std::string kData = CLBDPT_TEST_DATA_DIR;
const std::string kScenes = CLBDPT_SCENES_DIR;

std::string data(const std::string& name) { return kData + "/" + name; }

// The message load_scene throws for `path`, or "" if it loads.
std::string load_error(const std::string& path) {
    try {
        load_scene(path);
    } catch (const Error& e) {
        return e.what();
    }
    return "";
}

#define EXPECT_CONTAINS(haystack, needle)                                                       \
    EXPECT_NE(std::string(haystack).find(needle), std::string::npos)                            \
        << "expected \"" << (needle) << "\" in \"" << (haystack) << "\""

// A JSON scene written to a fresh folder; meshes are named by absolute path.
class TempScene {
public:
    explicit TempScene(const std::string& json) {
        std::string test = ::testing::UnitTest::GetInstance()->current_test_info()->name();
        for (char& c : test) c = c == '/' ? '_' : c;  // parameterised tests: "Name/3"
        dir_ = fs::temp_directory_path() /
               ("clbdpt_scene_test_" + std::to_string(::getpid()) + "_" + test + "_" + std::to_string(counter_++));
        fs::create_directories(dir_);
        path_ = (dir_ / "scene.json").string();
        std::ofstream(path_) << json;
    }
    ~TempScene() {
        std::error_code ec;
        fs::remove_all(dir_, ec);
    }
    const std::string& path() const { return path_; }

private:
    static inline int counter_ = 0;
    fs::path dir_;
    std::string path_;
};

// An OBJ (and files beside it, e.g. its MTL) written to a fresh folder.
class TempObj {
public:
    explicit TempObj(const std::string& obj, const std::vector<std::pair<std::string, std::string>>& beside = {}) {
        std::string test = ::testing::UnitTest::GetInstance()->current_test_info()->name();
        for (char& c : test) c = c == '/' ? '_' : c;
        dir_ = fs::temp_directory_path() / ("clbdpt_obj_test_" + std::to_string(::getpid()) + "_" + test);
        fs::create_directories(dir_);
        path_ = (dir_ / "model.obj").string();
        std::ofstream(path_) << obj;
        for (const auto& [name, text] : beside) {
            fs::create_directories((dir_ / name).parent_path());
            std::ofstream(dir_ / name) << text;
        }
    }
    ~TempObj() {
        std::error_code ec;
        fs::remove_all(dir_, ec);
    }
    const std::string& path() const { return path_; }

private:
    fs::path dir_;
    std::string path_;
};

std::string quoted_mesh(const std::string& name) { return "\"" + data(name) + "\""; }

int material_index(const Scene& scene, const std::string& name) {
    for (size_t i = 0; i < scene.material_names.size(); ++i) {
        if (scene.material_names[i] == name) return static_cast<int>(i);
    }
    ADD_FAILURE() << "no material named " << name;
    return 0;
}

const Material& material(const Scene& scene, const std::string& name) {
    return scene.materials[static_cast<size_t>(material_index(scene, name))];
}

void expect_rgb(const clbdpt_float4& v, float r, float g, float b, float tolerance = 1e-6f) {
    EXPECT_NEAR(v.s[0], r, tolerance);
    EXPECT_NEAR(v.s[1], g, tolerance);
    EXPECT_NEAR(v.s[2], b, tolerance);
}

void expect_vec(const Vec3& v, float x, float y, float z, float tolerance = 1e-4f) {
    EXPECT_NEAR(v.x, x, tolerance);
    EXPECT_NEAR(v.y, y, tolerance);
    EXPECT_NEAR(v.z, z, tolerance);
}

Vec3 xyz(const clbdpt_float4& v) { return {v.s[0], v.s[1], v.s[2]}; }

bool emissive(const Material& m) { return m.ke.s[0] > 0 || m.ke.s[1] > 0 || m.ke.s[2] > 0; }

// ---- The Cornell box ---------------------------------------------------------------------

TEST(SceneLoader, CornellBox) {
    const Scene scene = load_scene(kScenes + "/cornell-box/cornell-box.json");
    // 5 walls + light + 2 blocks of 5 quads = 16 quads.
    EXPECT_EQ(scene.triangles.size(), 32u);
    EXPECT_EQ(scene.infos.size(), 32u);
    EXPECT_TRUE(scene.normals.empty());
    EXPECT_TRUE(scene.lights.empty());
    EXPECT_TRUE(scene.warnings.empty()) << scene.warnings.front();

    int emissive_materials = 0;
    for (const Material& m : scene.materials) emissive_materials += emissive(m) ? 1 : 0;
    EXPECT_EQ(emissive_materials, 1);
    const Material& light = material(scene, "light");
    expect_rgb(light.ke, 17, 12, 4);
    expect_rgb(light.kd, 0.78f, 0.78f, 0.78f);
    EXPECT_EQ(light.kind, MATERIAL_DIFFUSE);
    expect_rgb(material(scene, "red").kd, 0.63f, 0.065f, 0.05f);
    expect_rgb(material(scene, "green").kd, 0.14f, 0.45f, 0.091f);
    expect_rgb(material(scene, "white").kd, 0.73f, 0.73f, 0.73f);

    // The light's two triangles face down into the room, as the one-sided emitter requires.
    int light_triangles = 0;
    for (size_t i = 0; i < scene.triangles.size(); ++i) {
        const TriangleInfo& info = scene.infos[i];
        EXPECT_EQ(info.source_index, static_cast<int>(i));
        EXPECT_EQ(info.light, -1);
        EXPECT_EQ(info.normals, -1);
        EXPECT_EQ(scene.triangles[i].p0.s[3], 0.0f);
        if (!emissive(scene.materials[static_cast<size_t>(info.material)])) continue;
        ++light_triangles;
        const Triangle& t = scene.triangles[i];
        const Vec3 n = normalize(cross(xyz(t.p1) - xyz(t.p0), xyz(t.p2) - xyz(t.p0)));
        expect_vec(n, 0, -1, 0, 1e-6f);
        EXPECT_NEAR(t.p0.s[1], 548.7f, 1e-3f);
    }
    EXPECT_EQ(light_triangles, 2);

    expect_vec(scene.bounds.lo, 0, 0, 0);
    expect_vec(scene.bounds.hi, 556, 548.8f, 559.2f);

    expect_vec(scene.camera.eye, 278, 273, -800);
    expect_vec(scene.camera.target, 278, 273, 0);
    expect_vec(scene.camera.up, 0, 1, 0);
    EXPECT_FLOAT_EQ(scene.camera.fov_degrees, 39.3f);
    EXPECT_FLOAT_EQ(scene.camera.focus_distance, 800.0f);
    EXPECT_EQ(scene.width, 256);
    EXPECT_EQ(scene.height, 256);
    EXPECT_EQ(scene.render.spp, 64);
    EXPECT_EQ(scene.render.max_depth, 5);
}

// ---- MTL mapping -------------------------------------------------------------------------

class MtlMapping : public ::testing::Test {
protected:
    static void SetUpTestSuite() { scene_ = new Scene(load_scene(data("materials.obj"))); }
    static void TearDownTestSuite() { delete scene_; }
    static const Scene& scene() { return *scene_; }
    static inline Scene* scene_ = nullptr;
};

TEST_F(MtlMapping, FacesFollowTheirMaterials) {
    // One face per material in file order, the first with none: "default".
    const char* expected[] = {"default",   "matte",      "lamp",       "mirror",   "glass",         "glass_no_ni",
                              "glossy_ns", "glossy_pr", "too_bright", "textured", "glowing_mirror"};
    ASSERT_EQ(scene().infos.size(), std::size(expected));
    for (size_t i = 0; i < scene().infos.size(); ++i) {
        EXPECT_EQ(scene().material_names[static_cast<size_t>(scene().infos[i].material)], expected[i]);
    }
    EXPECT_EQ(scene().materials.size(), scene().material_names.size());
}

TEST_F(MtlMapping, DefaultMaterialIsGreyDiffuse) {
    const Material& m = material(scene(), "default");
    EXPECT_EQ(m.kind, MATERIAL_DIFFUSE);
    expect_rgb(m.kd, 0.5f, 0.5f, 0.5f);
    expect_rgb(m.ke, 0, 0, 0);
}

TEST_F(MtlMapping, Diffuse) {
    const Material& m = material(scene(), "matte");
    EXPECT_EQ(m.kind, MATERIAL_DIFFUSE);
    expect_rgb(m.kd, 0.5f, 0.6f, 0.7f);
    expect_rgb(m.ks, 0, 0, 0);
    expect_rgb(m.ke, 0, 0, 0);
}

TEST_F(MtlMapping, Emissive) {
    const Material& m = material(scene(), "lamp");
    EXPECT_EQ(m.kind, MATERIAL_DIFFUSE);
    expect_rgb(m.ke, 10, 8, 6);
    expect_rgb(m.kd, 0.2f, 0.2f, 0.2f);
}

TEST_F(MtlMapping, MirrorIllum5) {
    const Material& m = material(scene(), "mirror");
    EXPECT_EQ(m.kind, MATERIAL_MIRROR);
    expect_rgb(m.ks, 0.9f, 0.8f, 0.7f);
}

TEST_F(MtlMapping, GlassIllum7UsesNi) {
    EXPECT_EQ(material(scene(), "glass").kind, MATERIAL_GLASS);
    EXPECT_FLOAT_EQ(material(scene(), "glass").ior, 1.7f);
    EXPECT_EQ(material(scene(), "glass_no_ni").kind, MATERIAL_GLASS);
    EXPECT_FLOAT_EQ(material(scene(), "glass_no_ni").ior, 1.5f);
}

TEST_F(MtlMapping, GlossyFromNs) {
    const Material& m = material(scene(), "glossy_ns");
    EXPECT_EQ(m.kind, MATERIAL_GLOSSY);
    expect_rgb(m.kd, 0.3f, 0.3f, 0.3f);
    expect_rgb(m.ks, 0.4f, 0.4f, 0.4f);
    EXPECT_NEAR(m.alpha, std::sqrt(2.0f / (98.0f + 2.0f)), 1e-6f);
}

TEST_F(MtlMapping, GlossyFromPr) {
    const Material& m = material(scene(), "glossy_pr");
    EXPECT_EQ(m.kind, MATERIAL_GLOSSY);
    EXPECT_NEAR(m.alpha, 0.25f, 1e-6f);
}

TEST_F(MtlMapping, EnergyRescaledWithWarning) {
    const Material& m = material(scene(), "too_bright");
    EXPECT_EQ(m.kind, MATERIAL_GLOSSY);
    // Red sums to 1.4 and is scaled to 1; green (0.8) and blue (0.4) are left alone.
    expect_rgb(m.kd, 0.8f / 1.4f, 0.5f, 0.2f);
    expect_rgb(m.ks, 0.6f / 1.4f, 0.3f, 0.2f);
    int warnings = 0;
    for (const std::string& w : scene().warnings) {
        if (w.find("Kd + Ks above 1") != std::string::npos) {
            ++warnings;
            EXPECT_CONTAINS(w, "1 material has");
            EXPECT_CONTAINS(w, "energy");
        }
    }
    EXPECT_EQ(warnings, 1);
}

TEST_F(MtlMapping, UnmappableFeaturesWarnOncePerKind) {
    int warnings = 0;
    for (const std::string& w : scene().warnings) {
        if (w.find("ignoring unsupported MTL features") == std::string::npos) continue;
        ++warnings;
        EXPECT_CONTAINS(w, "illum 3 (1 material)");
        EXPECT_CONTAINS(w, "Tf (1 material)");
    }
    EXPECT_EQ(warnings, 1);
    // Its map_Kd names a file that does not exist: one warning, and the plain colour is kept.
    int missing = 0;
    for (const std::string& w : scene().warnings) missing += w.find("1 texture missing or unreadable (first: 'wood.png')") != std::string::npos;
    EXPECT_EQ(missing, 1);
    expect_rgb(material(scene(), "textured").kd, 0.5f, 0.5f, 0.5f);
    EXPECT_EQ(material(scene(), "textured").kd_texture, 0);
    EXPECT_TRUE(scene().textures.empty());
    EXPECT_TRUE(scene().uvs.empty());
    // Only the energy rescale, the unmappable features and the missing texture warn; the scene
    // has a light.
    EXPECT_EQ(scene().warnings.size(), 3u);
}

TEST_F(MtlMapping, EmissiveMirrorStaysEmissive) {
    const Material& m = material(scene(), "glowing_mirror");
    EXPECT_EQ(m.kind, MATERIAL_MIRROR);
    expect_rgb(m.ke, 1, 2, 3);
}

// ---- JSON scenes -------------------------------------------------------------------------

TEST(SceneJson, AllFourLightTypes) {
    const Scene scene = load_scene(data("all_lights.json"));
    ASSERT_EQ(scene.lights.size(), 4u);

    const LightDesc& point = scene.lights[0];
    EXPECT_EQ(point.kind, LightDesc::Kind::Point);
    expect_vec(point.position, 0, 2, 0);
    expect_vec(point.color, 10, 10, 10);

    const LightDesc& spot = scene.lights[1];
    EXPECT_EQ(spot.kind, LightDesc::Kind::Spot);
    expect_vec(spot.position, 0, 3, 0);
    expect_vec(spot.target, 0, 0, 0);
    expect_vec(spot.direction, 0, -1, 0);
    expect_vec(spot.color, 5, 4, 3);
    EXPECT_FLOAT_EQ(spot.cone_angle, 25.0f);
    EXPECT_FLOAT_EQ(spot.cone_delta, 4.0f);

    const LightDesc& sun = scene.lights[2];
    EXPECT_EQ(sun.kind, LightDesc::Kind::Directional);
    expect_vec(sun.direction, 0, -1, 0);
    expect_vec(sun.color, 1, 0.5f, 0.25f);

    const LightDesc& env = scene.lights[3];
    EXPECT_EQ(env.kind, LightDesc::Kind::Environment);
    expect_vec(env.color, 2, 2, 2);
    EXPECT_TRUE(fs::path(env.map_path).is_absolute());
    EXPECT_TRUE(fs::equivalent(env.map_path, data("sky.ppm")));
    EXPECT_EQ(scene.environment_map.width, 2);
    EXPECT_EQ(scene.environment_map.height, 1);
    ASSERT_EQ(scene.environment_map.rgb.size(), 6u);
    EXPECT_FLOAT_EQ(scene.environment_map.rgb[0], 1.0f);
    EXPECT_FLOAT_EQ(scene.environment_map.rgb[1], 0.0f);
    EXPECT_FLOAT_EQ(scene.environment_map.rgb[5], 1.0f);

    expect_vec(scene.camera.eye, 0, 1, -5);
    EXPECT_FLOAT_EQ(scene.camera.fov_degrees, 45.0f);
    EXPECT_FLOAT_EQ(scene.camera.lens_radius, 0.1f);
    EXPECT_NEAR(scene.camera.focus_distance, std::sqrt(26.0f), 1e-5f);  // defaults to |target - eye|
    EXPECT_EQ(scene.width, 320);
    EXPECT_EQ(scene.height, 240);
    EXPECT_EQ(scene.render.spp, 8);
    EXPECT_EQ(scene.render.max_depth, 3);
    EXPECT_EQ(scene.render.seed, 7u);

    // floor.obj: a quad with per-vertex normals and no MTL.
    EXPECT_EQ(scene.triangles.size(), 2u);
    ASSERT_EQ(scene.normals.size(), 2u);
    EXPECT_EQ(scene.infos[1].normals, 1);
    expect_rgb(scene.normals[0].n2, 0, 1, 0);
    EXPECT_EQ(scene.material_names[static_cast<size_t>(scene.infos[0].material)], "default");
    EXPECT_TRUE(scene.warnings.empty());
}

TEST(SceneJson, ConstantEnvironmentNeedsNoMap) {
    TempScene t(R"({"meshes": [)" + quoted_mesh("frame.obj") +
                R"(], "lights": [{"type": "environment", "radiance": [0.5, 0.5, 0.5]}]})");
    const Scene scene = load_scene(t.path());
    ASSERT_EQ(scene.lights.size(), 1u);
    EXPECT_TRUE(scene.lights[0].map_path.empty());
    EXPECT_EQ(scene.environment_map.width, 0);
    EXPECT_TRUE(scene.warnings.empty());
}

TEST(SceneJson, Defaults) {
    const Scene scene = load_scene(data("defaults.json"));
    EXPECT_EQ(scene.width, 256);
    EXPECT_EQ(scene.height, 256);
    EXPECT_EQ(scene.render.spp, 16);
    EXPECT_EQ(scene.render.max_depth, 5);
    EXPECT_EQ(scene.render.seed, 0u);
    // No camera: framed like a bare OBJ.
    const float distance = std::sqrt(14.0f) / std::sin(0.5f * 39.3f * 3.14159265f / 180.0f);
    expect_vec(scene.camera.eye, 0, 0, distance);
    EXPECT_TRUE(scene.camera_is_automatic);
    expect_vec(scene.camera.target, 0, 0, 0);
    EXPECT_NEAR(scene.camera.focus_distance, distance, 1e-4f);
    // No light: a uniform white environment is added, and said so.
    ASSERT_EQ(scene.lights.size(), 1u);
    EXPECT_EQ(scene.lights[0].kind, LightDesc::Kind::Environment);
    expect_vec(scene.lights[0].color, 1, 1, 1);
    ASSERT_EQ(scene.warnings.size(), 1u);
    EXPECT_CONTAINS(scene.warnings[0], "scene has no lights: lit by a uniform white environment of radiance 1");
}

TEST(SceneJson, NoDefaultLightLeavesTheSceneDark) {
    LoadOptions options;
    options.default_light = false;
    const Scene scene = load_scene(data("defaults.json"), options);
    EXPECT_TRUE(scene.lights.empty());
    ASSERT_EQ(scene.warnings.size(), 1u);
    EXPECT_EQ(scene.warnings[0], "scene has no lights: the image will be black");
}

TEST(SceneJson, PartialCameraKeepsFramingForTheRest) {
    TempScene t(R"({"camera": {"fov": 60}, "meshes": [)" + quoted_mesh("frame.obj") + "]}");
    const Scene scene = load_scene(t.path());
    const float distance = std::sqrt(14.0f) / std::sin(0.5f * 60.0f * 3.14159265f / 180.0f);
    expect_vec(scene.camera.eye, 0, 0, distance);
    EXPECT_FLOAT_EQ(scene.camera.fov_degrees, 60.0f);
    EXPECT_TRUE(scene.camera_is_automatic);
}

TEST(SceneJson, UnknownKeyNamesFileAndKeyPath) {
    EXPECT_EQ(load_error(data("unknown_key.json")), data("unknown_key.json") + ": unknown key \"camera.fovy\"");
}

TEST(SceneJson, BadJsonNamesLineAndColumn) {
    // The comma after line 3 is missing: the parser stops at the end of the "render" token
    // (nlohmann's position: the last character it read).
    const std::string message = load_error(data("bad_syntax.json"));
    EXPECT_CONTAINS(message, data("bad_syntax.json") + ":4:10: ");
    EXPECT_CONTAINS(message, "syntax error");
}

struct BadJsonCase {
    const char* json;  // "MESH" is replaced by the absolute path of frame.obj
    const char* expected;
};

void PrintTo(const BadJsonCase& c, std::ostream* os) { *os << c.expected; }

class SceneJsonErrors : public ::testing::TestWithParam<BadJsonCase> {};

TEST_P(SceneJsonErrors, NameTheKey) {
    std::string json = GetParam().json;
    const size_t at = json.find("MESH");
    if (at != std::string::npos) json.replace(at, 4, quoted_mesh("frame.obj"));
    TempScene t(json);
    const std::string message = load_error(t.path());
    EXPECT_CONTAINS(message, t.path() + ": ");
    EXPECT_CONTAINS(message, GetParam().expected);
}

INSTANTIATE_TEST_SUITE_P(
    Cases, SceneJsonErrors,
    ::testing::Values(
        BadJsonCase{R"({"meshes": [MESH], "extra": 1})", R"(unknown key "extra")"},
        BadJsonCase{R"({"meshes": [MESH], "render": {"spp": 4, "samples": 2}})", R"(unknown key "render.samples")"},
        BadJsonCase{R"({"meshes": [MESH], "lights": [{"type": "point", "position": [0,0,0], "intensity": [1,1,1],
                      "radius": 1}]})",
                    R"(unknown key "lights[0].radius")"},
        BadJsonCase{R"({"meshes": [MESH], "film": {"width": "256"}})", R"("film.width" must be an integer)"},
        BadJsonCase{R"({"meshes": [MESH], "film": {"width": -1}})", R"("film.width" must be an integer from 1)"},
        BadJsonCase{R"({"meshes": [MESH], "film": {"height": 12.5}})", R"("film.height")"},
        BadJsonCase{R"({"meshes": [MESH], "render": {"spp": 0}})", R"("render.spp")"},
        BadJsonCase{R"({"meshes": [MESH], "render": {"seed": -3}})", R"("render.seed")"},
        BadJsonCase{R"({"meshes": [MESH], "camera": {"eye": [0, 0]}})", R"("camera.eye" must be an array of 3 numbers)"},
        BadJsonCase{R"({"meshes": [MESH], "camera": {"eye": [0, 0, 1e999]}})", R"("camera.eye[2]" must be finite)"},
        BadJsonCase{R"({"meshes": [MESH], "lights": [{"type": "point", "position": [0,0,0], "intensity": [1,1,1]},
                      {"type": "point", "position": [0,-1e400,0]}]})",
                    R"("lights[1].position[1]" must be finite)"},
        BadJsonCase{R"({"meshes": [MESH], "camera": {"eye": [0, 0, 1e39]}})", R"("camera.eye" must be finite)"},
        BadJsonCase{R"({"meshes": [MESH], "camera": {"fov": 1e300}})", R"("camera.fov" must be finite)"},
        BadJsonCase{R"({"meshes": [MESH], "camera": {"fov": 180}})", R"("camera.fov")"},
        BadJsonCase{R"({"meshes": [MESH], "camera": {"lens_radius": -1}})", R"("camera.lens_radius")"},
        BadJsonCase{R"({"meshes": [MESH], "camera": {"eye": [0,5,0], "target": [0,0,0]}})", R"("camera.up")"},
        BadJsonCase{R"({"meshes": [MESH], "camera": "front"})", R"("camera" must be an object)"},
        BadJsonCase{R"({"meshes": [MESH], "lights": [{"type": "area"}]})", R"("lights[0].type" must be one of)"},
        BadJsonCase{R"({"meshes": [MESH], "lights": [{"position": [0,0,0]}]})", R"("lights[0].type" is missing)"},
        BadJsonCase{R"({"meshes": [MESH], "lights": [{"type": "point", "position": [0,0,0]}]})",
                    R"("lights[0].intensity" is missing)"},
        BadJsonCase{R"({"meshes": [MESH], "lights": [{"type": "point", "position": [0,0,0], "intensity": [1,-1,1]}]})",
                    R"("lights[0].intensity" must not be negative)"},
        BadJsonCase{R"({"meshes": [MESH], "lights": [{"type": "spot", "position": [0,0,0], "target": [0,-1,0],
                      "intensity": [1,1,1], "cone_angle": 10, "cone_delta": 20}]})",
                    R"("lights[0].cone_delta")"},
        BadJsonCase{R"({"meshes": [MESH], "lights": [{"type": "directional", "direction": [0,0,0], "radiance": [1,1,1]}]})",
                    R"("lights[0].direction" must not be zero)"},
        BadJsonCase{R"({"meshes": [MESH], "lights": [{"type": "environment", "radiance": [1,1,1]},
                                                     {"type": "environment", "radiance": [1,1,1]}]})",
                    R"("lights[1]" is a second environment light)"},
        BadJsonCase{R"({"film": {"width": 64}})", R"("meshes" is missing)"},
        BadJsonCase{R"({"meshes": []})", R"("meshes" must name at least one mesh)"},
        BadJsonCase{R"({"meshes": "a.obj"})", R"("meshes" must be an array)"},
        BadJsonCase{R"([1, 2])", "must be a JSON object"}),
    [](const ::testing::TestParamInfo<BadJsonCase>& info) {
        // The case's index and the error it expects, as an identifier.
        std::string name = std::to_string(info.index) + "_";
        for (char c : std::string(info.param.expected).substr(0, 40))
            name += std::isalnum(static_cast<unsigned char>(c)) ? c : '_';
        return name;
    });

TEST(SceneJson, MissingEnvironmentMapNamesIt) {
    TempScene t(R"({"meshes": [)" + quoted_mesh("frame.obj") +
                R"(], "lights": [{"type": "environment", "map": "no_such_sky.exr"}]})");
    EXPECT_CONTAINS(load_error(t.path()), "cannot open '");
    EXPECT_CONTAINS(load_error(t.path()), "no_such_sky.exr' (referenced by " + t.path() + ")");
}

TEST(SceneJson, MeshesConcatenate) {
    TempScene t(R"({"meshes": [)" + quoted_mesh("floor.obj") + ", " + quoted_mesh("materials.obj") + "]}");
    const Scene scene = load_scene(t.path());
    ASSERT_EQ(scene.triangles.size(), 2u + 11u);
    for (size_t i = 0; i < scene.infos.size(); ++i) EXPECT_EQ(scene.infos[i].source_index, static_cast<int>(i));
    // floor.obj's faces and materials.obj's material-less face share one "default" material.
    int defaults = 0;
    for (const std::string& name : scene.material_names) defaults += name == "default" ? 1 : 0;
    EXPECT_EQ(defaults, 1);
    EXPECT_EQ(scene.infos[0].material, scene.infos[2].material);
    EXPECT_EQ(scene.material_names[static_cast<size_t>(scene.infos[3].material)], "matte");
    EXPECT_EQ(scene.material_names[static_cast<size_t>(scene.infos[12].material)], "glowing_mirror");
    EXPECT_EQ(scene.infos[2].normals, -1);
    expect_vec(scene.bounds.lo, -1, 0, -1);
    expect_vec(scene.bounds.hi, 1, 1, 1);
}

// ---- Broken inputs -----------------------------------------------------------------------

TEST(SceneErrors, MissingSceneFile) {
    EXPECT_EQ(load_error(data("no_such_scene.json")), "cannot open '" + data("no_such_scene.json") + "'");
    EXPECT_EQ(load_error(data("no_such_mesh.obj")), "cannot open '" + data("no_such_mesh.obj") + "'");
}

TEST(SceneErrors, UnknownSceneFormat) { EXPECT_CONTAINS(load_error(data("sky.ppm")), "unknown scene format"); }

TEST(SceneErrors, MissingMesh) {
    EXPECT_EQ(load_error(data("missing_mesh.json")),
              "cannot open '" + data("no_such_mesh.obj") + "' (referenced by " + data("missing_mesh.json") + ")");
}

// A download often lacks its MTL: one warning naming it, and the faces render grey.
TEST(SceneQuirks, MissingMtlWarnsAndRendersGrey) {
    const Scene scene = load_scene(data("missing_mtl.obj"));
    ASSERT_EQ(scene.triangles.size(), 1u);
    EXPECT_EQ(scene.material_names[size_t(scene.infos[0].material)], "default");
    int mentions = 0;
    for (const std::string& w : scene.warnings) mentions += w.find("no_such_file.mtl") != std::string::npos;
    EXPECT_EQ(mentions, 1);
    EXPECT_CONTAINS(scene.warnings[0], data("missing_mtl.obj") + ":2: cannot open '" + data("no_such_file.mtl") + "'");
}

TEST(SceneErrors, NanVertexNamesLine) {
    EXPECT_CONTAINS(load_error(data("nan_vertex.obj")), data("nan_vertex.obj") + ":4: ");
    EXPECT_CONTAINS(load_error(data("nan_vertex.obj")), "not finite");
}

TEST(SceneErrors, TruncatedFaceNamesLine) {
    EXPECT_CONTAINS(load_error(data("truncated_face.obj")), data("truncated_face.obj") + ":6: face needs at least 3");
}

TEST(SceneErrors, TruncatedVertexNamesLine) {
    EXPECT_CONTAINS(load_error(data("truncated_vertex.obj")),
                    data("truncated_vertex.obj") + ":5: vertex needs 3 coordinates");
}

TEST(SceneErrors, OutOfRangeFaceNamesLine) {
    EXPECT_CONTAINS(load_error(data("out_of_range.obj")), data("out_of_range.obj") + ":5: vertex index 7 out of range");
}

// Slivers and repeated corners are dropped and counted in one warning line.
TEST(SceneQuirks, ZeroAreaTrianglesAreDroppedAndCounted) {
    const Scene scene = load_scene(data("zero_area.obj"));
    EXPECT_EQ(scene.triangles.size(), 1u);
    int mentions = 0;
    for (const std::string& w : scene.warnings) {
        if (w.find("degenerate") == std::string::npos) continue;
        ++mentions;
        EXPECT_EQ(w, data("zero_area.obj") + ": dropped 1 degenerate triangle (zero area)");
    }
    EXPECT_EQ(mentions, 1);
}

// Windows exporters: backslashes, ".\" prefixes and names whose case differs from the file's,
// in `mtllib` and in texture maps (relative to the MTL's own folder).
TEST(SceneQuirks, WindowsPathsFindTheirFiles) {
    TempObj t("mtllib Materials\\Model.MTL\nv 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 0 1\n"
              "usemtl wood\nf 1/1 2/2 3/3\n",
              {{"materials/model.mtl", "newmtl wood\nKd 1 1 1\nmap_Kd .\\Images\\WOOD.ppm\n"},
               {"materials/images/wood.ppm", "P3\n1 1\n255\n255 128 0\n"}});
    const Scene scene = load_scene(t.path());
    ASSERT_EQ(scene.textures.size(), 1u);
    EXPECT_EQ(scene.materials[size_t(scene.infos[0].material)].kd_texture, 1);
    ASSERT_EQ(scene.uvs.size(), 1u);
    EXPECT_EQ(scene.texels.size(), 1u);
    EXPECT_EQ(scene.texels[0], 255u | 128u << 8 | 0u << 16 | 255u << 24);  // opaque, as stored
    for (const std::string& w : scene.warnings) EXPECT_NE(w.find("no lights"), std::string::npos) << w;
}

// Inline comments after data and `mtllib` names with unescaped spaces, as viewers' test files
// and some exporters write them.
TEST(SceneQuirks, InlineCommentsAndSpacesInMtllibNames) {
    TempObj t("mtllib my materials.mtl missing one.mtl # where the colours are\n"
              "v 0 0 0 # origin\nv 1 0 0\nv 0 1 0\nv 1 1 0\n"
              "usemtl red\nf 1 2 3 # first\nf 2 4 3\n",
              {{"my materials.mtl", "newmtl red\nKd 0.8 0.1 0.1\n"}});
    const Scene scene = load_scene(t.path());
    ASSERT_EQ(scene.triangles.size(), 2u);
    EXPECT_EQ(scene.material_names[size_t(scene.infos[0].material)], "red");
    std::string all;
    for (const std::string& w : scene.warnings) all += w + "\n";
    // "missing one.mtl" is two unknown tokens once "my materials.mtl" is found.
    EXPECT_CONTAINS(all, "cannot open '" + (fs::path(t.path()).parent_path() / "missing").string() + "'");
    EXPECT_CONTAINS(all, "cannot open '" + (fs::path(t.path()).parent_path() / "one.mtl").string() + "'");
    EXPECT_EQ(all.find("where"), std::string::npos) << all;
}

// A file of nothing but degenerate triangles has nothing to render.
TEST(SceneErrors, OnlyDegenerateTrianglesIsAnError) {
    TempObj t("v 0 0 0\nv 1 0 0\nv 2 0 0\nf 1 2 3\nf 1 1 2\n");
    EXPECT_EQ(load_error(t.path()), t.path() + ": no triangles with a non-zero area");
}

// tinyobj's per-material messages ("Both `d` and `Tr`", unknown material names) and unsupported
// keys collapse to one line per kind, however many materials repeat them.
TEST(SceneQuirks, RepeatedWarningsCollapseToOneLineEach) {
    std::string mtl, obj = "mtllib many.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\n";
    for (int i = 0; i < 40; ++i) {
        const std::string name = "m" + std::to_string(i);
        mtl += "newmtl " + name + "\nKd 0.5 0.5 0.5\nd 1\nTr 0\nillum 4\nmap_Ns shine" + std::to_string(i) + ".png\n";
        obj += "usemtl " + name + "\nf 1 2 3\nusemtl absent" + std::to_string(i) + "\nf 1 2 3\n";
    }
    TempObj t(obj, {{"many.mtl", mtl}});
    const Scene scene = load_scene(t.path());
    EXPECT_EQ(scene.triangles.size(), 80u);
    EXPECT_LE(scene.warnings.size(), 4u);
    for (const std::string& w : scene.warnings) EXPECT_EQ(w.find('\n'), std::string::npos) << w;
    std::string all;
    for (const std::string& w : scene.warnings) all += w + "\n";
    EXPECT_CONTAINS(all, "illum 4 (40 materials)");
    EXPECT_CONTAINS(all, "map_Ns (40 materials)");
    EXPECT_CONTAINS(all, "(and 39 more like it)");
}

TEST(SceneErrors, EmptyObj) {
    EXPECT_EQ(load_error(data("empty.obj")), data("empty.obj") + ": no faces (an OBJ scene needs triangles)");
}

TEST(SceneErrors, ErrorsInsideAJsonSceneNameTheMesh) {
    TempScene t(R"({"meshes": [)" + quoted_mesh("out_of_range.obj") + "]}");
    EXPECT_CONTAINS(load_error(t.path()), data("out_of_range.obj") + ":5: vertex index 7 out of range");
}

// ---- Participating media ---------------------------------------------------------------------

// media_box.obj: a closed cube "smoke", an open glass quad "veil", a floor "white", a "lamp".
std::string media_scene(const std::string& extra) {
    return R"({"meshes": [)" + quoted_mesh("media_box.obj") + "]" + (extra.empty() ? "" : ", " + extra) + "}";
}

TEST(SceneMedia, MediaMaterialsAndTheSceneMedium) {
    TempScene t(media_scene(R"("media": {"fog": {"sigma_a": [0.1, 0.2, 0.3], "sigma_s": [1, 2, 3], "g": 0.25},
                                          "smoke": {"sigma_s": [4, 4, 4]}},
                               "medium": "fog",
                               "materials": {"smoke": {"interface": true, "interior": "smoke"}})"));
    const Scene scene = load_scene(t.path());
    ASSERT_EQ(scene.media.size(), 2u);
    EXPECT_EQ(scene.media[0].name, "fog");
    expect_vec(scene.media[0].sigma_a, 0.1f, 0.2f, 0.3f);
    expect_vec(scene.media[0].sigma_s, 1, 2, 3);
    EXPECT_FLOAT_EQ(scene.media[0].g, 0.25f);
    expect_vec(scene.media[1].sigma_a, 0, 0, 0);  // absent coefficients are 0
    EXPECT_FLOAT_EQ(scene.media[1].g, 0.0f);
    EXPECT_EQ(scene.scene_medium, 1);
    const Material& smoke = material(scene, "smoke");
    EXPECT_EQ(smoke.kind, MATERIAL_INTERFACE);
    EXPECT_EQ(smoke.interior_medium, 2);
    EXPECT_EQ(smoke.exterior_medium, 1);  // the scene's medium, by default
    // Both sides of everything else hold the scene's medium: an open glass quad is fine.
    EXPECT_EQ(material(scene, "white").interior_medium, 1);
    EXPECT_EQ(material(scene, "white").exterior_medium, 1);
    EXPECT_EQ(material(scene, "veil").interior_medium, 1);
    EXPECT_EQ(material(scene, "veil").exterior_medium, 1);
}

// A grid written out in the scene file: values x fastest, scaled, placed in its bounds so that
// the voxel centres sit evenly inside them.
TEST(SceneMedia, DensityGridFromTheSceneFile) {
    TempScene t(media_scene(R"("media": {"smoke": {"sigma_s": [1, 1, 1], "density": {
                                   "resolution": [2, 1, 3], "values": [0, 1, 2, 3, 4, 5], "scale": 0.5,
                                   "bounds": [[0, 0.5, 0], [1, 1.5, 1]]}}},
                               "materials": {"smoke": {"interface": true, "interior": "smoke"}})"));
    const Scene scene = load_scene(t.path());
    ASSERT_EQ(scene.media.size(), 1u);
    ASSERT_TRUE(scene.media[0].density);
    const DensityGrid& g = *scene.media[0].density;
    EXPECT_EQ(g.size[0], 2);
    EXPECT_EQ(g.size[1], 1);
    EXPECT_EQ(g.size[2], 3);
    EXPECT_EQ(g.values, (std::vector<float>{0, 0.5f, 1, 1.5f, 2, 2.5f}));
    // Voxel (1, 0, 2) is centred at (0.75, 1.0, 5/6) in scene space.
    const float p[3] = {0.75f, 1.0f, 5.0f / 6.0f}, expected[3] = {1, 0, 2};
    for (int axis = 0; axis < 3; ++axis) {
        const float* row = g.world_to_grid[axis];
        EXPECT_NEAR(row[0] * p[0] + row[1] * p[1] + row[2] * p[2] + row[3], expected[axis], 1e-5f) << axis;
    }
}

TEST(SceneMedia, NoDefaultEnvironmentInAFoggyScene) {
    // Without "lights" and with an emitter the scene needs no default light anyway; a foggy
    // scene whose only light is missing gets none (an environment cannot shine through fog).
    TempScene t(R"({"meshes": [)" + quoted_mesh("frame.obj") +
                R"(], "media": {"fog": {"sigma_s": [1, 1, 1]}}, "medium": "fog"})");
    const Scene scene = load_scene(t.path());
    EXPECT_TRUE(scene.lights.empty());
}

struct BadMediaCase {
    const char* extra;
    const char* expected;
};

void PrintTo(const BadMediaCase& c, std::ostream* os) { *os << c.expected; }

class SceneMediaErrors : public ::testing::TestWithParam<BadMediaCase> {};

TEST_P(SceneMediaErrors, OneClearLine) {
    TempScene t(media_scene(GetParam().extra));
    const std::string message = load_error(t.path());
    EXPECT_CONTAINS(message, t.path() + ": ");
    EXPECT_CONTAINS(message, GetParam().expected);
    EXPECT_EQ(message.find('\n'), std::string::npos) << message;
}

INSTANTIATE_TEST_SUITE_P(
    Cases, SceneMediaErrors,
    ::testing::Values(
        BadMediaCase{R"("media": {"fog": {"sigma_a": [-1, 0, 0]}})", R"("media.fog.sigma_a" must not be negative)"},
        BadMediaCase{R"("media": {"fog": {"sigma_s": [1, 1, 1], "g": 1}})", R"("media.fog.g" must be between -1 and 1)"},
        BadMediaCase{R"("media": {"fog": {"sigma_t": [1, 1, 1]}})", R"(unknown key "media.fog.sigma_t")"},
        BadMediaCase{R"("media": {"fog": [1, 2]})", R"("media.fog" must be an object)"},
        BadMediaCase{R"("medium": "mist")", R"("medium" names no medium of "media" (got "mist"))"},
        BadMediaCase{R"("media": {"fog": {}}, "materials": {"smoke": {"interior": "mist"}})",
                     R"("materials.smoke.interior" names no medium)"},
        BadMediaCase{R"("materials": {"glass": {"interface": true}})", R"("materials.glass" names no material of the meshes)"},
        BadMediaCase{R"("materials": {"smoke": {"interface": "yes"}})", R"("materials.smoke.interface" must be true or false)"},
        BadMediaCase{R"("materials": {"lamp": {"interface": true}})", R"("materials.lamp.interface" cannot be set on an emissive)"},
        BadMediaCase{R"("media": {"ink": {"sigma_a": [1, 1, 1]}}, "materials": {"veil": {"interior": "ink"}})",
                     R"(material "veil" separates two media but its surface is not closed (4 edge(s))"},
        BadMediaCase{R"("media": {"fog": {"sigma_s": [1, 1, 1]}}, "medium": "fog",
                        "lights": [{"type": "environment", "radiance": [1, 1, 1]}])",
                     R"("lights[0]" is infinitely far: it cannot shine through the scene-wide "medium")"},
        BadMediaCase{R"("media": {"s": {"density": {"resolution": [2, 2, 2], "values": [1, 2, 3], "bounds": [[0, 0, 0], [1, 1, 1]]}}})",
                     R"("media.s.density.values" must be an array of 8 numbers (the resolution's product))"},
        BadMediaCase{R"("media": {"s": {"density": {"resolution": [1, 1, 1], "values": [-1], "bounds": [[0, 0, 0], [1, 1, 1]]}}})",
                     R"("media.s.density.values[0]" must be zero or positive)"},
        BadMediaCase{R"("media": {"s": {"density": {"resolution": [1, 1, 0], "values": [], "bounds": [[0, 0, 0], [1, 1, 1]]}}})",
                     R"("media.s.density.resolution" must be an integer from 1 to 1024)"},
        BadMediaCase{R"("media": {"s": {"density": {"resolution": [1, 1, 1], "values": [1]}}})",
                     R"("media.s.density" needs "file", or "resolution", "values" and "bounds")"},
        BadMediaCase{R"("media": {"s": {"density": {"resolution": [1, 1, 1], "values": [1], "bounds": [[0, 0, 0], [1, 0, 1]]}}})",
                     R"("media.s.density.bounds" must have its lowest corner below its highest on every axis)"},
        BadMediaCase{R"("media": {"s": {"density": {"file": "smoke.vdb", "values": [1]}}})",
                     R"("media.s.density" takes either "file" or "resolution" and "values", not both)"},
        BadMediaCase{R"("media": {"s": {"density": {"files": "smoke.vdb"}}})", R"(unknown key "media.s.density.files")"},
        BadMediaCase{R"("media": {"s": {"density": {"file": "no_such_smoke.vdb"}}})", R"(no_such_smoke.vdb: no such file)"}));

// ---- Bare OBJ scenes ---------------------------------------------------------------------

TEST(BareObj, CameraFramesTheBounds) {
    const Scene scene = load_scene(data("frame.obj"));
    expect_vec(scene.bounds.lo, -1, -2, -3);
    expect_vec(scene.bounds.hi, 1, 2, 3);
    // Bounding sphere of radius sqrt(14) fits the 39.3 degree field of view exactly.
    // OBJ's convention: the viewer on the +z side looking toward -z.
    const float distance = std::sqrt(14.0f) / std::sin(0.5f * 39.3f * 3.14159265f / 180.0f);
    expect_vec(scene.camera.eye, 0, 0, distance);
    expect_vec(scene.camera.target, 0, 0, 0);
    expect_vec(scene.camera.up, 0, 1, 0);
    EXPECT_FLOAT_EQ(scene.camera.fov_degrees, 39.3f);
    EXPECT_FLOAT_EQ(scene.camera.lens_radius, 0.0f);
    EXPECT_EQ(scene.width, 256);
    EXPECT_EQ(scene.height, 256);
    ASSERT_EQ(scene.lights.size(), 1u);  // the default white environment
    ASSERT_EQ(scene.warnings.size(), 1u);
    EXPECT_CONTAINS(scene.warnings[0], "scene has no lights: lit by a uniform white environment");
    EXPECT_EQ(scene.path, data("frame.obj"));
}

TEST(BareObj, EmissiveMaterialsAreTheLights) {
    const Scene scene = load_scene(data("materials.obj"));
    EXPECT_TRUE(scene.lights.empty());
    for (const std::string& w : scene.warnings) EXPECT_EQ(w.find("no lights"), std::string::npos) << w;
}

}  // namespace
}  // namespace clbdpt
