#include "render/scene_buffers.h"

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

}  // namespace

SceneBuffers::SceneBuffers(cl::Context& context, const DeviceScene& scene) : scene_(scene) {
    buffers_ = {upload(context, scene.nodes),     upload(context, scene.triangles), upload(context, scene.infos),
                upload(context, scene.normals),   upload(context, scene.materials), upload(context, scene.lights),
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
