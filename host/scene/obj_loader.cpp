// One OBJ mesh -> device triangles. The text is validated by prescan_obj while tinyobj
// parses and triangulates it (fan for quads, ear clipping beyond, both keeping the winding).
// Triangles of zero area, and faces that triangulate to nothing, are dropped and counted.
#include <algorithm>
#include <cctype>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <future>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include <tiny_obj_loader.h>

#include "scene/loader_internal.h"
#include "util/error.h"

namespace clbdpt::detail {
namespace {

std::vector<std::string> split_message_lines(const std::string& text) {
    std::vector<std::string> lines;
    std::istringstream in(text);
    std::string line;
    while (std::getline(in, line)) {
        while (!line.empty() && (line.back() == '\r' || line.back() == ' ' || line.back() == '.')) line.pop_back();
        if (!line.empty()) lines.push_back(line);
    }
    return lines;
}

clbdpt_float4 point4(const Vec3& p) {
    clbdpt_float4 v;
    v.s[0] = p.x;
    v.s[1] = p.y;
    v.s[2] = p.z;
    v.s[3] = 0.0f;
    return v;
}


// tinyobj repeats some warnings once per material or per `usemtl` line ("Both `d` and `Tr`
// parameters defined for \"x\"", "material [ 'x' ] not found in .mtl"): messages that differ
// only in quoted names and numbers are one kind, shown once with a count.
std::string warning_kind(const std::string& message) {
    std::string kind;
    bool in_quotes = false;
    for (char c : message) {
        if (c == '"' || c == '\'') {
            in_quotes = !in_quotes;
            if (in_quotes) kind += "Q";
        } else if (!in_quotes) {
            const bool digit = std::isdigit(static_cast<unsigned char>(c));
            if (!digit) kind += c;
            else if (kind.empty() || kind.back() != '#') kind += '#';  // a number, however long
        }
    }
    return kind;
}

// Adds "display: MESSAGE" once per kind, with "(and N more like it)" where there were more.
void add_collapsed(std::vector<std::string>* warnings, const std::string& display,
                   const std::vector<std::string>& messages) {
    std::vector<std::pair<std::string, size_t>> kinds;  // first message of each kind, count
    std::map<std::string, size_t> index;
    for (const std::string& m : messages) {
        auto [it, added] = index.emplace(warning_kind(m), kinds.size());
        if (added) kinds.push_back({m, 0});
        ++kinds[it->second].second;
    }
    for (const auto& [first, count] : kinds) {
        warnings->push_back(display + ": " + first +
                            (count > 1 ? " (and " + std::to_string(count - 1) + " more like it)" : std::string()));
    }
}

std::string plural(size_t n, const std::string& one, const std::string& many) {
    return std::to_string(n) + " " + (n == 1 ? one : many);
}

}  // namespace

void append_obj_mesh(Scene& scene, MeshLoadContext& context, const std::string& obj_path,
                     const std::string& display, const std::string& referenced_by) {
    require_readable_file(obj_path, display, referenced_by);
    std::string text = read_obj_text(obj_path, display);
    blank_inline_comments(&text);
    const MaterialLibraries libraries = find_material_libraries(text, obj_path, display);

    // tinyobj gets the MTL text from us: find_material_libraries resolved the `mtllib` names
    // (backslashes, case) where tinyobj would look for them verbatim.
    std::string mtl_text;
    for (const std::string& mtl_path : libraries.paths) {
        std::ifstream in(mtl_path, std::ios::binary);
        std::stringstream buffer;
        buffer << in.rdbuf();
        mtl_text += buffer.str() + "\n";
    }
    // Two parsers read the same text: tinyobj, which builds the mesh, and prescan_obj, which
    // checks what tinyobj lets pass and keeps line numbers. They are independent, so tinyobj
    // runs on a second thread (on large files each takes about half the load time). The
    // prescan's verdict comes first: its errors name the line.
    tinyobj::ObjReaderConfig config;
    config.triangulate = true;
    config.vertex_color = false;
    tinyobj::ObjReader reader;
    std::future<bool> parsed =
        std::async(std::launch::async, [&] { return reader.ParseFromString(text, mtl_text, config); });
    ObjPrescan scan;
    try {
        scan = prescan_obj(text, display);
    } catch (...) {
        parsed.wait();
        throw;
    }
    const bool ok = parsed.get();
    if (scan.face_count == 0) throw Error(display + ": no faces (an OBJ scene needs triangles)");
    if (!ok || !reader.Error().empty()) {
        std::vector<std::string> lines = split_message_lines(reader.Error());
        throw Error(display + ": " + (lines.empty() ? std::string("tinyobj failed to parse the file") : lines[0]));
    }
    for (const MaterialLibraries::Missing& missing : libraries.missing) {
        scene.warnings.push_back(display + ":" + std::to_string(missing.line) + ": cannot open '" + missing.shown +
                                 "'; its materials are replaced by the default grey diffuse");
    }
    std::vector<std::string> parser_warnings;
    for (const std::string& line : split_message_lines(reader.Warning())) {
        // Said already, with its line, by the missing-mtllib warning above.
        // Said already (missing MTL), or an artefact of handing tinyobj all MTL text at once (a
        // second `mtllib` line finds the text consumed).
        if (line.find("Material file [") != std::string::npos || line.find("Failed to load material") != std::string::npos ||
            line.find("Material stream in error state") != std::string::npos)
            continue;
        if (line.find("not found in .mtl") != std::string::npos) {
            if (!libraries.missing.empty()) continue;  // the missing file says it all
            parser_warnings.push_back(line + "; its faces use the \"default\" material");
            continue;
        }
        parser_warnings.push_back(line);
    }
    add_collapsed(&scene.warnings, display, parser_warnings);

    const tinyobj::attrib_t& attrib = reader.GetAttrib();
    const std::vector<tinyobj::material_t>& mtls = reader.GetMaterials();
    const size_t vertex_count = attrib.vertices.size() / 3;
    for (size_t i = 0; i < attrib.vertices.size(); ++i) {
        if (!std::isfinite(attrib.vertices[i])) {
            const size_t v = i / 3;
            const int line = v < scan.vertex_lines.size() ? scan.vertex_lines[v] : 0;
            throw Error(display + ":" + std::to_string(line) + ": vertex " + std::to_string(v + 1) + " is not finite");
        }
    }

    // Materials: unsupported features are counted per kind over all materials of the file.
    const int material_base = static_cast<int>(scene.materials.size());
    std::vector<std::string> base_dirs;
    for (const std::string& mtl_path : libraries.paths) base_dirs.push_back(std::filesystem::path(mtl_path).parent_path().string());
    base_dirs.push_back(std::filesystem::path(obj_path).parent_path().string());
    std::map<std::string, size_t> unsupported_count;
    std::vector<std::string> unsupported_order;
    size_t rescaled_count = 0;
    const size_t unreadable_before = context.textures.unreadable.size();
    for (const tinyobj::material_t& mtl : mtls) {
        std::vector<std::string> unsupported;
        bool rescaled = false;
        Material m = map_mtl_material(mtl, &unsupported, &rescaled);
        attach_textures(scene, context.textures, base_dirs, mtl, &m);
        for (const std::string& feature : unsupported) {
            if (unsupported_count[feature]++ == 0) unsupported_order.push_back(feature);
        }
        rescaled_count += rescaled ? 1 : 0;
        scene.materials.push_back(m);
        scene.material_names.push_back(mtl.name);
    }
    if (!unsupported_order.empty()) {
        std::string list;
        for (const std::string& feature : unsupported_order)
            list += (list.empty() ? "" : ", ") + feature + " (" + plural(unsupported_count[feature], "material", "materials") + ")";
        scene.warnings.push_back(display + ": ignoring unsupported MTL features: " + list);
    }
    if (rescaled_count > 0) {
        scene.warnings.push_back(display + ": " + plural(rescaled_count, "material has", "materials have") +
                                 " Kd + Ks above 1; both scaled down to conserve energy");
    }
    const std::vector<std::string>& unreadable = context.textures.unreadable;
    if (unreadable.size() > unreadable_before) {
        scene.warnings.push_back(display + ": " + plural(unreadable.size() - unreadable_before, "texture", "textures") +
                                 " missing or unreadable (first: '" + unreadable[unreadable_before] +
                                 "'); their materials use their constant colours");
    }
    const bool textured = !scene.textures.empty();

    auto position = [&](int index) {
        return Vec3(attrib.vertices[3 * index], attrib.vertices[3 * index + 1], attrib.vertices[3 * index + 2]);
    };
    auto normal = [&](int index) {
        return Vec3(attrib.normals[3 * index], attrib.normals[3 * index + 1], attrib.normals[3 * index + 2]);
    };

    size_t triangle_count = 0;
    for (const tinyobj::shape_t& shape : reader.GetShapes()) triangle_count += shape.mesh.num_face_vertices.size();
    scene.triangles.reserve(scene.triangles.size() + triangle_count);
    scene.infos.reserve(scene.infos.size() + triangle_count);
    if (!attrib.normals.empty()) scene.normals.reserve(scene.normals.size() + triangle_count);

    size_t flat_fallbacks = 0;
    size_t degenerate = 0;
    for (const tinyobj::shape_t& shape : reader.GetShapes()) {
        const tinyobj::mesh_t& mesh = shape.mesh;
        size_t offset = 0;
        for (size_t f = 0; f < mesh.num_face_vertices.size(); ++f) {
            const size_t n = mesh.num_face_vertices[f];
            if (n != 3) throw Error(display + ": tinyobj returned a face with " + std::to_string(n) + " corners");
            const tinyobj::index_t* idx = &mesh.indices[offset];
            offset += n;

            const int vi[3] = {idx[0].vertex_index, idx[1].vertex_index, idx[2].vertex_index};
            for (int k = 0; k < 3; ++k) {
                if (vi[k] < 0 || static_cast<size_t>(vi[k]) >= vertex_count) {
                    throw Error(display + ": face index out of range");
                }
            }

            // Slivers and repeated corners are routine in exported files (pbrt, Embree and
            // Mitsuba drop them too): they cover no area, so dropping them changes no image.
            const Vec3 p[3] = {position(vi[0]), position(vi[1]), position(vi[2])};
            const float doubled_area = length(cross(p[1] - p[0], p[2] - p[0]));
            if (!(doubled_area > 0.0f) || !std::isfinite(doubled_area)) {
                ++degenerate;
                continue;
            }

            int material = mesh.material_ids.empty() ? -1 : mesh.material_ids[f];
            if (material < 0 || static_cast<size_t>(material) >= mtls.size()) {
                if (context.default_material < 0) {
                    context.default_material = static_cast<int>(scene.materials.size());
                    scene.materials.push_back(default_material());
                    scene.material_names.push_back(kDefaultMaterialName);
                }
                material = context.default_material;
            } else {
                material += material_base;
            }

            TriangleInfo info{};
            info.material = material;
            info.light = -1;
            info.normals = -1;
            info.source_index = static_cast<clbdpt_int>(scene.triangles.size());
            if (idx[0].normal_index >= 0 && idx[1].normal_index >= 0 && idx[2].normal_index >= 0) {
                TriangleNormals tn{};
                clbdpt_float4* out[3] = {&tn.n0, &tn.n1, &tn.n2};
                bool usable = true;
                for (int k = 0; k < 3; ++k) {
                    const Vec3 nk = normal(idx[k].normal_index);
                    const float len = length(nk);
                    if (!(len > 0.0f) || !std::isfinite(len)) {
                        usable = false;
                        break;
                    }
                    *out[k] = point4(nk * (1.0f / len));
                }
                if (usable) {
                    info.normals = static_cast<clbdpt_int>(scene.normals.size());
                    scene.normals.push_back(tn);
                } else {
                    ++flat_fallbacks;
                }
            }

            if (textured) {
                // Texture coordinates for every triangle once any material has a texture
                // (earlier meshes' triangles get (0, 0)).
                scene.uvs.resize(scene.triangles.size());
                TriangleUV uv{};
                float* corner[3][2] = {{&uv.u0, &uv.v0}, {&uv.u1, &uv.v1}, {&uv.u2, &uv.v2}};
                for (int k = 0; k < 3; ++k) {
                    const int t = idx[k].texcoord_index;
                    if (t < 0 || static_cast<size_t>(2 * t + 1) >= attrib.texcoords.size()) continue;
                    *corner[k][0] = attrib.texcoords[2 * t];
                    *corner[k][1] = attrib.texcoords[2 * t + 1];
                }
                scene.uvs.push_back(uv);
            }

            Triangle tri{};
            tri.p0 = point4(p[0]);
            tri.p1 = point4(p[1]);
            tri.p2 = point4(p[2]);
            scene.triangles.push_back(tri);
            scene.infos.push_back(info);
            for (const Vec3& q : p) scene.bounds.extend(q);
        }
    }

    // A face of n corners makes n - 2 triangles; tinyobj makes none of a polygon whose ear
    // clipping finds no ear (a degenerate one).
    if (scan.face_triangles > triangle_count) degenerate += scan.face_triangles - triangle_count;
    if (degenerate > 0) {
        scene.warnings.push_back(display + ": dropped " +
                                 plural(degenerate, "degenerate triangle", "degenerate triangles") + " (zero area)");
    }
    if (scene.triangles.empty()) throw Error(display + ": no triangles with a non-zero area");
    if (flat_fallbacks > 0) {
        scene.warnings.push_back(display + ": " + std::to_string(flat_fallbacks) +
                                 " triangle(s) have a zero-length vertex normal; they are shaded flat");
    }
}

}  // namespace clbdpt::detail
