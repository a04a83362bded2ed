// The scene as the host holds it after loading: flat triangle arrays in the device layout
// (cl/shared/types.h), materials, the camera and light descriptions from the scene file, and the
// render settings. Loading never half-succeeds: every problem throws clbdpt::Error with a
// one-line message naming the file and line.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "scene/density_grid.h"
#include "shared/types.h"
#include "util/vec3.h"

namespace clbdpt {

struct CameraDesc {
    Vec3 eye{0, 0, 0};
    Vec3 target{0, 0, 1};
    Vec3 up{0, 1, 0};
    float fov_degrees = 39.3f;  // full angle across the shorter image axis (pbrt's convention)
    float lens_radius = 0.0f;
    float focus_distance = 1.0f;
};

// A light from the scene file's "lights" array. Area lights are not here: they come from
// emissive MTL materials (Ke) and are made per triangle by the renderer.
struct LightDesc {
    enum class Kind { Point, Spot, Directional, Environment };
    Kind kind = Kind::Point;
    Vec3 position;            // point, spot
    Vec3 target;              // spot
    Vec3 direction;           // directional: the direction light travels
    Vec3 color;               // point/spot "intensity", directional/environment "radiance"
    float cone_angle = 30.0f; // spot: half angle of the cone, degrees
    float cone_delta = 5.0f;  // spot: width of the falloff band inside the cone, degrees
    std::string map_path;     // environment: lat-long map (absolute path), empty = constant
};

// A lat-long environment map, linear RGB, row 0 = top (+y). Loaded with the scene.
struct EnvironmentMap {
    int width = 0;
    int height = 0;
    std::vector<float> rgb;  // width * height * 3
};

// A participating medium from the scene file's "media" (cl/medium.h): coefficients per scene
// unit, per RGB channel, and the Henyey-Greenstein asymmetry g; with a density grid the
// coefficients are per unit density (the grid's values already times the scene file's "scale").
struct MediumDesc {
    std::string name;
    Vec3 sigma_a;
    Vec3 sigma_s;
    float g = 0.0f;
    std::shared_ptr<const DensityGrid> density;  // null: homogeneous
};

struct RenderSettings {
    int spp = 16;
    int max_depth = 5;
    uint32_t seed = 0;
};

struct Scene {
    std::string path;  // the file it was loaded from
    CameraDesc camera;
    int width = 256;
    int height = 256;
    RenderSettings render;

    std::vector<Triangle> triangles;       // load order until the BVH reorders them
    std::vector<TriangleInfo> infos;       // one per triangle
    std::vector<TriangleNormals> normals;  // referenced by TriangleInfo::normals
    std::vector<Material> materials;
    std::vector<std::string> material_names;  // one per material

    // Textures (only when a material names one): texture coordinates per triangle (same order
    // as triangles; empty when no material has a texture), one TextureInfo per use of an image
    // by a material, and every image's texels in one array (layout in cl/shared/types.h).
    std::vector<TriangleUV> uvs;
    std::vector<TextureInfo> textures;
    std::vector<uint32_t> texels;

    std::vector<LightDesc> lights;
    EnvironmentMap environment_map;  // filled if an environment light names a map

    // Participating media. Materials refer to them as 1 + index (Material.interior_medium,
    // exterior_medium; 0 = vacuum); scene_medium (same convention) fills the space outside every
    // closed mesh, the camera's unless it is inside one.
    std::vector<MediumDesc> media;
    int scene_medium = 0;

    bool camera_is_automatic = true;    // no camera given: framed from the bounds (may be refined
                                        // once the BVH exists, see choose_automatic_view)
    Bounds3 bounds;                     // of all triangles
    std::vector<std::string> warnings;  // one line each (unmappable MTL features, ...)
};

// The camera a bare OBJ gets: from the +z side (OpenGL's convention, which OBJ files follow),
// looking along -z at the centre of `bounds` from far enough that the bounding sphere (radius =
// half the diagonal) just fits in the field of view.
CameraDesc frame_bounds(const Bounds3& bounds, float fov_degrees);

struct LoadOptions {
    // A scene with no light at all gets a uniform white environment (radiance 1), as Mitsuba
    // does, so an unlit model renders as a clay render instead of black.
    bool default_light = true;
};

// Loads a scene file (.json) or a bare .obj (camera framing the bounding box, lit by its
// emissive materials). Throws clbdpt::Error.
Scene load_scene(const std::string& path, const LoadOptions& options = {});

}  // namespace clbdpt
