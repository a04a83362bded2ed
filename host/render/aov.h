// Debug renders of the first hit (--aov normal|albedo|depth): they prove the BVH traversal end
// to end without any light transport.
#pragma once

#include <string>
#include <vector>

#include "device/opencl.h"
#include "render/device_scene.h"

namespace clbdpt {

// Throws Error for an unknown name.
int parse_aov(const std::string& name);

// One float rgb triple per pixel, row 0 at the top.
std::vector<float> render_aov(DeviceContext& device, const DeviceScene& scene, int aov);

}  // namespace clbdpt
