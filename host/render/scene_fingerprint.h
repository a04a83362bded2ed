// What a checkpoint's scene must match to be resumed (film/checkpoint.h): a 64-bit hash of the
// scene as the kernels see it. Scene data enters through the device scene, so the meshes, materials, textures, lights, media, camera and film size all
// count, whichever files or command-line overrides they came from; the BVH does not (it is
// derived from the triangles, and its build order may vary between runs).
#pragma once

#include <cstdint>

#include "render/device_scene.h"

namespace clbdpt {

uint64_t scene_fingerprint(const DeviceScene& scene);

}  // namespace clbdpt
