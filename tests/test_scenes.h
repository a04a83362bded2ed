// Shared by the whole-image correctness tests (furnace_test, scene_agreement_test,
// hard_cases_test): scenes built in code (triangles, quads, boxes, tessellated spheres with a
// chosen facing), scene scaling, the CLBDPT_TEST_SCALE pass multiplier, and comparisons in
// standard errors that also print one machine-readable line each for scripts/stat_report.sh:
//
//     STAT <test>/<comparison> <statistic> <threshold> <pass|fail>
//
// The statistic is the largest |difference| / (combined standard error) over the image mean
// and the regions compared, the threshold the number of standard errors allowed; for exact
// checks (a sum of pixels that must be 0) the statistic is the quantity and the threshold 0.
#pragma once

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <iostream>
#include <string>
#include <utility>
#include <vector>

#include "render_test_util.h"

namespace clbdpt::test {

// ---- Run length -------------------------------------------------------------------------

// CLBDPT_TEST_SCALE (default 1) multiplies every pass count of the statistical tests, so a
// report can run them longer (scripts/stat_report.sh). Thresholds stay in standard errors, so
// a longer run is a sharper test of the same claim.
inline int test_scale() {
    static const int scale = [] {
        const char* s = std::getenv("CLBDPT_TEST_SCALE");
        int v = s ? std::atoi(s) : 1;
        return v >= 1 ? v : 1;
    }();
    return scale;
}

inline int scaled_passes(int passes) { return passes * test_scale(); }

// ---- Scenes built in code -------------------------------------------------------------

inline cl_float4 float4_of(Vec3 v) {
    cl_float4 r;
    r.s[0] = v.x;
    r.s[1] = v.y;
    r.s[2] = v.z;
    r.s[3] = 0.0f;
    return r;
}

inline Vec3 vec3_of(const cl_float4& v) { return {v.s[0], v.s[1], v.s[2]}; }

inline Material diffuse_material(Vec3 kd, Vec3 ke = {0, 0, 0}) {
    Material m{};
    m.kind = MATERIAL_DIFFUSE;
    m.kd = float4_of(kd);
    m.ke = float4_of(ke);
    m.ior = 1.0f;
    return m;
}

inline Material mirror_material(Vec3 ks) {
    Material m{};
    m.kind = MATERIAL_MIRROR;
    m.ks = float4_of(ks);
    m.ior = 1.0f;
    return m;
}

inline Material glass_material(float ior) {
    Material m{};
    m.kind = MATERIAL_GLASS;
    m.ks = float4_of({1, 1, 1});
    m.ior = ior;
    return m;
}

// Builds a Scene the way the loader leaves one: triangles in load order, one TriangleInfo
// each (flat shading, light filled in by build_device_scene), bounds over every vertex.
struct SceneBuilder {
    Scene scene;

    int material(const Material& m, const std::string& name = "") { return add_scene_material(scene, m, name); }

    // Front face (the emitting one, the outside of glass) = counter-clockwise seen from it.
    void triangle(Vec3 a, Vec3 b, Vec3 c, int material) { add_scene_triangle(scene, a, b, c, material); }

    // a, b, c, d counter-clockwise seen from the front.
    void quad(Vec3 a, Vec3 b, Vec3 c, Vec3 d, int material) {
        triangle(a, b, c, material);
        triangle(a, c, d, material);
    }

    // Axis-aligned box; inward: the faces' fronts look into the box (a room), else out of it.
    void box(Vec3 lo, Vec3 hi, bool inward, int material) { box(lo, hi, inward, {material, material, material, material, material, material}); }

