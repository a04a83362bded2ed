// Textures from MTL maps, end to end: OBJ + MTL + image files written to a temporary folder,
// loaded as a user's model would be, rendered on PoCL.
//   - a textured quad seen head-on under the default white environment renders its texture
//     (orientation, sRGB decoding and the MTL's Kd multiplier included);
//   - a cut-out (map_d) lets light through in shadow and connection rays exactly where the
//     geometry would have a hole: the same image as the quad cut in half, for bdpt, pt and lt;
//   - an emitter's map_Ke is seen directly by every strategy, and bdpt, pt and lt agree on
//     the light it casts;
//   - bdpt, pt and lt agree on a normal-mapped floor (the shading-normal correction holds);
//   - an untextured scene's kernel carries no texture code.
#include <gtest/gtest.h>
#include <unistd.h>

#include <OpenImageIO/imageio.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "render/aov.h"
#include "render/features.h"
#include "test_scenes.h"

namespace clbdpt::test {
namespace {

namespace fs = std::filesystem;

// A folder of files for one test, removed afterwards.
class TempFolder {
public:
    TempFolder() {
        dir_ = fs::temp_directory_path() /
               ("clbdpt_textures_" + std::to_string(::getpid()) + "_" + current_test_name());
        fs::create_directories(dir_);
    }
    ~TempFolder() {
        std::error_code ec;
        fs::remove_all(dir_, ec);
    }
    std::string write(const std::string& name, const std::string& text) const {
        std::ofstream((dir_ / name).string()) << text;
        return (dir_ / name).string();
    }
    // 8-bit image, `channels` per texel, row 0 at the top.
    void write_png(const std::string& name, int w, int h, int channels, const std::vector<unsigned char>& texels) const {
        auto out = OIIO::ImageOutput::create((dir_ / name).string());
        ASSERT_TRUE(out);
        OIIO::ImageSpec spec(w, h, channels, OIIO::TypeDesc::UINT8);
        ASSERT_TRUE(out->open((dir_ / name).string(), spec));
        ASSERT_TRUE(out->write_image(OIIO::TypeDesc::UINT8, texels.data()));
        out->close();
    }

private:
    fs::path dir_;
};

float srgb_to_linear(int code) {
    const float c = float(code) / 255.0f;
    return c <= 0.04045f ? c / 12.92f : std::pow((c + 0.055f) / 1.055f, 2.4f);
}

// ---- A textured quad seen head-on -------------------------------------------------------

// 16 x 16, four solid 8 x 8 quadrants (bilinear filtering only blends along the middle).
const int kQuadrantCodes[4][3] = {{200, 30, 30}, {30, 200, 30}, {30, 30, 200}, {128, 128, 128}};  // TL TR BL BR

void write_checker(const TempFolder& folder, const std::string& name) {
    std::vector<unsigned char> texels;
    for (int y = 0; y < 16; ++y)
        for (int x = 0; x < 16; ++x)
            for (int c = 0; c < 3; ++c) texels.push_back((unsigned char)kQuadrantCodes[(y / 8) * 2 + x / 8][c]);
    folder.write_png(name, 16, 16, 3, texels);
}

// The quad [-1,1]^2 at z = 0 facing +z with material `material` of quad.mtl, uv (0,0) at its
// lower left, seen by a 90-degree view from (0, 0, 1) that covers it exactly: image = texture
// (row 0 on top).
DeviceScene head_on_quad(const TempFolder& folder, int film) {
    const std::string obj = folder.write("quad.obj",
                                         "mtllib quad.mtl\nv -1 -1 0\nv 1 -1 0\nv 1 1 0\nv -1 1 0\n"
                                         "vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nusemtl tex\nf 1/1 2/2 3/3 4/4\n");
    Scene scene = load_scene(obj);
    EXPECT_EQ(scene.textures.size(), 1u);
    EXPECT_EQ(scene.uvs.size(), 2u);
    scene.camera.eye = Vec3(0, 0, 1);
    scene.camera.target = Vec3(0, 0, 0);
    scene.camera.fov_degrees = 90.0f;
    return build_device_scene(scene, film, film);
}

// Checks the mean of each channel over an 8 x 8 block of pixels inside each quadrant of a
// 32 x 32 image (clear of the blended middle and of the edges: the texture repeats, so bilinear
// filtering blends an edge texel with the opposite edge's) against scale x the texel, within
// 4.5 standard errors of the pass-to-pass spread (12 comparisons).
void expect_quadrants(const DeviceScene& ds, const RenderOptions& options, const float scale[3], const std::string& what) {
    const int film = 32;
    const int passes = scaled_passes(24);
    Renderer renderer(test_device(), ds, options);
    const int corner[4][2] = {{2, 2}, {22, 2}, {2, 22}, {22, 22}};  // TL TR BL BR (x, y)
    std::vector<double> sum(12, 0.0), sum2(12, 0.0);
    for (int pass = 0; pass < passes; ++pass) {
        Film f(film, film);
        renderer.render_passes(f, uint32_t(pass), 1);
        const std::vector<float> img = f.image();
        for (int q = 0; q < 4; ++q)
            for (int c = 0; c < 3; ++c) {
                double v = 0;
                for (int y = corner[q][1]; y < corner[q][1] + 8; ++y)
                    for (int x = corner[q][0]; x < corner[q][0] + 8; ++x) v += img[(size_t(y) * film + x) * 3 + c];
                v /= 64.0;
                sum[q * 3 + c] += v;
                sum2[q * 3 + c] += v * v;
            }
    }
    for (int q = 0; q < 4; ++q)
        for (int c = 0; c < 3; ++c) {
            const double mean = sum[q * 3 + c] / passes;
            const double var = std::max(0.0, sum2[q * 3 + c] / passes - mean * mean) * passes / (passes - 1);
            const double se = std::sqrt(var / passes) + 1e-6 * mean;
            const double expected = scale[c] * srgb_to_linear(kQuadrantCodes[q][c]);
            EXPECT_NEAR(mean, expected, 4.5 * se) << what << ": quadrant " << q << " channel " << c;
        }
}

bool has_define(const DeviceScene& ds, const std::string& define) {
    const std::vector<std::string> d = kernel_defines(ds, Integrator::Bdpt, 3, false, SamplerKind::Independent);
    return std::find(d.begin(), d.end(), define) != d.end();
}

// A floor seen from above at 45 degrees, as the cut-out, emission and normal-map scenes below
// are built: camera (0, 3.5, 3.5) looking at the origin, 60-degree view, 24 x 24 film.
DeviceScene floor_view(const std::string& obj) {
    Scene scene = load_scene(obj);
    scene.camera.eye = Vec3(0, 3.5f, 3.5f);
    scene.camera.target = Vec3(0, 0, 0);
    scene.camera.fov_degrees = 60.0f;
    return build_device_scene(scene, 24, 24);
}

// bdpt, pt and lt agree region by region and on the image mean within 4.5 combined standard
// errors (16 regions + the mean, 3 pairs); the seeds are fixed.
void expect_integrators_agree(const DeviceScene& ds, uint32_t seed, const std::string& what) {
    const int passes = scaled_passes(48);
    RegionStats bdpt = render_stats_or_fail(ds, make_options(Integrator::Bdpt, 3, seed), passes, 4, "bdpt");
    RegionStats pt = render_stats_or_fail(ds, make_options(Integrator::Pt, 3, seed + 1), passes, 4, "pt");
    RegionStats lt = render_stats_or_fail(ds, make_options(Integrator::Lt, 3, seed + 2), passes, 4, "lt");
    ASSERT_GT(bdpt.image_mean, 0.0);
    expect_agree(bdpt, pt, 4.5, what + ": bdpt vs pt");
    expect_agree(bdpt, lt, 4.5, what + ": bdpt vs lt");
    expect_agree(pt, lt, 4.5, what + ": pt vs lt");
}

// Under the uniform white environment with max depth 1 the exitance of a lone Lambertian quad
// is exactly its reflectance: the pixel's expected value is Kd x the texel.
TEST(Textures, TexturedQuadImageIsItsTexture) {
    TempFolder folder;
    write_checker(folder, "checker.png");
    folder.write("quad.mtl", "newmtl tex\nKd 0.5 1 1\nmap_Kd checker.png\n");
    const DeviceScene ds = head_on_quad(folder, 32);
    EXPECT_TRUE(has_define(ds, "HAS_TEXTURES"));
    const float kd[3] = {0.5f, 1.0f, 1.0f};
    expect_quadrants(ds, make_options(Integrator::Pt, 1, 7), kd, "pt");
}

// The albedo AOV shows the texture too (a deterministic first-hit lookup: the centre pixel of
// each quadrant is Kd x its texel to float rounding).
TEST(Textures, AlbedoAovShowsTheTexture) {
    TempFolder folder;
    write_checker(folder, "checker.png");
    folder.write("quad.mtl", "newmtl tex\nKd 0.5 1 1\nmap_Kd checker.png\n");
    const DeviceScene ds = head_on_quad(folder, 32);
    const std::vector<float> albedo = render_aov(test_device(), ds, parse_aov("albedo"));
    const float kd[3] = {0.5f, 1.0f, 1.0f};
    const int centre[4][2] = {{8, 8}, {24, 8}, {8, 24}, {24, 24}};  // TL TR BL BR (x, y)
    for (int q = 0; q < 4; ++q)
        for (int c = 0; c < 3; ++c)
            EXPECT_NEAR(albedo[(size_t(centre[q][1]) * 32 + size_t(centre[q][0])) * 3 + size_t(c)],
                        kd[c] * srgb_to_linear(kQuadrantCodes[q][c]), 1e-5f)
                << "quadrant " << q << " channel " << c;
}

// An emitter with map_Ke seen directly shows Ke x the texel, whichever strategy finds it: the
// camera ray hitting it (pt: s = 0), a point sampled on it joined to the lens (lt: (1,1)), or
// both under MIS (bdpt).
TEST(Textures, EmissionMapIsSeenByEveryStrategy) {
    TempFolder folder;
    write_checker(folder, "checker.png");
    folder.write("quad.mtl", "newmtl tex\nKd 0 0 0\nKe 2 4 4\nmap_Ke checker.png\n");
    const DeviceScene ds = head_on_quad(folder, 32);
    EXPECT_TRUE(has_define(ds, "HAS_EMISSION_TEXTURES"));
    const float ke[3] = {2.0f, 4.0f, 4.0f};
    uint32_t seed = 31;
    for (Integrator integrator : {Integrator::Bdpt, Integrator::Pt, Integrator::Lt})
        expect_quadrants(ds, make_options(integrator, 0, seed++), ke, integrator_name(integrator));
}

// ---- Cut-outs ---------------------------------------------------------------------------

// A floor lit by a small ceiling light through a horizontal blocker. The blocker is either the
// whole quad with map_d cutting away its left half, or just its right half as geometry: every
// integrator must render the same image for both (shadow rays, connections, lt's splats and
// camera rays all see the same hole).
std::string cutout_obj(const TempFolder& folder, bool cutout) {
    std::string obj =
        "mtllib room.mtl\n"
        "v -2 0 -2\nv 2 0 -2\nv 2 0 2\nv -2 0 2\n"            // floor 1-4, facing +y
        "v -0.2 2 -0.2\nv 0.2 2 -0.2\nv 0.2 2 0.2\nv -0.2 2 0.2\n"  // light 5-8, facing -y
        "v -1 1 -1\nv 1 1 -1\nv 1 1 1\nv -1 1 1\nv 0 1 -1\nv 0 1 1\n"  // blocker 9-12, middle 13-14
        "vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nvt 0.5 0\nvt 0.5 1\n"
        "usemtl floor\nf 1 4 3 2\n"
        "usemtl light\nf 5 6 7 8\n";
    if (cutout) obj += "usemtl leaf\nf 9/1 12/4 11/3 10/2\n";
    else obj += "usemtl floor\nf 13/5 14/6 11/3 10/2\n";
    return folder.write(cutout ? "cut.obj" : "half.obj", obj);
}

TEST(Textures, CutoutsLetLightThroughInEveryRayQuery) {
    TempFolder folder;
    // Grey mask, 8 x 2: the left half (u < 0.5) is a hole.
    std::vector<unsigned char> mask;
    for (int y = 0; y < 2; ++y)
        for (int x = 0; x < 8; ++x) mask.push_back(x < 4 ? 0 : 255);
    folder.write_png("mask.png", 8, 2, 1, mask);
    folder.write("room.mtl",
                 "newmtl floor\nKd 0.7 0.7 0.7\n"
                 "newmtl light\nKd 0 0 0\nKe 20 20 20\n"
                 "newmtl leaf\nKd 0.7 0.7 0.7\nmap_d -clamp on mask.png\n");
    const DeviceScene a = floor_view(cutout_obj(folder, true));
    const DeviceScene b = floor_view(cutout_obj(folder, false));
    ASSERT_EQ(a.textures.size(), 1u);
    EXPECT_TRUE(has_define(a, "HAS_CUTOUTS"));
    expect_pt_routes_agree(a, 3, 4, "cut-out");

    // Tolerance: 16 regions + the image mean per integrator, 4.5 combined standard errors.
    const int passes = scaled_passes(48);
    const Integrator integrators[] = {Integrator::Bdpt, Integrator::Pt, Integrator::Lt};
    uint32_t seed = 11;
    for (Integrator integrator : integrators) {
        const std::string name = integrator_name(integrator);
        RegionStats sa = render_stats_or_fail(a, make_options(integrator, 3, seed++), passes, 4, name + " cut-out");
        RegionStats sb = render_stats_or_fail(b, make_options(integrator, 3, seed++), passes, 4, name + " half quad");
        ASSERT_GT(sb.image_mean, 0.0);
        expect_agree(sa, sb, 4.5, name + ": cut-out vs geometry with the same hole");
    }
}

// A floor lit from above by an emitter whose map_Ke is the checker: light sampling (pt's s = 1),
// emitted rays (lt, bdpt's light subpaths) and emitter hits must weigh the texture alike.
TEST(Textures, BdptPtLtAgreeUnderATexturedEmitter) {
    TempFolder folder;
    write_checker(folder, "checker.png");
    folder.write("room.mtl", "newmtl floor\nKd 0.7 0.7 0.7\nnewmtl light\nKd 0 0 0\nKe 8 8 8\nmap_Ke checker.png\n");
    const std::string obj = folder.write(
        "floor.obj",
        "mtllib room.mtl\nv -2 0 -2\nv 2 0 -2\nv 2 0 2\nv -2 0 2\n"
        "v -0.5 1.5 -0.5\nv 0.5 1.5 -0.5\nv 0.5 1.5 0.5\nv -0.5 1.5 0.5\n"
        "vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\n"
        "usemtl floor\nf 1 4 3 2\nusemtl light\nf 5/1 6/2 7/3 8/4\n");
    const DeviceScene ds = floor_view(obj);
    EXPECT_TRUE(has_define(ds, "HAS_EMISSION_TEXTURES"));
    expect_integrators_agree(ds, 41, "emission map");
    expect_pt_routes_agree(ds, 3, 4, "emission map");
}

// ---- Normal maps ------------------------------------------------------------------------

// A floor whose normal map tilts its shading normal by +-30 degrees in stripes, under a ceiling
// light: bdpt, pt and lt must agree (light subpaths use the adjoint correction with the
// perturbed normal, camera subpaths the plain BSDF).
TEST(Textures, BdptPtLtAgreeOnANormalMappedFloor) {
    TempFolder folder;
    std::vector<unsigned char> normals;
    const float s = std::sin(0.5236f), c = std::cos(0.5236f);
    for (int y = 0; y < 4; ++y)
        for (int x = 0; x < 8; ++x) {
            const float nx = (x / 2) % 2 ? s : -s;
            normals.push_back((unsigned char)std::lround((nx * 0.5f + 0.5f) * 255.0f));
            normals.push_back(128);
            normals.push_back((unsigned char)std::lround((c * 0.5f + 0.5f) * 255.0f));
        }
    folder.write_png("normals.png", 8, 4, 3, normals);
    folder.write("room.mtl",
                 "newmtl floor\nKd 0.7 0.7 0.7\nnorm normals.png\n"
                 "newmtl light\nKd 0 0 0\nKe 20 20 20\n");
    const std::string obj = folder.write(
        "floor.obj",
        "mtllib room.mtl\nv -2 0 -2\nv 2 0 -2\nv 2 0 2\nv -2 0 2\n"
        "v -0.2 2 -0.2\nv 0.2 2 -0.2\nv 0.2 2 0.2\nv -0.2 2 0.2\n"
        "vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\n"
        "usemtl floor\nf 1/1 4/4 3/3 2/2\nusemtl light\nf 5 6 7 8\n");
    const DeviceScene ds = floor_view(obj);
    EXPECT_TRUE(has_define(ds, "HAS_BUMP_MAPS"));
    EXPECT_TRUE(has_define(ds, "HAS_SHADING_NORMALS"));
    expect_integrators_agree(ds, 21, "normal map");
    expect_pt_routes_agree(ds, 3, 4, "normal map");
}

// ---- Specialisation ---------------------------------------------------------------------

// A scene without textures builds no texture code; the all-features build does not add it
// either (its buffers would be placeholders).
TEST(Textures, UntexturedSceneHasNoTextureCode) {
    Scene scene = load_scene(scene_path("cornell-box"));
    DeviceScene ds = build_device_scene(scene, 8, 8);
    for (bool all : {false, true}) {
        for (const std::string& d : kernel_defines(ds, Integrator::Bdpt, 5, all, SamplerKind::Independent)) {
            EXPECT_NE(d, "HAS_TEXTURES");
            EXPECT_NE(d, "HAS_CUTOUTS");
            EXPECT_NE(d, "HAS_BUMP_MAPS");
            EXPECT_NE(d, "HAS_EMISSION_TEXTURES");
        }
    }
}

}  // namespace
}  // namespace clbdpt::test
