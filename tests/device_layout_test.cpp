// The device compiler must lay out every shared struct exactly as the host compiler does.
// host/device/layout_checks.cpp pins the host side at compile time; this test runs
// cl/kernels/layout_test.cl on the default device and compares its sizeof/alignment/offsetof
// values with the host's, entry by entry, using the one list both sides expand.
#include "device/opencl.h"
#include "kernels/layout_test.cl"  // as C++: only the struct/field list, not the kernel

#include <gtest/gtest.h>

#include <cstddef>
#include <string>
#include <vector>

namespace clbdpt {
namespace {

struct LayoutValue {
    std::string what;
    int value;
};

std::vector<LayoutValue> host_layout() {
    std::vector<LayoutValue> values;
#define HOST_STRUCT(T)                                             \
    values.push_back({"sizeof(" #T ")", static_cast<int>(sizeof(T))}); \
    values.push_back({"alignof(" #T ")", static_cast<int>(alignof(T))});
#define HOST_FIELD(T, f) values.push_back({"offsetof(" #T ", " #f ")", static_cast<int>(offsetof(T, f))});
    CLBDPT_LAYOUT_LIST(HOST_STRUCT, HOST_FIELD)
#undef HOST_STRUCT
#undef HOST_FIELD
    return values;
}

TEST(DeviceLayout, MatchesHost) {
    const std::vector<LayoutValue> host = host_layout();

    DeviceContext device(select_device(""));
    const ProgramBuild& build = device.program("kernels/layout_test.cl", {});
    cl::Kernel kernel(build.program, "report_layout");

    std::vector<cl_int> out(host.size() + 1, -1);
    cl::Buffer buffer(device.context(), CL_MEM_WRITE_ONLY, out.size() * sizeof(cl_int));
    kernel.setArg(0, buffer);
    device.queue().enqueueNDRangeKernel(kernel, cl::NullRange, cl::NDRange(1), cl::NDRange(1));
    device.queue().enqueueReadBuffer(buffer, CL_TRUE, 0, out.size() * sizeof(cl_int), out.data());

    ASSERT_EQ(out[0], static_cast<int>(host.size())) << "device reported a different number of layout values";
    for (size_t i = 0; i < host.size(); ++i) {
        EXPECT_EQ(out[i + 1], host[i].value) << host[i].what << " differs on " << device.entry().name;
    }
}

}  // namespace
}  // namespace clbdpt
