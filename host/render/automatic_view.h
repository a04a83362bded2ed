// The view a scene without a camera gets. load_scene frames the bounding box from the +z side
// (frame_bounds); once the BVH exists, this checks what that view shows. A model that encloses
// its content (an atrium, a room, a courtyard) shows nothing but an outer wall from there, so
// the camera moves inside, to where it sees the most of the model, as a viewer would.
#pragma once

#include <string>

#include "render/device_scene.h"
#include "scene/scene.h"

namespace clbdpt {

struct AutomaticView {
    CameraDesc camera;
    bool moved_inside = false;
    std::string note;  // one line for the user when the camera moved
};

// `framed`: the camera frame_bounds gave; `bounds`: the scene's; `scene`: its BVH and triangles.
AutomaticView choose_automatic_view(const CameraDesc& framed, const Bounds3& bounds, const DeviceScene& scene);

}  // namespace clbdpt
