// A scene larger than the device allows is refused before anything is uploaded, naming the
// buffer and the sizes (render/scene_buffers.h).
#include "render/scene_buffers.h"

#include <gtest/gtest.h>

#include "util/error.h"

namespace {

std::string error_of(const clbdpt::DeviceScene& scene, const clbdpt::DeviceEntry& device) {
    try {
        clbdpt::check_scene_fits_device(scene, device);
    } catch (const clbdpt::Error& e) {
        return e.what();
    }
    return "";
}

TEST(SceneBuffers, SceneTooLargeForTheDeviceIsRefusedUpFront) {
    clbdpt::DeviceScene scene;
    scene.triangles.resize(1000);
    scene.texels.resize(100);
    clbdpt::DeviceEntry device;
    device.name = "small-device";
    device.max_alloc = 1 << 20;
    device.global_memory = 1 << 30;
    EXPECT_EQ(error_of(scene, device), "");

    device.max_alloc = sizeof(Triangle) * 999;
    const std::string too_big = error_of(scene, device);
    EXPECT_NE(too_big.find("triangles"), std::string::npos) << too_big;
    EXPECT_NE(too_big.find("small-device"), std::string::npos) << too_big;
    EXPECT_NE(too_big.find("CL_DEVICE_MAX_MEM_ALLOC_SIZE"), std::string::npos) << too_big;

    device.max_alloc = 1 << 20;
    device.global_memory = sizeof(Triangle) * 1000;
    const std::string too_much = error_of(scene, device);
    EXPECT_NE(too_much.find("more than device small-device's"), std::string::npos) << too_much;
}

}  // namespace
