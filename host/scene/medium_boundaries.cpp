// A transmitting surface that separates two media must close: a ray that enters through it has to leave
// through it, or it would carry the interior medium out into the scene. Checked per material,
// on exact corner positions (an OBJ's shared vertices give bit-equal corners).
#include <array>
#include <map>
#include <string>
#include <utility>

#include "scene/loader_internal.h"
#include "util/error.h"

namespace clbdpt::detail {

namespace {

using Corner = std::array<float, 3>;

Corner corner_of(const cl_float4& p) { return {p.s[0], p.s[1], p.s[2]}; }

}  // namespace

void check_medium_boundaries(const Scene& scene, const std::string& file) {
    for (size_t m = 0; m < scene.materials.size(); ++m) {
        const Material& material = scene.materials[m];
        // Only glass and interfaces let rays through; an opaque surface's interior is never
        // entered (the walls of a fog-filled room may well be open).
        const bool transmits = material.kind == MATERIAL_GLASS || material.kind == MATERIAL_INTERFACE;
        if (!transmits || material.interior_medium == material.exterior_medium) continue;
        // Directed edges, counted: a closed, consistently wound surface has each edge once in
        // each direction.
        std::map<std::pair<Corner, Corner>, int> edges;
        bool any = false;
        for (size_t i = 0; i < scene.triangles.size(); ++i) {
            if (scene.infos[i].material != int(m)) continue;
            any = true;
            const Triangle& t = scene.triangles[i];
            const Corner c[3] = {corner_of(t.p0), corner_of(t.p1), corner_of(t.p2)};
            for (int k = 0; k < 3; ++k) ++edges[{c[k], c[(k + 1) % 3]}];
        }
        if (!any) continue;
        size_t open = 0;
        for (const auto& [edge, count] : edges) {
            auto twin = edges.find({edge.second, edge.first});
            const int twins = twin == edges.end() ? 0 : twin->second;
            if (twins != count) open += size_t(count > twins ? count - twins : 0);
        }
        if (open > 0) {
            throw Error(file + ": material \"" + scene.material_names[m] +
                        "\" separates two media but its surface is not closed (" + std::to_string(open) +
                        " edge(s) without an oppositely wound twin)");
        }
    }
}

}  // namespace clbdpt::detail