    // materials: -x, +x, -y, +y, -z, +z faces.
    void box(Vec3 lo, Vec3 hi, bool inward, const std::vector<int>& materials) {
        Vec3 c[8];
        for (int i = 0; i < 8; ++i) c[i] = {i & 1 ? hi.x : lo.x, i & 2 ? hi.y : lo.y, i & 4 ? hi.z : lo.z};
        // Each face counter-clockwise seen from outside the box.
        const int faces[6][4] = {{0, 4, 6, 2}, {1, 3, 7, 5}, {0, 1, 5, 4}, {2, 6, 7, 3}, {0, 2, 3, 1}, {4, 5, 7, 6}};
        for (int f = 0; f < 6; ++f) {
            const int* q = faces[f];
            if (inward)
                quad(c[q[0]], c[q[3]], c[q[2]], c[q[1]], materials[f]);
            else
                quad(c[q[0]], c[q[1]], c[q[2]], c[q[3]], materials[f]);
        }
    }

    // Watertight icosphere (an icosahedron subdivided `subdivisions` times, vertices projected
    // onto the sphere and shared between neighbouring triangles bit for bit). inward: the
    // front faces look toward the centre.
    void sphere(Vec3 center, float radius, int subdivisions, bool inward, int material) {
        const float t = (1.0f + std::sqrt(5.0f)) / 2.0f;
        std::vector<Vec3> v = {{-1, t, 0}, {1, t, 0}, {-1, -t, 0}, {1, -t, 0}, {0, -1, t}, {0, 1, t},
                               {0, -1, -t}, {0, 1, -t}, {t, 0, -1}, {t, 0, 1}, {-t, 0, -1}, {-t, 0, 1}};
        for (Vec3& p : v) p = normalize(p);
        std::vector<std::array<int, 3>> f = {{0, 11, 5}, {0, 5, 1},  {0, 1, 7},   {0, 7, 10}, {0, 10, 11},
                                              {1, 5, 9},  {5, 11, 4}, {11, 10, 2}, {10, 7, 6}, {7, 1, 8},
                                              {3, 9, 4},  {3, 4, 2},  {3, 2, 6},   {3, 6, 8},  {3, 8, 9},
                                              {4, 9, 5},  {2, 4, 11}, {6, 2, 10},  {8, 6, 7},  {9, 8, 1}};
        for (int s = 0; s < subdivisions; ++s) {
            std::vector<std::array<int, 3>> next;
            std::vector<std::pair<std::pair<int, int>, int>> mids;
            auto midpoint = [&](int a, int b) {
                std::pair<int, int> key(std::min(a, b), std::max(a, b));
                for (auto& m : mids)
                    if (m.first == key) return m.second;
                v.push_back(normalize((v[a] + v[b]) * 0.5f));
                mids.push_back({key, int(v.size()) - 1});
                return int(v.size()) - 1;
            };
            for (auto& tri : f) {
                int a = midpoint(tri[0], tri[1]), b = midpoint(tri[1], tri[2]), c = midpoint(tri[2], tri[0]);
                next.push_back({tri[0], a, c});
                next.push_back({tri[1], b, a});
                next.push_back({tri[2], c, b});
                next.push_back({a, b, c});
            }
            f.swap(next);
        }
        // The base faces are counter-clockwise seen from outside.
        for (auto& tri : f) {
            Vec3 a = center + v[tri[0]] * radius, b = center + v[tri[1]] * radius, c = center + v[tri[2]] * radius;
            if (inward)
                triangle(a, c, b, material);
            else
                triangle(a, b, c, material);
        }
    }

