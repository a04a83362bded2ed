#include "render/media_nesting.h"

#include <cmath>

#include "bvh/bvh_query.h"

namespace clbdpt {
namespace {

Vec3 geometric_normal(const Triangle& t) {
    return cross(vec3_of(t.p1) - vec3_of(t.p0), vec3_of(t.p2) - vec3_of(t.p0));
}

std::string medium_name(const Scene& scene, int medium) {
    return medium == 0 ? "vacuum" : "'" + scene.media[size_t(medium - 1)].name + "'";
}

// Triangles probed per material and side: enough to catch a block standing in smoke, few
// enough that a 10M-triangle scene spends milliseconds on it.
constexpr size_t kProbesPerMaterial = 64;

}  // namespace

int medium_seen_along(const DeviceScene& ds, int scene_medium, Vec3 p, Vec3 d) {
    float distance;
    const int hit = closest_hit_triangle(ds.nodes, ds.triangles, p, d, &distance);
    if (hit < 0) return scene_medium;
    const Vec3 ng = geometric_normal(ds.triangles[size_t(hit)]);
    const Material& m = ds.materials[size_t(ds.infos[size_t(hit)].material)];
    return dot(d, ng) < 0.0f ? m.exterior_medium : m.interior_medium;
}

std::vector<std::string> check_media_nesting(const Scene& scene, const DeviceScene& ds) {
    std::vector<std::string> warnings;
    if (scene.media.empty()) return warnings;
    // Up to kProbesPerMaterial triangles of each material, spread over its triangles in BVH
    // order (so over space), without a list of every triangle per material.
    std::vector<size_t> count(ds.materials.size(), 0);
    for (const TriangleInfo& info : ds.infos) ++count[size_t(info.material)];
    std::vector<std::vector<size_t>> probes(ds.materials.size());
    std::vector<size_t> seen(ds.materials.size(), 0);
    for (size_t i = 0; i < ds.infos.size(); ++i) {
        const size_t m = size_t(ds.infos[i].material);
        const size_t step = (count[m] + kProbesPerMaterial - 1) / kProbesPerMaterial;  // >= 1
        if (seen[m]++ % step == 0) probes[m].push_back(i);
    }
    // The probes leave the surface a hair off its plane (1e-5 of the scene's radius: below any
    // gap a model would leave between a surface and a boundary), slightly off the normal so
    // that they do not run along axis-aligned walls.
    const float radius = 0.5f * length(scene.bounds.extent());
    const float hair = 1e-5f * (radius > 0 ? radius : 1.0f);
    const Vec3 tilt = normalize(Vec3(0.3137f, 0.8712f, 0.3776f)) * 0.05f;
    for (size_t m = 0; m < ds.materials.size(); ++m) {
        const Material& material = ds.materials[m];
        if (material.kind == MATERIAL_INTERFACE) continue;
        int probed = 0, wrong = 0, found = -1, declared = -1;
        for (size_t i : probes[m]) {
            const Triangle& t = ds.triangles[i];
            const Vec3 n = geometric_normal(t);
            if (!(length(n) > 0)) continue;  // degenerate: no sides
            const Vec3 c = (vec3_of(t.p0) + vec3_of(t.p1) + vec3_of(t.p2)) * (1.0f / 3.0f);
            for (int side = 0; side < 2; ++side) {
                const Vec3 out = normalize(n) * (side == 0 ? 1.0f : -1.0f);  // front: exterior
                const Vec3 d = normalize(out + tilt);
                const int region = medium_seen_along(ds, scene.scene_medium, c + out * hair, d);
                const int says = side == 0 ? material.exterior_medium : material.interior_medium;
                ++probed;
                if (region != says) {
                    ++wrong;
                    found = region;
                    declared = says;
                }
            }
        }
        if (wrong > 0)
            warnings.push_back("material '" + scene.material_names[m] + "': " + std::to_string(wrong) + " of " +
                               std::to_string(probed) + " probed sides lie in " + medium_name(scene, found) +
                               " but the material declares " + medium_name(scene, declared) +
                               " there; a surface inside a medium needs it on both sides (the scene file's "
                               "\"materials\"), or the estimators will disagree");
    }
    return warnings;
}

}  // namespace clbdpt
