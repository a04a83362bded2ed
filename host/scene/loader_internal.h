// Private to host/scene: the pieces load_scene (scene_loader.cpp) is assembled from. One concept
// per file: obj_prescan.cpp validates OBJ text line by line, obj_loader.cpp turns a tinyobj mesh
// into device triangles, mtl_materials.cpp maps MTL materials, scene_json.cpp reads scene files.
#pragma once

#include <cstddef>
#include <map>
#include <string>
#include <string_view>
#include <vector>

#include "scene/scene.h"

namespace tinyobj {
struct material_t;
struct texture_option_t;
}

namespace clbdpt::detail {

// ---- obj_prescan.cpp ---------------------------------------------------------------------

// What the pre-scan learns about an OBJ file (vertex lines, face counts). tinyobj silently turns "nan" or a missing
// coordinate into 0 and skips faces with bad indices, so every `v`, `vn`, `vt` and `f` line is
// checked here too, and the line numbers are kept to name the culprit.
struct ObjPrescan {
    std::vector<int> vertex_lines;     // source line of each `v`, in order
    size_t face_count = 0;             // `f` lines
    size_t face_triangles = 0;         // triangles the faces make: n - 2 for n corners
};

// The whole file; throws Error("cannot open/read 'display'").
std::string read_obj_text(const std::string& obj_path, const std::string& display);

// Blanks out inline comments on data lines ("f 1 2 3 # a note", which tinyobj refuses), in
// place and keeping the line breaks, so line numbers stay. Elsewhere a '#' may belong to a
// name ("usemtl Material #4"), so other lines are left alone.
void blank_inline_comments(std::string* text);

// Validates OBJ `text` (shown in messages as `display`). Throws Error "display:LINE: ..." on a
// malformed or truncated line, a non-finite number or an index out of range.
ObjPrescan prescan_obj(std::string_view text, const std::string& display);

// The `mtllib` files `text` names, resolved next to `obj_path` (backslashes, "./" prefixes and
// case differences tolerated): the ones that exist, in order, and the ones that do not, each
// with its line, to be warned about.
struct MaterialLibraries {
    struct Missing {
        int line;
        std::string shown;  // the path as the message shows it
    };
    std::vector<std::string> paths;
    std::vector<Missing> missing;
};
MaterialLibraries find_material_libraries(std::string_view text, const std::string& obj_path,
                                          const std::string& display);

// ---- mtl_materials.cpp -------------------------------------------------------------------

// Maps one MTL material to the device Material (see the mapping table in mtl_materials.cpp),
// textures aside. Appends the features it has no equivalent for, as MTL spells them, to
// `unsupported`; sets *rescaled when Kd + Ks exceeded 1 and both were scaled down.
Material map_mtl_material(const tinyobj::material_t& mtl, std::vector<std::string>* unsupported, bool* rescaled);

// Grey Lambertian (kd 0.5) for faces that name no material.
Material default_material();
constexpr const char* kDefaultMaterialName = "default";

bool is_emissive(const Material& m);

// ---- medium_boundaries.cpp ---------------------------------------------------------------

// Every glass or interface material with different media on its two sides must enclose its
// interior: its triangles form closed surfaces, each edge shared by two of them with opposite
// directions (a consistent winding, so the interior is one side). Throws naming the material
// and the number of open edges; `file` is the scene file that assigned the media.
void check_medium_boundaries(const Scene& scene, const std::string& file);

// ---- mtl_textures.cpp --------------------------------------------------------------------

// Where an MTL's texture reference `name` points, relative to `base_dir` (backslashes, "./"
// prefixes and case differences tolerated); "" if no such file exists.
std::string resolve_texture_path(const std::string& base_dir, const std::string& name);

// Reads each texture image once into Scene::texels and adds one TextureInfo per use. A name is
// looked up in each of `base_dirs` in turn (the MTL's folder, then the OBJ's).
class TextureLoader {
public:
    struct Use {
        int texture = 0;               // 1 + TextureInfo index, 0 = missing or unreadable
        bool has_alpha = false;        // the image has an alpha channel
        bool alpha_has_holes = false;  // ... with some texel below 1/2
    };
    // colour: 8-bit texels are sRGB-encoded colour (else data: heights, normals, masks).
    Use add(Scene& scene, const std::vector<std::string>& base_dirs, const std::string& name,
            const tinyobj::texture_option_t& option, bool colour);

    std::vector<std::string> unreadable;  // references that could not be read, as written

private:
    struct Image {
        size_t offset = 0;
        int width = 0, height = 0, format = 0;
        bool has_alpha = false, has_holes = false;
    };
    std::map<std::string, Image> images_;  // by resolved path and colour/data
};

// Sets m's texture fields from the maps `mtl` names (the mapping table in mtl_textures.cpp).
void attach_textures(Scene& scene, TextureLoader& loader, const std::vector<std::string>& base_dirs,
                     const tinyobj::material_t& mtl, Material* m);

// ---- obj_loader.cpp ----------------------------------------------------------------------

// State shared by the meshes of one scene.
struct MeshLoadContext {
    int default_material = -1;  // index of the shared "default" material once one face needs it
    TextureLoader textures;
};

// Appends the triangles, normals and materials of one OBJ file to `scene` and extends its
// bounds. `referenced_by` names the scene file that lists it (empty for a bare OBJ scene).
void append_obj_mesh(Scene& scene, MeshLoadContext& context, const std::string& obj_path,
                     const std::string& display, const std::string& referenced_by);

// ---- scene_json.cpp ----------------------------------------------------------------------

// Fills `scene` from a JSON scene file (meshes, lights, environment map included).
void load_json_scene(Scene& scene, const std::string& path);

// ---- scene_loader.cpp --------------------------------------------------------------------


// Throws Error("cannot open 'display'[ (referenced by ...)]") unless `path` is a readable file.
void require_readable_file(const std::string& path, const std::string& display,
                           const std::string& referenced_by);

}  // namespace clbdpt::detail
