#include "render/aov.h"

#include "render/features.h"
#include "render/scene_buffers.h"
#include "util/error.h"

namespace clbdpt {

int parse_aov(const std::string& name) {
    // Values match AOV_* in cl/kernels/aov.cl.
    if (name == "normal") return 0;
    if (name == "albedo") return 1;
    if (name == "depth") return 2;
    throw Error("unknown AOV '" + name + "' (expected normal, albedo or depth)");
}

std::vector<float> render_aov(DeviceContext& device, const DeviceScene& scene, int aov) {
    // The scene's own feature flags: textures, cut-outs and bump maps show as they render.
    const std::vector<std::string> defines =
        kernel_defines(scene, Integrator::Bdpt, 1, false, SamplerKind::Independent);
    const ProgramBuild& build = device.program("kernels/aov.cl", defines);
    const int pixels = scene.camera.width * scene.camera.height;
    std::vector<cl_float4> out(pixels);
    try {
        cl::Context& ctx = device.context();
        SceneBuffers buffers(ctx, scene);
        cl::Buffer result(ctx, CL_MEM_WRITE_ONLY, sizeof(cl_float4) * pixels);
        cl::Kernel kernel(build.program, "render_aov");
        buffers.set_args(kernel);
        cl_uint arg = SceneBuffers::kSceneArgCount;
        kernel.setArg(arg++, 0);
        kernel.setArg(arg++, pixels);
        kernel.setArg(arg++, aov);
        kernel.setArg(arg++, result);
        device.queue().enqueueNDRangeKernel(kernel, cl::NullRange, cl::NDRange(size_t(pixels)), cl::NullRange);
        device.queue().enqueueReadBuffer(result, CL_TRUE, 0, sizeof(cl_float4) * pixels, out.data());
    } catch (const cl::Error& e) {
        throw Error(std::string("OpenCL: ") + e.what() + ": " + cl_error_name(e.err()) + " while rendering the AOV");
    }
    std::vector<float> rgb(size_t(pixels) * 3);
    for (int i = 0; i < pixels; ++i)
        for (int c = 0; c < 3; ++c) rgb[size_t(i) * 3 + c] = out[i].s[c];
    return rgb;
}

}  // namespace clbdpt
