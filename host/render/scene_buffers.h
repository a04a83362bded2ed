// The device scene uploaded to one OpenCL context, and the kernel arguments every
// light-transport kernel takes first (SCENE_KERNEL_ARGS in cl/scene.h).
#pragma once

#include <vector>

#include "device/opencl.h"
#include "render/device_scene.h"

namespace clbdpt {

// Throws Error, before anything is uploaded, if a buffer of the scene exceeds the device's
// largest allocation or the scene its global memory, naming the buffer and the sizes (an
// upload that fails half-way gives only a driver's error code, or none until a launch).
void check_scene_fits_device(const DeviceScene& scene, const DeviceEntry& device);

class SceneBuffers {
public:
    SceneBuffers(cl::Context& context, const DeviceScene& scene);

    // Sets arguments 0 .. kSceneArgCount - 1.
    void set_args(cl::Kernel& kernel) const;

    static constexpr cl_uint kSceneArgCount = 16;
    static constexpr cl_uint kCameraArg = kSceneArgCount - 2;  // then SceneInfo, the last

private:
    const DeviceScene& scene_;
    std::vector<cl::Buffer> buffers_;
};

}  // namespace clbdpt
