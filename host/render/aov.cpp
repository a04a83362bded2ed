#include "render/aov.h"

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
    const ProgramBuild& build = device.program("kernels/aov.cl", {});
    const int pixels = scene.camera.width * scene.camera.height;
    std::vector<cl_float4> out(pixels);
    try {
        cl::Context& ctx = device.context();
        auto ro = [&](const void* data, size_t bytes) {
            return cl::Buffer(ctx, CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR, bytes, const_cast<void*>(data));
        };
        cl::Buffer nodes = ro(scene.nodes.data(), sizeof(BvhNode) * scene.nodes.size());
        cl::Buffer tris = ro(scene.triangles.data(), sizeof(Triangle) * scene.triangles.size());
        cl::Buffer infos = ro(scene.infos.data(), sizeof(TriangleInfo) * scene.infos.size());
        cl::Buffer materials = ro(scene.materials.data(), sizeof(Material) * scene.materials.size());
        cl::Buffer result(ctx, CL_MEM_WRITE_ONLY, sizeof(cl_float4) * pixels);
        cl::Kernel kernel(build.program, "render_aov");
        kernel.setArg(0, nodes);
        kernel.setArg(1, tris);
        kernel.setArg(2, infos);
        kernel.setArg(3, materials);
        kernel.setArg(4, scene.camera);
        kernel.setArg(5, 0);
        kernel.setArg(6, pixels);
        kernel.setArg(7, aov);
        kernel.setArg(8, result);
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
