// The JSON scene file: camera, film, meshes, lights, render settings. Strict on purpose: an
// unknown key is usually a typo ("fovy") that would otherwise silently render the wrong image,
// so every key is checked and every message names the file and the key path.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <initializer_list>
#include <optional>
#include <sstream>

#include <nlohmann/json.hpp>

#include "film/image_io.h"
#include "scene/loader_internal.h"
#include "util/error.h"

namespace clbdpt::detail {
namespace {

namespace fs = std::filesystem;
using json = nlohmann::json;

// Largest film side accepted; guards the width * height * 3 buffer sizes against overflow.
constexpr int kMaxFilmSide = 32768;

std::string join_key(const std::string& prefix, const std::string& name) {
    return prefix.empty() ? name : prefix + "." + name;
}

// "file:line:column: what" from nlohmann's byte offset (1-based, the character it stopped at).
std::string describe_parse_error(const std::string& file, const std::string& text, const json::parse_error& e) {
    std::string what = e.what();
    // nlohmann: "[json.exception.parse_error.101] parse error at line 3, column 5: syntax error ..."
    const size_t at = what.find("parse error");
    if (at != std::string::npos) {
        const size_t colon = what.find(": ", at);
        if (colon != std::string::npos) what = what.substr(colon + 2);
    }
    if (e.byte == 0) return file + ": " + what;
    const size_t index = std::min(e.byte - 1, text.size());
    size_t line = 1;
    size_t line_start = 0;
    for (size_t i = 0; i < index; ++i) {
        if (text[i] == '\n') {
            ++line;
            line_start = i + 1;
        }
    }
    const size_t column = index - line_start + 1;
    return file + ":" + std::to_string(line) + ":" + std::to_string(column) + ": " + what;
}

// "[json.exception.out_of_range.406] number overflow ..." -> "number overflow ...".
std::string strip_exception_id(const std::string& what) {
    if (what.rfind("[json.exception.", 0) == 0) {
        const size_t end = what.find("] ");
        if (end != std::string::npos) return what.substr(end + 2);
    }
    return what;
}

// Follows the parser's events to know which key it is reading, so that an error thrown in the
// middle of parsing (number overflow) can still name the key ("camera.eye[2]").
class KeyPathTracker {
public:
    void on_event(json::parse_event_t event, const json& parsed) {
        switch (event) {
            case json::parse_event_t::object_start: frames_.push_back({false, "", 0}); break;
            case json::parse_event_t::array_start: frames_.push_back({true, "", 0}); break;
            case json::parse_event_t::key:
                if (!frames_.empty() && parsed.is_string()) frames_.back().key = parsed.get<std::string>();
                break;
            case json::parse_event_t::object_end:
            case json::parse_event_t::array_end:
                if (!frames_.empty()) frames_.pop_back();
                finished_value();
                break;
            case json::parse_event_t::value: finished_value(); break;
        }
    }

    std::string path() const {
        std::string out;
        for (const Frame& f : frames_) {
            if (f.array) {
                out += "[" + std::to_string(f.index) + "]";
            } else if (!f.key.empty()) {
                out += (out.empty() ? "" : ".") + f.key;
            }
        }
        return out;
    }

private:
    struct Frame {
        bool array;
        std::string key;  // object: the key being read
        size_t index;     // array: the element being read
    };
    void finished_value() {
        if (!frames_.empty() && frames_.back().array) ++frames_.back().index;
    }
    std::vector<Frame> frames_;
};

class SceneJsonReader {
public:
    explicit SceneJsonReader(std::string file) : file_(std::move(file)) {}

    [[noreturn]] void fail(const std::string& key, const std::string& what) const {
        throw Error(file_ + ": \"" + key + "\" " + what);
    }

    void check_keys(const json& object, const std::string& prefix, std::initializer_list<const char*> allowed) const {
        for (auto it = object.begin(); it != object.end(); ++it) {
            bool known = false;
            for (const char* name : allowed) known = known || it.key() == name;
            if (!known) throw Error(file_ + ": unknown key \"" + join_key(prefix, it.key()) + "\"");
        }
    }

    const json& object(const json& value, const std::string& key) const {
        if (!value.is_object()) fail(key, "must be an object");
        return value;
    }