    // Latitude-longitude sphere of `segments` x `rings` quads (triangles at the poles), the
    // coarse tessellation exporters write for low-poly models, facing outward. smooth: each
    // corner carries the exact sphere normal (an OBJ's `vn`), so the shading normals differ
    // from the facets' by up to half a segment's angle and the terminator bands exist.
    void uv_sphere(Vec3 center, float radius, int segments, int rings, bool smooth, int material) {
        const float pi = 3.14159265358979323846f;
        auto unit = [&](int ring, int segment) {
            const float theta = pi * float(ring) / float(rings), phi = 2.0f * pi * float(segment % segments) / float(segments);
            return Vec3{std::sin(theta) * std::cos(phi), std::cos(theta), -std::sin(theta) * std::sin(phi)};
        };
        auto add = [&](Vec3 a, Vec3 b, Vec3 c) {  // unit directions, counter-clockwise from outside
            triangle(center + a * radius, center + b * radius, center + c * radius, material);
            if (!smooth) return;
            TriangleNormals tn{};
            tn.n0 = float4_of(a);
            tn.n1 = float4_of(b);
            tn.n2 = float4_of(c);
            scene.infos.back().normals = int(scene.normals.size());
            scene.normals.push_back(tn);
        };
        for (int r = 0; r < rings; ++r)
            for (int k = 0; k < segments; ++k) {
                const Vec3 a = unit(r, k), b = unit(r + 1, k), c = unit(r + 1, k + 1), d = unit(r, k + 1);
                if (r > 0) add(a, b, d);
                if (r + 1 < rings) add(d, b, c);
            }
    }

