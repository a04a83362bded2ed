// load_scene: picks the reader by extension, frames bare OBJ files, and warns about scenes
// that cannot produce a single non-black pixel.
#include <algorithm>
#include <cctype>
#include <cmath>
#include <filesystem>
#include <fstream>

#include "scene/loader_internal.h"
#include "util/error.h"

namespace clbdpt {
namespace detail {

namespace fs = std::filesystem;

constexpr float kPi = 3.14159265358979323846f;

void require_readable_file(const std::string& path, const std::string& display,
                           const std::string& referenced_by) {
    std::error_code ec;
    const bool regular = fs::is_regular_file(path, ec);
    if (!regular || !std::ifstream(path)) {
        throw Error("cannot open '" + display + "'" +
                    (referenced_by.empty() ? std::string() : " (referenced by " + referenced_by + ")"));
    }
}

namespace {

std::string lower_extension(const std::string& path) {
    std::string ext = fs::path(path).extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
    return ext;
}

bool has_emissive_triangle(const Scene& scene) {
    for (const TriangleInfo& info : scene.infos) {
        if (is_emissive(scene.materials[static_cast<size_t>(info.material)])) return true;
    }
    return false;
}

}  // namespace
}  // namespace detail

CameraDesc frame_bounds(const Bounds3& bounds, float fov_degrees) {
    CameraDesc camera;
    camera.fov_degrees = fov_degrees;
    const Vec3 center = bounds.empty() ? Vec3(0, 0, 0) : bounds.center();
    const float radius = bounds.empty() ? 0.0f : 0.5f * length(bounds.extent());
    // The bounding sphere just fits the shorter image axis when its tangent cone has the
    // field of view's half angle: distance = radius / sin(fov / 2).
    const float half_fov = 0.5f * fov_degrees * detail::kPi / 180.0f;
    float distance = radius / std::sin(half_fov);
    if (!(distance > 0.0f) || !std::isfinite(distance)) distance = 1.0f;
    // OBJ files follow OpenGL's convention: +y up, the viewer on the +z side looking toward -z.
    const Vec3 forward(0, 0, -1);
    camera.eye = center - forward * distance;
    camera.target = center;
    camera.up = Vec3(0, 1, 0);
    camera.lens_radius = 0.0f;
    camera.focus_distance = distance;
    return camera;
}

Scene load_scene(const std::string& path, const LoadOptions& options) {
    Scene scene;
    scene.path = path;
    const std::string ext = detail::lower_extension(path);
    if (ext == ".json") {
        detail::load_json_scene(scene, path);
    } else if (ext == ".obj") {
        detail::MeshLoadContext context;
        detail::append_obj_mesh(scene, context, path, path, "");
        scene.camera = frame_bounds(scene.bounds, CameraDesc{}.fov_degrees);
    } else {
        detail::require_readable_file(path, path, "");
        throw Error(path + ": unknown scene format '" + ext + "' (expected .json or .obj)");
    }
    if (scene.lights.empty() && !detail::has_emissive_triangle(scene)) {
        // An environment cannot shine through a scene-wide medium (scene_json.cpp).
        if (options.default_light && scene.scene_medium == 0) {
            LightDesc sky;
            sky.kind = LightDesc::Kind::Environment;
            sky.color = Vec3(1, 1, 1);
            scene.lights.push_back(sky);
            scene.warnings.push_back(
                "scene has no lights: lit by a uniform white environment of radiance 1 (--no-default-light turns it off)");
        } else {
            scene.warnings.push_back("scene has no lights: the image will be black");
        }
    }
    return scene;
}

}  // namespace clbdpt