    float number(const json& value, const std::string& key) const {
        if (!value.is_number()) fail(key, "must be a number");
        const float x = value.get<float>();
        if (!std::isfinite(x)) fail(key, "must be finite");
        return x;
    }

    float number_in(const json& value, const std::string& key, float lo, bool lo_open, float hi, bool hi_open,
                    const std::string& range) const {
        const float x = number(value, key);
        const bool ok_lo = lo_open ? x > lo : x >= lo;
        const bool ok_hi = hi_open ? x < hi : x <= hi;
        if (!ok_lo || !ok_hi) fail(key, "must be " + range);
        return x;
    }

    // An integer in [lo, hi]; 64.0 is accepted as 64, 64.5 is not.
    long long integer(const json& value, const std::string& key, long long lo, long long hi) const {
        long long x = 0;
        if (value.is_number_integer()) {
            if (value.is_number_unsigned() && value.get<unsigned long long>() > static_cast<unsigned long long>(hi)) {
                fail(key, "must be an integer from " + std::to_string(lo) + " to " + std::to_string(hi));
            }
            x = value.get<long long>();
        } else if (value.is_number_float()) {
            const double d = value.get<double>();
            if (!std::isfinite(d) || d != std::floor(d) || d < static_cast<double>(lo) || d > static_cast<double>(hi)) {
                fail(key, "must be an integer from " + std::to_string(lo) + " to " + std::to_string(hi));
            }
            x = static_cast<long long>(d);
        } else {
            fail(key, "must be an integer");
        }
        if (x < lo || x > hi) {
            fail(key, "must be an integer from " + std::to_string(lo) + " to " + std::to_string(hi));
        }
        return x;
    }

    Vec3 vec3(const json& value, const std::string& key) const {
        if (!value.is_array() || value.size() != 3) fail(key, "must be an array of 3 numbers");
        Vec3 v;
        for (int i = 0; i < 3; ++i) {
            if (!value[i].is_number()) fail(key, "must be an array of 3 numbers");
            v[i] = value[i].get<float>();
            if (!std::isfinite(v[i])) fail(key, "must be finite");
        }
        return v;
    }

    Vec3 color(const json& value, const std::string& key) const {
        const Vec3 c = vec3(value, key);
        if (c.x < 0 || c.y < 0 || c.z < 0) fail(key, "must not be negative");
        return c;
    }

    Vec3 direction(const json& value, const std::string& key) const {
        const Vec3 d = vec3(value, key);
        if (!(length(d) > 0.0f)) fail(key, "must not be zero");
        return normalize(d);
    }

