// One OBJ mesh -> device triangles. The text is validated by prescan_obj first; tinyobj then
// parses and triangulates it (fan for quads, ear clipping beyond, both keeping the winding), and
// each triangle is checked for zero area and traced back to its `f` line for the message.
#include <algorithm>
#include <cmath>
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

// Follows tinyobj's output back to the `f` lines: tinyobj emits a face's triangles together and
// faces in file order, and every triangle of a face uses only that face's corners.
class FaceTracker {
public:
    explicit FaceTracker(const ObjPrescan& scan) : scan_(scan) {}

    // The index of the face triangle (a, b, c) came from, or -1 once the trail is lost.
    long face_of(int a, int b, int c) {
        if (lost_) return -1;
        const long face_count = static_cast<long>(scan_.face_lines.size());
        while (face_ < face_count && !(emitted_ < corners(face_) - 2 && contains(face_, a, b, c))) {
            if (emitted_ == 0) empty_faces_.push_back(face_);
            ++face_;
            emitted_ = 0;
        }
        if (face_ == face_count) {
            lost_ = true;
            return -1;
        }
        ++emitted_;
        return face_;
    }

    // The first face that produced no triangle at all (tinyobj drops polygons whose ear
    // clipping finds no ear, i.e. degenerate ones), or -1.
    long first_empty_face() {
        if (lost_) return -1;
        const long face_count = static_cast<long>(scan_.face_lines.size());
        if (face_ < face_count && emitted_ == 0) empty_faces_.push_back(face_);
        for (long f = face_ + 1; f < face_count; ++f) empty_faces_.push_back(f);
        return empty_faces_.empty() ? -1 : empty_faces_.front();
    }

private:
    long corners(long f) const {
        return static_cast<long>(scan_.face_offsets[f + 1] - scan_.face_offsets[f]);
    }
    bool contains(long f, int a, int b, int c) const {
        auto begin = scan_.face_vertices.begin() + static_cast<long>(scan_.face_offsets[f]);
        auto end = scan_.face_vertices.begin() + static_cast<long>(scan_.face_offsets[f + 1]);
        return std::find(begin, end, a) != end && std::find(begin, end, b) != end &&
               std::find(begin, end, c) != end;
    }

    const ObjPrescan& scan_;
    long face_ = 0;
    long emitted_ = 0;
    bool lost_ = false;
    std::vector<long> empty_faces_;
};

}  // namespace

void append_obj_mesh(Scene& scene, MeshLoadContext& context, const std::string& obj_path,
                     const std::string& display, const std::string& referenced_by) {
    require_readable_file(obj_path, display, referenced_by);
    const ObjPrescan scan = prescan_obj(obj_path, display);
    if (scan.face_lines.empty()) throw Error(display + ": no faces (an OBJ scene needs triangles)");

    tinyobj::ObjReaderConfig config;
    config.triangulate = true;
    config.vertex_color = false;
    tinyobj::ObjReader reader;
    const bool ok = reader.ParseFromFile(obj_path, config);
    if (!ok || !reader.Error().empty()) {
        std::vector<std::string> lines = split_message_lines(reader.Error());
        throw Error(display + ": " + (lines.empty() ? std::string("tinyobj failed to parse the file") : lines[0]));
    }
    for (const std::string& line : split_message_lines(reader.Warning())) {
        // A material file that cannot be read is an error here (tinyobj only warns and falls
        // back to its default material). prescan_obj catches the usual case with a line number.
        if (line.find("Material file [") != std::string::npos || line.find("Failed to load material") != std::string::npos) {
            throw Error(display + ": " + line);
        }
        if (line.find("not found in .mtl") != std::string::npos) {
            scene.warnings.push_back(display + ": " + line + "; its faces use the \"default\" material");
            continue;
        }
        scene.warnings.push_back(display + ": " + line);
    }

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

    const int material_base = static_cast<int>(scene.materials.size());
    for (const tinyobj::material_t& mtl : mtls) {
        scene.materials.push_back(map_mtl_material(mtl, display, &scene.warnings));
        scene.material_names.push_back(mtl.name);
    }

    auto position = [&](int index) {
        return Vec3(attrib.vertices[3 * index], attrib.vertices[3 * index + 1], attrib.vertices[3 * index + 2]);
    };
    auto normal = [&](int index) {
        return Vec3(attrib.normals[3 * index], attrib.normals[3 * index + 1], attrib.normals[3 * index + 2]);
    };

    FaceTracker tracker(scan);
    size_t flat_fallbacks = 0;
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
            const long face = tracker.face_of(vi[0], vi[1], vi[2]);
            const std::string where =
                display + (face >= 0 ? ":" + std::to_string(scan.face_lines[face]) : std::string());

            const Vec3 p[3] = {position(vi[0]), position(vi[1]), position(vi[2])};
            const float doubled_area = length(cross(p[1] - p[0], p[2] - p[0]));
            if (!(doubled_area > 0.0f) || !std::isfinite(doubled_area)) {
                throw Error(where + ": zero-area triangle");
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

            Triangle tri{};
            tri.p0 = point4(p[0]);
            tri.p1 = point4(p[1]);
            tri.p2 = point4(p[2]);
            scene.triangles.push_back(tri);
            scene.infos.push_back(info);
            for (const Vec3& q : p) scene.bounds.extend(q);
        }
    }

    const long empty_face = tracker.first_empty_face();
    if (empty_face >= 0) {
        throw Error(display + ":" + std::to_string(scan.face_lines[empty_face]) +
                    ": zero-area face (no triangle survives triangulation)");
    }
    if (flat_fallbacks > 0) {
        scene.warnings.push_back(display + ": " + std::to_string(flat_fallbacks) +
                                 " triangle(s) have a zero-length vertex normal; they are shaded flat");
    }
}

}  // namespace clbdpt::detail