    void camera(Vec3 eye, Vec3 target, float fov_degrees, Vec3 up = {0, 1, 0}) {
        scene.camera.eye = eye;
        scene.camera.target = target;
        scene.camera.up = up;
        scene.camera.fov_degrees = fov_degrees;
        scene.camera.lens_radius = 0.0f;
        scene.camera.focus_distance = length(target - eye);
    }
};

// A closed Cornell-like room built in code: [-1,1] x [0,2] x [-1,1], red -x wall, green +x
// wall, white elsewhere, a white block on the floor, and a square ceiling light of side
// `light_side` just below the ceiling, facing down, whose radiance is scaled by
// (0.5 / light_side)^2 so its power does not depend on its size. The camera looks down at the
// floor and never sees the ceiling (the light is not in view, so a light too small for a
// camera ray to hit is not a difference between strategies that can and cannot see it).
struct RoomMaterials {
    int white, red, green, light;
};

inline RoomMaterials room_materials(SceneBuilder& b, float light_radiance = 12.0f, float light_side = 0.5f) {
    RoomMaterials m;
    m.white = b.material(diffuse_material({0.73f, 0.73f, 0.73f}), "white");
    m.red = b.material(diffuse_material({0.63f, 0.065f, 0.05f}), "red");
    m.green = b.material(diffuse_material({0.14f, 0.45f, 0.091f}), "green");
    const float scale = (0.5f / light_side) * (0.5f / light_side);
    m.light = b.material(diffuse_material({0, 0, 0}, Vec3{1.0f, 0.85f, 0.6f} * (light_radiance * scale)), "light");
    return m;
}

inline void room_walls(SceneBuilder& b, const RoomMaterials& m, bool with_block = true) {
    b.box({-1, 0, -1}, {1, 2, 1}, /*inward=*/true, {m.red, m.green, m.white, m.white, m.white, m.white});
    if (with_block) b.box({-0.55f, 0, -0.1f}, {0.0f, 0.6f, 0.45f}, /*inward=*/false, m.white);
}

// A horizontal square emitter facing down (counter-clockwise seen from below), centred at c.
inline void ceiling_light(SceneBuilder& b, Vec3 c, float side, int material) {
    const float h = 0.5f * side;
    b.quad({c.x - h, c.y, c.z - h}, {c.x + h, c.y, c.z - h}, {c.x + h, c.y, c.z + h}, {c.x - h, c.y, c.z + h}, material);
}

inline void room_camera(SceneBuilder& b) { b.camera({0, 1, -0.95f}, {0, 0.6f, 1}, 60.0f); }

// The room with its walls (and block), its ceiling light and its camera.
inline void lit_room(SceneBuilder& b, bool with_block = true) {
    RoomMaterials m = room_materials(b);
    room_walls(b, m, with_block);
    ceiling_light(b, {0, 1.999f, 0.2f}, 0.5f, m.light);
    room_camera(b);
}

inline Scene room_scene(float light_side) {
    SceneBuilder b;
    RoomMaterials m = room_materials(b, 12.0f, light_side);
    room_walls(b, m);
    ceiling_light(b, {0, 1.999f, 0.2f}, light_side, m.light);
    room_camera(b);
    return b.scene;
}

// ---- Participating media (cl/medium.h) ----

// 1 + the index of a new medium.
inline int add_medium(Scene& scene, const std::string& name, Vec3 sigma_a, Vec3 sigma_s, float g) {
    MediumDesc m;
    m.name = name;
    m.sigma_a = sigma_a;
    m.sigma_s = sigma_s;
    m.g = g;
    scene.media.push_back(m);
    return int(scene.media.size());
}

inline Material interface_material(int interior, int exterior = 0) {
    Material m = diffuse_material({0, 0, 0});
    m.kind = MATERIAL_INTERFACE;
    m.interior_medium = interior;
    m.exterior_medium = exterior;
    return m;
}

// The scene-wide medium on both sides of every material, as the scene file's "medium" makes it.
inline void fill_with(Scene& scene, int medium) {
    scene.scene_medium = medium;
    for (Material& m : scene.materials) m.interior_medium = m.exterior_medium = medium;
}

inline void add_environment(Scene& scene, Vec3 radiance) {
    LightDesc env;
    env.kind = LightDesc::Kind::Environment;
    env.color = radiance;
    scene.lights.push_back(env);
}

// Every position in the scene (vertices, camera eye and target, light positions) mapped by f,
// the bounds recomputed.
template <class F>
inline void map_scene_positions(Scene& scene, F f) {
    auto map4 = [&](cl_float4& p) {
        Vec3 q = f(vec3_of(p));
        for (int i = 0; i < 3; ++i) p.s[i] = q[i];
    };
    Bounds3 bounds;
    for (Triangle& t : scene.triangles) {
        map4(t.p0);
        map4(t.p1);
        map4(t.p2);
        bounds.extend(vec3_of(t.p0));
        bounds.extend(vec3_of(t.p1));
        bounds.extend(vec3_of(t.p2));
    }
    scene.bounds = bounds;
    scene.camera.eye = f(scene.camera.eye);
    scene.camera.target = f(scene.camera.target);
    for (LightDesc& l : scene.lights) {
        l.position = f(l.position);
        l.target = f(l.target);
    }
}

// Every length in the scene times s: positions, focus distance, lens radius. Radiance and
// reflectance do not change, so the image must not either (point and spot intensities would
// need s^2 to keep irradiance; the scenes scaled here have none).
inline void scale_scene(Scene& scene, float s) {
    map_scene_positions(scene, [s](Vec3 p) { return p * s; });
    scene.camera.focus_distance *= s;
    scene.camera.lens_radius *= s;
}

// Every position in the scene moved by `offset`.
inline void translate_scene(Scene& scene, Vec3 offset) {
    map_scene_positions(scene, [offset](Vec3 p) { return p + offset; });
}

// ---- Statistics -------------------------------------------------------------------------

inline std::string current_test_name() {
    const ::testing::TestInfo* info = ::testing::UnitTest::GetInstance()->current_test_info();
    if (!info) return "unknown";
    std::string name = std::string(info->test_suite_name()) + "." + info->name();
    return name;
}

// One STAT line per comparison (stdout), parsed by scripts/stat_report.sh; spaces in names
// become underscores so the line splits on whitespace.
inline void report_stat(const std::string& comparison, double statistic, double threshold, bool pass) {
    std::string name = current_test_name() + "/" + comparison;
    std::replace(name.begin(), name.end(), ' ', '_');
    char line[512];
    std::snprintf(line, sizeof line, "STAT %s %.4g %.4g %s", name.c_str(), statistic, threshold, pass ? "pass" : "fail");
    std::cout << line << std::endl;
}

// Whether two independent estimates agree region by region and on the image mean within
// `sigmas` combined standard errors. rel_floor: a floor on the standard error relative to
// the compared values, for estimators that are (nearly) deterministic (float rounding of the
// per-sample products is ~1e-6 relative; the floor is well above it and well below any error
// worth catching). Prints one STAT line (the worst |z|) and fails the test through EXPECT.
inline double expect_agree(const RegionStats& a, const RegionStats& b, double sigmas, const std::string& what,
                           double rel_floor = 1e-5) {
    double worst = 0;
    auto z_of = [&](double ma, double sa, double mb, double sb) {
        double floor = rel_floor * std::max(std::fabs(ma), std::fabs(mb));
        double se = std::sqrt(sa * sa + sb * sb + floor * floor);
        double d = std::fabs(ma - mb);
        double z = se > 0 ? d / se : (d > 0 ? INFINITY : 0.0);
        return std::isnan(z) ? INFINITY : z;  // a NaN estimate is a failure, not a skip
    };
    for (size_t r = 0; r < a.mean.size(); ++r) {
        double z = z_of(a.mean[r], a.std_error[r], b.mean[r], b.std_error[r]);
        worst = std::max(worst, z);
        EXPECT_LE(z, sigmas) << what << " region " << r << ": " << a.mean[r] << " +- " << a.std_error[r] << " vs "
                             << b.mean[r] << " +- " << b.std_error[r] << " (" << z << " standard errors)";
    }
    double z = z_of(a.image_mean, a.image_std_error, b.image_mean, b.image_std_error);
    worst = std::max(worst, z);
    EXPECT_LE(z, sigmas) << what << " image mean: " << a.image_mean << " +- " << a.image_std_error << " vs "
                         << b.image_mean << " +- " << b.image_std_error << " (" << z << " standard errors)";
    report_stat(what, worst, sigmas, !(worst > sigmas));
    return worst;
}

// Whether an estimate matches a known value in every region and on the image mean.
inline double expect_matches(const RegionStats& a, double expected, double sigmas, const std::string& what,
                             double rel_floor = 1e-5) {
    RegionStats exact = a;
    std::fill(exact.mean.begin(), exact.mean.end(), expected);
    std::fill(exact.std_error.begin(), exact.std_error.end(), 0.0);
    exact.image_mean = expected;
    exact.image_std_error = 0.0;
    return expect_agree(a, exact, sigmas, what, rel_floor);
}

// Renders `passes` independent passes and returns per-region statistics; any non-finite
// sample makes the renderer throw clbdpt::Error, which fails the test with its message.
inline RegionStats render_stats_or_fail(const DeviceScene& scene, const RenderOptions& options, int passes, int blocks,
                                        const std::string& what) {
    try {
        return render_region_stats(scene, options, passes, blocks);
    } catch (const std::exception& e) {
        ADD_FAILURE() << what << ": render failed: " << e.what();
        report_stat(what + "/finite", 1, 0, false);
        RegionStats empty;
        empty.blocks = blocks;
        empty.mean.assign(size_t(blocks) * blocks, NAN);
        empty.std_error.assign(size_t(blocks) * blocks, NAN);
        empty.image_mean = NAN;
        empty.image_std_error = NAN;
        return empty;
    }
}

// Paired comparison of two scenes that should give the same image: both are rendered with the
// same options and seed, pass by pass, so pass p of each uses the same random numbers and
// their difference cancels most of the noise (in a scaled scene most paths are the same
// paths). Passes are still independent of each other, so the mean of the per-pass
// differences has the standard error of their spread / sqrt(passes): a far sharper test of
// "same expected image" than two independent renders, and as valid.
struct PairedStats {
    RegionStats a, b;  // each scene on its own (mean and standard error)
    RegionStats diff;  // a - b per region and for the image
};


// The same for one scene under two sets of options that should give the same image, with the
// same seed (e.g. two estimators of one class of paths, the rest drawn alike).
inline PairedStats render_paired(const DeviceScene& scene_a, const RenderOptions& options_a,
                                 const DeviceScene& scene_b, const RenderOptions& options_b, int passes, int blocks) {
    Renderer ra(test_device(), scene_a, options_a), rb(test_device(), scene_b, options_b);
    const int w = scene_a.camera.width, h = scene_a.camera.height;
    const int n = blocks * blocks + 1;
    std::vector<double> sum[3], sum2[3];
    for (auto& v : sum) v.assign(n, 0.0);
    for (auto& v : sum2) v.assign(n, 0.0);
    for (int pass = 0; pass < passes; ++pass) {
        Film fa(w, h), fb(w, h);
        ra.render_passes(fa, uint32_t(pass), 1);
        rb.render_passes(fb, uint32_t(pass), 1);
        std::vector<double> va = region_values(fa.image(), w, h, blocks), vb = region_values(fb.image(), w, h, blocks);
        for (int r = 0; r < n; ++r) {
            const double v[3] = {va[r], vb[r], va[r] - vb[r]};
            for (int k = 0; k < 3; ++k) {
                sum[k][r] += v[k];
                sum2[k][r] += v[k] * v[k];
            }
        }
    }
    PairedStats out;
    RegionStats* st[3] = {&out.a, &out.b, &out.diff};
    for (int k = 0; k < 3; ++k) {
        st[k]->blocks = blocks;
        for (int r = 0; r < n; ++r) {
            double m = sum[k][r] / passes;
            double var = std::max(0.0, sum2[k][r] / passes - m * m) * passes / (passes - 1);
            double se = std::sqrt(var / passes);
            if (r + 1 < n) {
                st[k]->mean.push_back(m);
                st[k]->std_error.push_back(se);
            } else {
                st[k]->image_mean = m;
                st[k]->image_std_error = se;
            }
        }
    }
    return out;
}

inline PairedStats render_paired(const DeviceScene& scene_a, const DeviceScene& scene_b, const RenderOptions& options,
                                 int passes, int blocks) {
    return render_paired(scene_a, options, scene_b, options, passes, blocks);
}

// Whether the paired difference is zero within `sigmas` of its standard error, with a floor
// of rel_floor times the compared values (a bit-identical pair has a standard error of 0).
inline double expect_same_paired(const PairedStats& p, double sigmas, const std::string& what, double rel_floor = 1e-5) {
    double worst = 0;
    for (size_t r = 0; r <= p.diff.mean.size(); ++r) {
        bool image = r == p.diff.mean.size();
        double d = image ? p.diff.image_mean : p.diff.mean[r];
        double se = image ? p.diff.image_std_error : p.diff.std_error[r];
        double scale = image ? std::max(std::fabs(p.a.image_mean), std::fabs(p.b.image_mean))
                             : std::max(std::fabs(p.a.mean[r]), std::fabs(p.b.mean[r]));
        double s = std::sqrt(se * se + rel_floor * rel_floor * scale * scale);
        double z = s > 0 ? std::fabs(d) / s : (d != 0 ? INFINITY : 0.0);
        if (std::isnan(z)) z = INFINITY;
        worst = std::max(worst, z);
        EXPECT_LE(z, sigmas) << what << (image ? " image mean" : " region " + std::to_string(r)) << ": "
                             << (image ? p.a.image_mean : p.a.mean[r]) << " vs " << (image ? p.b.image_mean : p.b.mean[r])
                             << ", paired difference " << d << " +- " << se << " (" << z << " standard errors)";
    }
    report_stat(what, worst, sigmas, !(worst > sigmas));
    return worst;
}

inline RenderOptions make_options(Integrator integrator, int max_depth, uint32_t seed,
                                  SamplerKind sampler = SamplerKind::Independent) {
    RenderOptions o;
    o.integrator = integrator;
    o.max_depth = max_depth;
    o.seed = seed;
    o.sampler = sampler;
    return o;
}

// Per-region statistics of `passes` (times CLBDPT_TEST_SCALE) independent passes of one
// integrator, independent sampler, over blocks x blocks regions.
inline RegionStats render_regions(const DeviceScene& scene, Integrator integrator, int depth, uint32_t seed,
                                  int passes, const std::string& what, int blocks = 4) {
    return render_stats_or_fail(scene, make_options(integrator, depth, seed), scaled_passes(passes), blocks, what);
}

// Whether the kernel built for `scene` (bdpt, depth 5, its own features) has flag `define`.
inline bool kernel_has_define(const Scene& scene, const std::string& define) {
    DeviceScene ds = build_device_scene(scene, 8, 8);
    for (const std::string& d : kernel_defines(ds, Integrator::Bdpt, 5, false, SamplerKind::Sobol))
        if (d == define) return true;
    return false;
}

// The set-up of the Beer-Lambert tests (media_test.cpp, medium_grid_test.cpp): an emitter of
// radiance le 3 units in front of a camera whose 4-degree view it just fills (0.22 wide, the
// view 0.21 at its distance, so the light tracer's points on it mostly land on the film), and
// an axis-aligned box of material `slab` spanning z 1 .. 1.5 across the whole view. Every ray
// crosses the slab within 0.1% of its thickness (1/cos(2 deg) - 1 = 6e-4).
inline void emitter_behind_slab(SceneBuilder& b, Vec3 le, int slab) {
    int emitter = b.material(diffuse_material({0, 0, 0}, le), "panel");
    const float h = 0.11f;
    b.quad({-h, -h, 3}, {-h, h, 3}, {h, h, 3}, {h, -h, 3}, emitter);  // facing -z, toward the camera
    b.box({-1.5f, -1.5f, 1.0f}, {1.5f, 1.5f, 1.5f}, /*inward=*/false, slab);
    b.camera({0, 0, 0}, {0, 0, 1}, 4.0f);
}

inline std::string options_name(const RenderOptions& o) {
    std::string n = integrator_name(o.integrator);
    if (o.sampler != SamplerKind::Independent) n += std::string("-") + sampler_name(o.sampler);
    return n + "-d" + std::to_string(o.max_depth);
}


// The path tracer one vertex at a time (cl/path_tracer.h) against the same strategies made
// from a stored camera subpath, as bdpt makes them (RenderOptions::pt_from_subpaths): the
// same draws, vertex functions and order of sums give the same film bit for bit, and the same
// number of rays. Sobol sampler, `passes` passes at max depth `max_depth`.
inline void expect_pt_routes_agree(const DeviceScene& scene, int max_depth, int passes, const std::string& what,
                                   int roulette_camera_from = kRouletteCameraFrom) {
    RenderOptions options = make_options(Integrator::Pt, max_depth, 5, SamplerKind::Sobol);
    options.roulette_camera_from = roulette_camera_from;
    Renderer one_vertex_at_a_time(test_device(), scene, options);
    Film a(scene.camera.width, scene.camera.height);
    one_vertex_at_a_time.render_passes(a, 0, passes);
    options.pt_from_subpaths = true;
    Renderer from_subpaths(test_device(), scene, options);
    Film b(scene.camera.width, scene.camera.height);
    from_subpaths.render_passes(b, 0, passes);
    size_t differing = 0;
    for (size_t i = 0; i < a.camera_sum.size(); ++i) differing += a.camera_sum[i] != b.camera_sum[i];
    EXPECT_EQ(differing, 0u) << what << ": " << differing << " of " << a.camera_sum.size() << " film values differ";
    EXPECT_EQ(one_vertex_at_a_time.stats().rays, from_subpaths.stats().rays) << what;
    EXPECT_EQ(one_vertex_at_a_time.stats().samples, from_subpaths.stats().samples) << what;
    double total = 0;
    for (double v : a.camera_sum) total += v;
    EXPECT_GT(total, 0.0) << what << ": a black image shows nothing";
}

}  // namespace clbdpt::test