    std::string string(const json& value, const std::string& key) const {
        if (!value.is_string()) fail(key, "must be a string");
        std::string s = value.get<std::string>();
        if (s.empty()) fail(key, "must not be empty");
        return s;
    }

private:
    std::string file_;
};

// What the "camera" section says; absent fields come from framing the bounds.
struct CameraSection {
    std::optional<Vec3> eye, target, up;
    std::optional<float> fov, lens_radius, focus_distance;
};

CameraSection read_camera(const SceneJsonReader& r, const json& section) {
    r.object(section, "camera");
    r.check_keys(section, "camera", {"eye", "target", "up", "fov", "lens_radius", "focus_distance"});
    CameraSection c;
    if (section.contains("eye")) c.eye = r.vec3(section["eye"], "camera.eye");
    if (section.contains("target")) c.target = r.vec3(section["target"], "camera.target");
    if (section.contains("up")) c.up = r.vec3(section["up"], "camera.up");
    if (section.contains("fov")) {
        c.fov = r.number_in(section["fov"], "camera.fov", 0.0f, true, 180.0f, true,
                            "between 0 and 180 degrees (exclusive)");
    }
    if (section.contains("lens_radius")) {
        c.lens_radius = r.number_in(section["lens_radius"], "camera.lens_radius", 0.0f, false, INFINITY, false,
                                    "zero or positive");
    }
    if (section.contains("focus_distance")) {
        c.focus_distance = r.number_in(section["focus_distance"], "camera.focus_distance", 0.0f, true, INFINITY,
                                       false, "positive");
    }
    return c;
}

LightDesc read_light(const SceneJsonReader& r, const json& value, const std::string& key,
                     const fs::path& scene_dir) {
    r.object(value, key);
    if (!value.contains("type")) r.fail(key + ".type", "is missing");
    const std::string type = r.string(value["type"], key + ".type");
    auto required = [&](const char* name) -> const json& {
        if (!value.contains(name)) r.fail(join_key(key, name), "is missing");
        return value[name];
    };

    LightDesc light;
    if (type == "point") {
        r.check_keys(value, key, {"type", "position", "intensity"});
        light.kind = LightDesc::Kind::Point;
        light.position = r.vec3(required("position"), key + ".position");
        light.color = r.color(required("intensity"), key + ".intensity");
    } else if (type == "spot") {
        r.check_keys(value, key, {"type", "position", "target", "intensity", "cone_angle", "cone_delta"});
        light.kind = LightDesc::Kind::Spot;
        light.position = r.vec3(required("position"), key + ".position");
        light.target = r.vec3(required("target"), key + ".target");
        light.color = r.color(required("intensity"), key + ".intensity");
        if (!(length(light.target - light.position) > 0.0f)) r.fail(key + ".target", "must differ from the position");
        light.direction = normalize(light.target - light.position);
        if (value.contains("cone_angle")) {
            light.cone_angle = r.number_in(value["cone_angle"], key + ".cone_angle", 0.0f, true, 180.0f, false,
                                           "greater than 0 and at most 180 degrees");
        }
        if (value.contains("cone_delta")) {
            light.cone_delta = r.number_in(value["cone_delta"], key + ".cone_delta", 0.0f, false, INFINITY, false,
                                           "zero or positive");
        }
        if (light.cone_delta > light.cone_angle) {
            r.fail(key + ".cone_delta", "must not exceed cone_angle (" + std::to_string(light.cone_angle) + ")");
        }
    } else if (type == "directional") {
        r.check_keys(value, key, {"type", "direction", "radiance"});
        light.kind = LightDesc::Kind::Directional;
        light.direction = r.direction(required("direction"), key + ".direction");
        light.color = r.color(required("radiance"), key + ".radiance");
    } else if (type == "environment") {
        r.check_keys(value, key, {"type", "radiance", "map"});
        light.kind = LightDesc::Kind::Environment;
        if (value.contains("map")) {
            const std::string map = r.string(value["map"], key + ".map");
            light.map_path = fs::absolute(scene_dir / map).lexically_normal().string();
            light.color = value.contains("radiance") ? r.color(value["radiance"], key + ".radiance") : Vec3(1, 1, 1);
        } else {
            light.color = r.color(required("radiance"), key + ".radiance");
        }
    } else {
        r.fail(key + ".type", "must be one of \"point\", \"spot\", \"directional\", \"environment\" (got \"" +
                                  type + "\")");
    }
    return light;
}

// A medium's "density": a grid written out in the scene file,
//   {"resolution": [nx, ny, nz], "values": [nx * ny * nz numbers, x fastest], "bounds": [lo, hi]}
// or one read from an OpenVDB file, {"file": "smoke.vdb", "grid": "density", "bounds": [lo, hi]}
// (bounds optional: the file's own placement); both take "scale", a factor on every value.
std::shared_ptr<const DensityGrid> read_density(const SceneJsonReader& r, const json& value, const std::string& key,
                                                const fs::path& scene_dir, std::vector<std::string>& warnings) {
    r.object(value, key);
    r.check_keys(value, key, {"resolution", "values", "bounds", "file", "grid", "scale"});
    auto grid = std::make_shared<DensityGrid>();
    const bool from_file = value.contains("file");
    std::optional<std::pair<Vec3, Vec3>> bounds;
    if (value.contains("bounds")) {
        const json& b = value["bounds"];
        if (!b.is_array() || b.size() != 2) {
            r.fail(key + ".bounds", "must be [[x, y, z], [x, y, z]], the lowest and highest corners");
        }
        bounds.emplace(r.vec3(b[0], key + ".bounds"), r.vec3(b[1], key + ".bounds"));
        for (int axis = 0; axis < 3; ++axis) {
            if (!(bounds->first[axis] < bounds->second[axis])) {
                r.fail(key + ".bounds", "must have its lowest corner below its highest on every axis");
            }
        }
    }
    if (from_file) {
        if (value.contains("resolution") || value.contains("values")) {
            r.fail(key, "takes either \"file\" or \"resolution\" and \"values\", not both");
        }
        const std::string file =
            fs::absolute(scene_dir / r.string(value["file"], key + ".file")).lexically_normal().string();
        const std::string name = value.contains("grid") ? r.string(value["grid"], key + ".grid") : "density";
        try {
            *grid = read_openvdb_grid(file, name);
        } catch (const Error& e) {
            r.fail(key + ".file", std::string("cannot be used: ") + e.what());
        }
        if (grid->negative_voxels > 0) {
            warnings.push_back(file + ": " + std::to_string(grid->negative_voxels) + " negative voxel(s) of grid \"" +
                               name + "\" read as 0");
        }
        if (bounds) place_grid_in_box(*grid, bounds->first, bounds->second, 1);
    } else {
        if (value.contains("grid")) r.fail(key + ".grid", "names a grid of a \"file\", and there is none");
        if (!value.contains("resolution") || !value.contains("values") || !bounds) {
            r.fail(key, "needs \"file\", or \"resolution\", \"values\" and \"bounds\"");
        }
        const json& res = value["resolution"];
        if (!res.is_array() || res.size() != 3) r.fail(key + ".resolution", "must be an array of 3 integers");
        size_t count = 1;
        for (int axis = 0; axis < 3; ++axis) {
            grid->size[axis] = int(r.integer(res[axis], key + ".resolution", 1, 1024));
            count *= size_t(grid->size[axis]);
        }
        const json& values = value["values"];
        if (!values.is_array() || values.size() != count) {
            r.fail(key + ".values", "must be an array of " + std::to_string(count) + " numbers (the resolution's product)");
        }
        grid->values.reserve(count);
        for (size_t i = 0; i < count; ++i) {
            grid->values.push_back(r.number_in(values[i], key + ".values[" + std::to_string(i) + "]", 0.0f, false,
                                               INFINITY, false, "zero or positive"));
        }
        place_grid_in_box(*grid, bounds->first, bounds->second, 0);
    }
    if (value.contains("scale")) {
        const float scale = r.number_in(value["scale"], key + ".scale", 0.0f, false, INFINITY, false, "zero or positive");
        for (float& v : grid->values) v *= scale;
    }
    return grid;
}

// "media": {"fog": {"sigma_a": [r, g, b], "sigma_s": [r, g, b], "g": 0.3, "density": {...}}, ...}
std::vector<MediumDesc> read_media(const SceneJsonReader& r, const json& section, const fs::path& scene_dir,
                                   std::vector<std::string>& warnings) {
    r.object(section, "media");
    std::vector<MediumDesc> media;
    for (auto it = section.begin(); it != section.end(); ++it) {
        const std::string key = "media." + it.key();
        const json& value = r.object(it.value(), key);
        r.check_keys(value, key, {"sigma_a", "sigma_s", "g", "density"});
        MediumDesc m;
        m.name = it.key();
        if (m.name.empty()) r.fail(key, "needs a name");
        if (value.contains("sigma_a")) m.sigma_a = r.color(value["sigma_a"], key + ".sigma_a");
        if (value.contains("sigma_s")) m.sigma_s = r.color(value["sigma_s"], key + ".sigma_s");
        if (value.contains("g")) m.g = r.number_in(value["g"], key + ".g", -1.0f, true, 1.0f, true, "between -1 and 1 (exclusive)");
        if (value.contains("density")) m.density = read_density(r, value["density"], key + ".density", scene_dir, warnings);
        media.push_back(m);
    }
    return media;
}

// 1 + the index of the medium `name` names (0 for "vacuum").
int medium_reference(const SceneJsonReader& r, const std::vector<MediumDesc>& media, const json& value,
                     const std::string& key) {
    const std::string name = r.string(value, key);
    if (name == "vacuum") return 0;
    for (size_t i = 0; i < media.size(); ++i)
        if (media[i].name == name) return int(i) + 1;
    r.fail(key, "names no medium of \"media\" (got \"" + name + "\")");
}

// "materials": {"MTL name": {"interface": true, "interior": "smoke", "exterior": "fog"}}: the
// media on either side of every material of that name, and whether it is only a boundary
// between media. Both sides default to the scene-wide medium (so a single glass pane, an open
// surface, is fog on both sides in a foggy scene; "vacuum" names no medium).
void apply_material_media(const SceneJsonReader& r, const json* section, Scene& scene) {
    for (Material& m : scene.materials) m.interior_medium = m.exterior_medium = scene.scene_medium;
    if (section) {
        for (auto it = section->begin(); it != section->end(); ++it) {
            const std::string key = "materials." + it.key();
            const json& value = r.object(it.value(), key);
            r.check_keys(value, key, {"interface", "interior", "exterior"});
            bool any = false;
            for (size_t i = 0; i < scene.materials.size(); ++i) {
                if (scene.material_names[i] != it.key()) continue;
                any = true;
                Material& m = scene.materials[i];
                if (value.contains("interface")) {
                    if (!value["interface"].is_boolean()) r.fail(key + ".interface", "must be true or false");
                    if (value["interface"].get<bool>()) {
                        if (is_emissive(m)) r.fail(key + ".interface", "cannot be set on an emissive material (Ke)");
                        m.kind = MATERIAL_INTERFACE;
                    }
                }
                if (value.contains("interior")) m.interior_medium = medium_reference(r, scene.media, value["interior"], key + ".interior");
                if (value.contains("exterior")) m.exterior_medium = medium_reference(r, scene.media, value["exterior"], key + ".exterior");
            }
            if (!any) r.fail(key, "names no material of the meshes");
        }
    }
}

void load_environment_map(Scene& scene, const LightDesc& light, const std::string& shown_path) {
    require_readable_file(light.map_path, shown_path, scene.path);
    EnvironmentMap& env = scene.environment_map;
    env.rgb = read_image_rgb(light.map_path, &env.width, &env.height);
    size_t clamped = 0;
    for (size_t i = 0; i < env.rgb.size(); ++i) {
        if (!std::isfinite(env.rgb[i])) {
            const size_t pixel = i / 3;
            throw Error(shown_path + ": pixel (" + std::to_string(pixel % static_cast<size_t>(env.width)) + "," +
                        std::to_string(pixel / static_cast<size_t>(env.width)) + ") is NaN/Inf");
        }
        if (env.rgb[i] < 0.0f) {
            env.rgb[i] = 0.0f;
            ++clamped;
        }
    }
    if (clamped > 0) {
        scene.warnings.push_back(shown_path + ": " + std::to_string(clamped) +
                                 " negative channel value(s) set to 0");
    }
}

}  // namespace

void load_json_scene(Scene& scene, const std::string& path) {
    require_readable_file(path, path, "");
    std::ifstream in(path, std::ios::binary);
    std::stringstream buffer;
    buffer << in.rdbuf();
    const std::string text = buffer.str();

    json root;
    KeyPathTracker tracker;
    try {
        root = json::parse(text, [&tracker](int, json::parse_event_t event, json& parsed) {
            tracker.on_event(event, parsed);
            return true;
        });
    } catch (const json::parse_error& e) {
        throw Error(describe_parse_error(path, text, e));
    } catch (const json::out_of_range& e) {
        // A number too large for a double (1e999) is the only way JSON can spell infinity.
        throw Error(path + ": \"" + tracker.path() + "\" must be finite (" + strip_exception_id(e.what()) + ")");
    } catch (const json::exception& e) {
        throw Error(path + ": " + strip_exception_id(e.what()));
    }

    const SceneJsonReader r(path);
    const fs::path scene_dir = fs::path(path).parent_path();
    if (!root.is_object()) throw Error(path + ": the top level must be a JSON object");
    r.check_keys(root, "", {"camera", "film", "meshes", "lights", "render", "media", "medium", "materials"});

    // Everything in the file is checked before any mesh is read, so a typo fails fast.
    CameraSection camera;
    if (root.contains("camera")) camera = read_camera(r, root["camera"]);

    if (root.contains("film")) {
        const json& film = r.object(root["film"], "film");
        r.check_keys(film, "film", {"width", "height"});
        if (film.contains("width")) scene.width = static_cast<int>(r.integer(film["width"], "film.width", 1, kMaxFilmSide));
        if (film.contains("height")) {
            scene.height = static_cast<int>(r.integer(film["height"], "film.height", 1, kMaxFilmSide));
        }
    }

    if (root.contains("render")) {
        const json& render = r.object(root["render"], "render");
        r.check_keys(render, "render", {"spp", "max_depth", "seed"});
        if (render.contains("spp")) scene.render.spp = static_cast<int>(r.integer(render["spp"], "render.spp", 1, INT32_MAX));
        if (render.contains("max_depth")) {
            scene.render.max_depth = static_cast<int>(r.integer(render["max_depth"], "render.max_depth", 0, 1024));
        }
        if (render.contains("seed")) {
            scene.render.seed = static_cast<uint32_t>(r.integer(render["seed"], "render.seed", 0, UINT32_MAX));
        }
    }

    if (!root.contains("meshes")) throw Error(path + ": \"meshes\" is missing (a scene needs at least one mesh)");
    const json& meshes = root["meshes"];
    if (!meshes.is_array()) r.fail("meshes", "must be an array of file names");
    if (meshes.empty()) r.fail("meshes", "must name at least one mesh");
    std::vector<std::string> mesh_names;
    for (size_t i = 0; i < meshes.size(); ++i) {
        mesh_names.push_back(r.string(meshes[i], "meshes[" + std::to_string(i) + "]"));
    }

    std::vector<std::string> map_shown_paths;  // per light, the map path as messages show it
    if (root.contains("lights")) {
        const json& lights = root["lights"];
        if (!lights.is_array()) r.fail("lights", "must be an array");
        int environment_count = 0;
        for (size_t i = 0; i < lights.size(); ++i) {
            const std::string key = "lights[" + std::to_string(i) + "]";
            scene.lights.push_back(read_light(r, lights[i], key, scene_dir));
            map_shown_paths.push_back(lights[i].contains("map")
                                          ? (scene_dir / lights[i]["map"].get<std::string>()).lexically_normal().string()
                                          : std::string());
            if (scene.lights.back().kind == LightDesc::Kind::Environment && ++environment_count > 1) {
                r.fail(key, "is a second environment light (only one is allowed)");
            }
        }
    }

    if (root.contains("media")) scene.media = read_media(r, root["media"], scene_dir, scene.warnings);
    if (root.contains("medium")) scene.scene_medium = medium_reference(r, scene.media, root["medium"], "medium");
    if (root.contains("materials")) r.object(root["materials"], "materials");
    if (scene.scene_medium != 0) {
        for (size_t i = 0; i < scene.lights.size(); ++i) {
            const LightDesc::Kind kind = scene.lights[i].kind;
            if (kind == LightDesc::Kind::Environment || kind == LightDesc::Kind::Directional) {
                r.fail("lights[" + std::to_string(i) + "]",
                       "is infinitely far: it cannot shine through the scene-wide \"medium\" (put the medium inside "
                       "a closed mesh of an \"interface\" material instead)");
            }
        }
    }

    MeshLoadContext context;
    for (const std::string& name : mesh_names) {
        const fs::path resolved = scene_dir / name;
        const std::string shown = resolved.lexically_normal().string();
        append_obj_mesh(scene, context, resolved.string(), shown, path);
    }

    for (size_t i = 0; i < scene.lights.size(); ++i) {
        if (!scene.lights[i].map_path.empty()) load_environment_map(scene, scene.lights[i], map_shown_paths[i]);
    }
    apply_material_media(r, root.contains("materials") ? &root["materials"] : nullptr, scene);
    check_medium_boundaries(scene, path);

    // The camera: framed on the bounds, then overridden by whatever the file says.
    const float fov = camera.fov.value_or(CameraDesc{}.fov_degrees);
    scene.camera = frame_bounds(scene.bounds, fov);
    if (camera.eye) scene.camera.eye = *camera.eye;
    if (camera.target) scene.camera.target = *camera.target;
    if (camera.up) scene.camera.up = *camera.up;
    if (camera.lens_radius) scene.camera.lens_radius = *camera.lens_radius;
    scene.camera_is_automatic = !camera.eye && !camera.target;
    const Vec3 view = scene.camera.target - scene.camera.eye;
    if (!(length(view) > 0.0f)) r.fail("camera.target", "must differ from camera.eye");
    if (!(length(scene.camera.up) > 0.0f)) r.fail("camera.up", "must not be zero");
    if (!(length(cross(normalize(view), normalize(scene.camera.up))) > 1e-6f)) {
        r.fail("camera.up", "must not be parallel to the viewing direction");
    }
    scene.camera.focus_distance = camera.focus_distance.value_or(length(view));
}

}  // namespace clbdpt::detail
