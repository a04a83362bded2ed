// Private to host/scene: the pieces load_scene (scene_loader.cpp) is assembled from. One concept
// per file: obj_prescan.cpp validates OBJ text line by line, obj_loader.cpp turns a tinyobj mesh
// into device triangles, mtl_materials.cpp maps MTL materials, scene_json.cpp reads scene files.
#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include "scene/scene.h"

namespace tinyobj {
struct material_t;
}

namespace clbdpt::detail {

// ---- obj_prescan.cpp ---------------------------------------------------------------------

// What the pre-scan learns about an OBJ file (faces and line numbers). tinyobj silently turns "nan" or a missing
// coordinate into 0 and skips faces with bad indices, so every `v`, `vn`, `vt`, `f` and `mtllib`
// line is checked here first, and the line numbers are kept to name the culprit later.
struct ObjPrescan {
    std::vector<int> vertex_lines;     // source line of each `v`, in order
    std::vector<int> face_lines;       // source line of each `f`, in order
    std::vector<size_t> face_offsets;  // face f's corners: face_vertices[face_offsets[f]..[f+1])
    std::vector<int> face_vertices;    // 0-based position index of every face corner
};

// Reads and validates `obj_path` (shown in messages as `display`). Throws Error
// "display:LINE: ..." on a malformed or truncated line, a non-finite number, an index out of
// range, or a `mtllib` whose file does not exist next to the OBJ.
ObjPrescan prescan_obj(const std::string& obj_path, const std::string& display);

// ---- mtl_materials.cpp -------------------------------------------------------------------

// Maps one MTL material to the device Material (see the mapping table in mtl_materials.cpp).
// Features with no equivalent add one warning, naming `source` and the material, to `warnings`.
Material map_mtl_material(const tinyobj::material_t& mtl, const std::string& source,
                          std::vector<std::string>* warnings);

// Grey Lambertian (kd 0.5) for faces that name no material.
Material default_material();
constexpr const char* kDefaultMaterialName = "default";

bool is_emissive(const Material& m);

// ---- obj_loader.cpp ----------------------------------------------------------------------

// State shared by the meshes of one scene.
struct MeshLoadContext {
    int default_material = -1;  // index of the shared "default" material once one face needs it
};

// Appends the triangles, normals and materials of one OBJ file to `scene` and extends its
// bounds. `referenced_by` names the scene file that lists it (empty for a bare OBJ scene).
void append_obj_mesh(Scene& scene, MeshLoadContext& context, const std::string& obj_path,
                     const std::string& display, const std::string& referenced_by);

// ---- scene_json.cpp ----------------------------------------------------------------------

// Fills `scene` from a JSON scene file (meshes, lights, environment map included).
void load_json_scene(Scene& scene, const std::string& path);

// ---- scene_loader.cpp --------------------------------------------------------------------

// The camera a bare OBJ gets: looking along +z at the centre of `bounds` from far enough that
// the bounding sphere (radius = half the diagonal) just fits in the field of view.
CameraDesc frame_bounds(const Bounds3& bounds, float fov_degrees);

// Throws Error("cannot open 'display'[ (referenced by ...)]") unless `path` is a readable file.
void require_readable_file(const std::string& path, const std::string& display,
                           const std::string& referenced_by);

}  // namespace clbdpt::detail
