#include "render/scene_buffers.h"

#include <cstdio>

#include "util/error.h"

namespace clbdpt {

namespace {

// OpenCL cannot make empty buffers: an absent feature gets a one-element placeholder.
template <typename T>
cl::Buffer upload(cl::Context& context, const std::vector<T>& data) {
    if (data.empty()) {
        T zero{};
        return cl::Buffer(context, CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR, sizeof(T), &zero);
    }
    return cl::Buffer(context, CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR, sizeof(T) * data.size(),
                      const_cast<T*>(data.data()));
}

template <typename T>
uint64_t bytes_of(const std::vector<T>& data) {
    return uint64_t(sizeof(T)) * std::max<size_t>(data.size(), 1);
}

std::string gib(uint64_t bytes) {
    char text[32];
    std::snprintf(text, sizeof text, "%.2f GiB", double(bytes) / double(uint64_t(1) << 30));
    return text;
}

}  // namespace

void check_scene_fits_device(const DeviceScene& s, const DeviceEntry& device) {
    const std::pair<const char*, uint64_t> buffers[] = {
        {"BVH nodes", bytes_of(s.nodes)},
        {"triangles", bytes_of(s.triangles)},
        {"triangle materials", bytes_of(s.infos)},
        {"vertex normals", bytes_of(s.normals)},
        {"materials", bytes_of(s.materials)},
        {"lights", bytes_of(s.lights)},
        {"light distribution", bytes_of(s.light_cdf)},
        {"environment map", bytes_of(s.env_texels)},
        {"environment distribution", bytes_of(s.env_distribution)},
        {"texture coordinates", bytes_of(s.uvs)},
        {"textures", bytes_of(s.textures)},
        {"texels", bytes_of(s.texels)},
        {"media", bytes_of(s.media)},
        {"density grids", bytes_of(s.densities)},
    };
    uint64_t total = 0;
    for (const auto& [name, bytes] : buffers) {
        total += bytes;
        if (device.max_alloc > 0 && bytes > device.max_alloc)
            throw Error("the scene's " + std::string(name) + " take " + gib(bytes) + ", more than the " +
                        gib(device.max_alloc) + " device " + device.name +
                        " can allocate at once (CL_DEVICE_MAX_MEM_ALLOC_SIZE)");
    }
    if (device.global_memory > 0 && total > device.global_memory)
        throw Error("the scene takes " + gib(total) + ", more than device " + device.name + "'s " +
                    gib(device.global_memory) + " of memory");
}

SceneBuffers::SceneBuffers(cl::Context& context, const DeviceScene& scene) : scene_(scene) {
    // The triangles go up transposed (TriangleRows): a copy for the upload's moment only.
    buffers_ = {upload(context, scene.nodes),     upload(context, triangle_rows(scene.triangles)),
                upload(context, scene.infos),     upload(context, scene.normals),
                upload(context, scene.materials), upload(context, scene.lights),
                upload(context, scene.light_cdf), upload(context, scene.env_texels),
                upload(context, scene.env_distribution), upload(context, scene.uvs),
                upload(context, scene.textures),  upload(context, scene.texels),
                upload(context, scene.media),
                upload(context, scene.densities)};
}

void SceneBuffers::set_args(cl::Kernel& kernel) const {
    for (size_t i = 0; i < buffers_.size(); ++i) kernel.setArg(cl_uint(i), buffers_[i]);
    kernel.setArg(kCameraArg, scene_.camera);
    kernel.setArg(kCameraArg + 1, scene_.info);
}

}  // namespace clbdpt
