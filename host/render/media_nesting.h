// Whether the media a scene's materials declare agree with the regions their surfaces lie in.
//
// A surface inside a closed medium (a block standing in smoke) must have that medium on both of
// its sides: rays leaving it start in the medium its material names. A scene that gets this
// wrong renders, but its estimators then disagree (a path tracer and a light tracer see
// different media around the same surface), so the mismatch is reported as a warning.
#pragma once

#include <string>
#include <vector>

#include "render/device_scene.h"
#include "scene/scene.h"
#include "util/vec3.h"

namespace clbdpt {

// The medium (1 + index, 0 = vacuum) that a ray from p along the unit direction d starts in:
// the side facing p of the first surface it meets (every medium's boundary is closed), or the
// scene's medium where it meets nothing.
int medium_seen_along(const DeviceScene& ds, int scene_medium, Vec3 p, Vec3 d);

// One warning line per material whose surfaces, probed on both sides at up to 64 of its
// triangles, lie in another medium than the material declares there. Empty for a scene
// without media. Interfaces are the boundaries themselves and are not probed.
std::vector<std::string> check_media_nesting(const Scene& scene, const DeviceScene& ds);

}  // namespace clbdpt
