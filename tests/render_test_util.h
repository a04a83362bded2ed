// Shared by the whole-image tests: one OpenCL device context per test process (so programs
// are built once), bundled-scene loading, and per-pass statistics for tolerances in standard
// errors.
#pragma once

#include <cmath>
#include <string>
#include <vector>

#include "device/opencl.h"
#include "render/device_scene.h"
#include "render/renderer.h"
#include "scene/scene.h"

namespace clbdpt::test {

inline DeviceContext& test_device() {
    static DeviceContext device(select_device(""));
    return device;
}

// Appends a material to a hand-built scene; returns its index.
inline int add_scene_material(Scene& scene, const Material& m, const std::string& name = "") {
    scene.materials.push_back(m);
    scene.material_names.push_back(name.empty() ? "m" + std::to_string(scene.materials.size() - 1) : name);
    return int(scene.materials.size()) - 1;
}

// Appends a triangle to a hand-built scene. Front face (the emitting one, the outside of
// glass) = counter-clockwise seen from it: normal = normalize(cross(b - a, c - a)).
inline void add_scene_triangle(Scene& scene, Vec3 a, Vec3 b, Vec3 c, int material) {
    auto corner = [](Vec3 v) {
        cl_float4 r;
        r.s[0] = v.x;
        r.s[1] = v.y;
        r.s[2] = v.z;
        r.s[3] = 0.0f;
        return r;
    };
    Triangle t{};
    t.p0 = corner(a);
    t.p1 = corner(b);
    t.p2 = corner(c);
    TriangleInfo info{};
    info.material = material;
    info.light = -1;
    info.normals = -1;
    info.source_index = int(scene.triangles.size());
    scene.triangles.push_back(t);
    scene.infos.push_back(info);
    scene.bounds.extend(a);
    scene.bounds.extend(b);
    scene.bounds.extend(c);
}

// A point light of intensity `color` at `position`.
inline LightDesc point_light(Vec3 position, Vec3 color) {
    LightDesc l;
    l.kind = LightDesc::Kind::Point;
    l.position = position;
    l.color = color;
    return l;
}

// A spot light at `position` aimed at `target`: intensity `color`, a cone of half angle
// cone_angle whose outer cone_delta degrees fall off.
inline LightDesc spot_light(Vec3 position, Vec3 target, Vec3 color, float cone_angle, float cone_delta) {
    LightDesc l;
    l.kind = LightDesc::Kind::Spot;
    l.position = position;
    l.target = target;
    l.color = color;
    l.cone_angle = cone_angle;
    l.cone_delta = cone_delta;
    return l;
}

inline std::string scene_path(const std::string& name) {
    return std::string(CLBDPT_SCENES_DIR) + "/" + name + "/" + name + ".json";
}

// Per-region statistics over independent passes: the image is cut into blocks x blocks
// regions; each pass (one sample per pixel, its own sample index) gives one value per region
// (mean over the region's pixels and channels), and passes are independent, so the mean's
// standard error is the passes' standard deviation / sqrt(passes).
struct RegionStats {
    int blocks = 0;
    std::vector<double> mean;       // per region
    std::vector<double> std_error;  // per region
    double image_mean = 0;
    double image_std_error = 0;
};

// Mean over the pixels and channels of each of blocks x blocks regions, then of the image
// (the last entry).
inline std::vector<double> region_values(const std::vector<float>& img, int w, int h, int blocks) {
    const int regions = blocks * blocks;
    std::vector<double> value(regions + 1, 0.0);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            int region = (y * blocks / h) * blocks + (x * blocks / w);
            for (int c = 0; c < 3; ++c) {
                double v = img[(size_t(y) * w + x) * 3 + c];
                value[region] += v;
                value[regions] += v;
            }
        }
    for (int r = 0; r <= regions; ++r) value[r] *= r < regions ? double(regions) / (3.0 * w * h) : 1.0 / (3.0 * w * h);
    return value;
}

inline RegionStats render_region_stats(const DeviceScene& scene, RenderOptions options, int passes, int blocks) {
    Renderer renderer(test_device(), scene, options);
    const int w = scene.camera.width, h = scene.camera.height;
    const int regions = blocks * blocks;
    std::vector<double> sum(regions + 1), sum2(regions + 1);
    for (int pass = 0; pass < passes; ++pass) {
        Film film(w, h);
        renderer.render_passes(film, uint32_t(pass), 1);
        std::vector<double> value = region_values(film.image(), w, h, blocks);
        for (int r = 0; r <= regions; ++r) {
            sum[r] += value[r];
            sum2[r] += value[r] * value[r];
        }
    }
    RegionStats st;
    st.blocks = blocks;
    for (int r = 0; r <= regions; ++r) {
        double m = sum[r] / passes;
        double var = std::max(0.0, (sum2[r] / passes - m * m)) * passes / (passes - 1);
        double se = std::sqrt(var / passes);
        if (r < regions) {
            st.mean.push_back(m);
            st.std_error.push_back(se);
        } else {
            st.image_mean = m;
            st.image_std_error = se;
        }
    }
    return st;
}

}  // namespace clbdpt::test
