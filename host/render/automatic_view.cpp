#include "render/automatic_view.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

#include "bvh/bvh_query.h"

namespace clbdpt {
namespace {

constexpr float kPi = 3.14159265358979323846f;
constexpr int kProbeGrid = 24;        // probe rays per side of the framed view
constexpr int kSphereProbes = 256;    // probe directions around a candidate eye
// The framed view "sees only an outer wall" when the median probe hit lies within this
// fraction of the box's depth behind its front face...
constexpr float kWallDepth = 0.05f;
// ... and a point inside "is enclosed" when at least this fraction of directions hit something,
constexpr float kEnclosed = 0.6f;
// with content: at least this fraction of those hits away from the box's faces (more than
// kFaceMargin of the extent from each), which tells a furnished room from an empty shell.
constexpr float kWithContent = 0.1f;
constexpr float kFaceMargin = 0.05f;
// An eye with this fraction of directions blocked within kCrampedDistance of the diagonal sits
// inside something (a column, a wall).
constexpr float kCramped = 0.3f;
constexpr float kCrampedDistance = 0.01f;

Vec3 sphere_direction(int i, int n) {  // Fibonacci sphere: evenly spread directions
    const float z = 1.0f - 2.0f * (float(i) + 0.5f) / float(n);
    const float r = std::sqrt(std::max(0.0f, 1.0f - z * z));
    const float phi = float(i) * kPi * (3.0f - std::sqrt(5.0f));
    return {r * std::cos(phi), z, r * std::sin(phi)};
}

bool away_from_faces(Vec3 p, const Bounds3& b) {
    const Vec3 e = b.extent();
    for (int k = 0; k < 3; ++k) {
        const float margin = kFaceMargin * e[k];
        if (p[k] < b.lo[k] + margin || p[k] > b.hi[k] - margin) return false;
    }
    return true;
}

struct EyeProbe {
    float enclosed = 0;      // fraction of directions that hit
    float with_content = 0;  // fraction of hits away from the box's faces
    float cramped = 0;       // fraction of directions blocked very close
};

EyeProbe probe_eye(const DeviceScene& s, const Bounds3& b, Vec3 eye) {
    const float diagonal = length(b.extent());
    int hits = 0, inner = 0, close = 0;
    for (int i = 0; i < kSphereProbes; ++i) {
        const Vec3 d = sphere_direction(i, kSphereProbes);
        const float t = closest_hit_distance(s.nodes, s.triangles, eye, d);
        if (!std::isfinite(t)) continue;
        ++hits;
        inner += away_from_faces(eye + d * t, b) ? 1 : 0;
        close += t < kCrampedDistance * diagonal ? 1 : 0;
    }
    EyeProbe p;
    p.enclosed = float(hits) / float(kSphereProbes);
    p.with_content = hits ? float(inner) / float(hits) : 0.0f;
    p.cramped = float(close) / float(kSphereProbes);
    return p;
}

// The kProbeGrid^2 unit directions through a square view along `forward` (up roughly `up`).
std::vector<Vec3> view_directions(Vec3 forward, Vec3 up, float fov_degrees) {
    const Vec3 right = normalize(cross(forward, up));
    const Vec3 true_up = cross(right, forward);
    const float tan_half = std::tan(0.5f * fov_degrees * kPi / 180.0f);
    std::vector<Vec3> directions;
    for (int y = 0; y < kProbeGrid; ++y)
        for (int x = 0; x < kProbeGrid; ++x) {
            const float sx = (2.0f * (float(x) + 0.5f) / kProbeGrid - 1.0f) * tan_half;
            const float sy = (2.0f * (float(y) + 0.5f) / kProbeGrid - 1.0f) * tan_half;
            directions.push_back(normalize(forward + right * sx + true_up * sy));
        }
    return directions;
}

// Mean free distance (misses count as the diagonal) over a grid of rays filling the view.
float view_depth(const DeviceScene& s, const Bounds3& b, Vec3 eye, Vec3 forward, float fov_degrees) {
    const float diagonal = length(b.extent());
    double sum = 0;
    for (const Vec3& d : view_directions(forward, Vec3(0, 1, 0), fov_degrees))
        sum += std::min(diagonal, closest_hit_distance(s.nodes, s.triangles, eye, d));
    return float(sum / double(kProbeGrid * kProbeGrid));
}

}  // namespace

AutomaticView choose_automatic_view(const CameraDesc& framed, const Bounds3& bounds, const DeviceScene& scene) {
    AutomaticView view;
    view.camera = framed;
    const Vec3 extent = bounds.extent();
    if (bounds.empty() || !(extent.x > 0 && extent.y > 0 && extent.z > 0)) return view;

    // 1. What the framed view shows: how deep behind the box's front face its hits lie.
    const Vec3 forward = normalize(framed.target - framed.eye);
    std::vector<float> depths;
    for (const Vec3& d : view_directions(forward, framed.up, framed.fov_degrees)) {
        const float t = closest_hit_distance(scene.nodes, scene.triangles, framed.eye, d);
        if (std::isfinite(t)) depths.push_back((bounds.hi.z - (framed.eye + d * t).z) / extent.z);
    }
    if (depths.empty()) return view;
    std::nth_element(depths.begin(), depths.begin() + long(depths.size() / 2), depths.end());
    if (depths[depths.size() / 2] > kWallDepth) return view;

    // 2. Is there an enclosed, furnished inside? Candidate eyes: the box's centre, and lower, at
    // about a person's eye height in a room of that size.
    const Vec3 center = bounds.center();
    const Vec3 candidates[] = {center, Vec3(center.x, bounds.lo.y + 0.3f * extent.y, center.z)};
    const Vec3 directions[] = {Vec3(0, 0, -1), Vec3(0, 0, 1), Vec3(1, 0, 0), Vec3(-1, 0, 0)};
    float best = -1;
    for (const Vec3& eye : candidates) {
        const EyeProbe p = probe_eye(scene, bounds, eye);
        if (p.enclosed < kEnclosed || p.with_content < kWithContent || p.cramped > kCramped) continue;
        for (const Vec3& dir : directions) {
            const float depth = view_depth(scene, bounds, eye, dir, framed.fov_degrees);
            if (depth > best) {
                best = depth;
                view.camera.eye = eye;
                view.camera.target = eye + dir * (0.5f * length(extent));
            }
        }
    }
    if (best < 0) return view;
    view.moved_inside = true;
    view.camera.up = Vec3(0, 1, 0);
    view.camera.focus_distance = length(view.camera.target - view.camera.eye);
    char note[256];
    const Vec3& e = view.camera.eye;
    const Vec3& t = view.camera.target;
    std::snprintf(note, sizeof note,
                  "the model encloses its content: camera placed inside, --lookat %g %g %g %g %g %g 0 1 0 "
                  "(give --lookat to aim it yourself)",
                  e.x, e.y, e.z, t.x, t.y, t.z);
    view.note = note;
    return view;
}

}  // namespace clbdpt
