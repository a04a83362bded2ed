// The Sobol sampler's promise: for every pixel and every draw, the first 2^m samples' 2D values
// form a (0,m,2)-net — each elementary interval [a/2^i, (a+1)/2^i) x [b/2^(m-i), ...) holds
// exactly one point — for any power-of-two count, since the index shuffle keeps prefixes
// whole. The independent sampler has no such structure (and is checked not to, so the test
// can fail).
#include <gtest/gtest.h>

#include "device/opencl.h"
#include "render_test_util.h"

namespace clbdpt::test {
namespace {

std::vector<cl_float2> values(const std::vector<std::string>& defines, uint32_t pixel, uint32_t draw, int n) {
    DeviceContext& device = test_device();
    const ProgramBuild& build = device.program("kernels/rng_test.cl", defines);
    cl::Kernel kernel(build.program, "sample_values");
    cl::Buffer out(device.context(), CL_MEM_WRITE_ONLY, sizeof(cl_float2) * n);
    kernel.setArg(0, pixel);
    kernel.setArg(1, uint32_t(3));
    kernel.setArg(2, draw);
    kernel.setArg(3, out);
    device.queue().enqueueNDRangeKernel(kernel, cl::NullRange, cl::NDRange(size_t(n)), cl::NullRange);
    std::vector<cl_float2> host(n);
    device.queue().enqueueReadBuffer(out, CL_TRUE, 0, sizeof(cl_float2) * n, host.data());
    return host;
}

bool is_net(const std::vector<cl_float2>& points, int m) {
    const int n = 1 << m;
    for (int i = 0; i <= m; ++i) {
        const int cols = 1 << i, rows = 1 << (m - i);
        std::vector<int> count(size_t(n), 0);
        for (int k = 0; k < n; ++k) {
            int cx = std::min(int(points[k].s[0] * cols), cols - 1);
            int cy = std::min(int(points[k].s[1] * rows), rows - 1);
            if (++count[size_t(cy) * cols + cx] > 1) return false;
        }
    }
    return true;
}

TEST(Rng, SobolPrefixesAreNets) {
    for (uint32_t pixel : {0u, 17u, 4093u})
        for (uint32_t draw : {0u, 1u, 9u, 40u}) {
            std::vector<cl_float2> v = values({"SAMPLER_SOBOL"}, pixel, draw, 256);
            for (int m = 1; m <= 8; ++m) EXPECT_TRUE(is_net(v, m)) << "pixel " << pixel << " draw " << draw << " m " << m;
            for (const cl_float2& p : v) {
                EXPECT_GE(p.s[0], 0.0f);
                EXPECT_LT(p.s[0], 1.0f);
                EXPECT_GE(p.s[1], 0.0f);
                EXPECT_LT(p.s[1], 1.0f);
            }
        }
}

TEST(Rng, DrawsAndPixelsAreDecorrelated) {
    // Different pixels and draws get different scrambles: their point sets differ.
    std::vector<cl_float2> a = values({"SAMPLER_SOBOL"}, 5, 2, 16), b = values({"SAMPLER_SOBOL"}, 6, 2, 16),
                           c = values({"SAMPLER_SOBOL"}, 5, 3, 16);
    EXPECT_NE(a[0].s[0], b[0].s[0]);
    EXPECT_NE(a[0].s[0], c[0].s[0]);
}

// ZSobol: each pixel's 2^m samples are an aligned block of one image-wide Sobol sequence, and
// so are a 2x2 pixel quad's 4 * 2^m (Morton order): both form nets, for every draw. That is the
// blue-noise property: neighbouring pixels' samples complement each other.
std::vector<cl_float2> zsobol_quad(uint32_t x0, uint32_t y0, int log2_spp, uint32_t draw) {
    DeviceContext& device = test_device();
    const ProgramBuild& build = device.program("kernels/rng_test.cl", {"SAMPLER_ZSOBOL"});
    cl::Kernel kernel(build.program, "zsobol_values");
    const int n = 4 << log2_spp;
    const int base4_digits = 6 + (log2_spp + 1) / 2;  // a 64 x 64 image
    cl::Buffer out(device.context(), CL_MEM_WRITE_ONLY, sizeof(cl_float2) * n);
    kernel.setArg(0, x0);
    kernel.setArg(1, y0);
    kernel.setArg(2, cl_int(log2_spp));
    kernel.setArg(3, cl_int(base4_digits));
    kernel.setArg(4, uint32_t(9));
    kernel.setArg(5, draw);
    kernel.setArg(6, out);
    device.queue().enqueueNDRangeKernel(kernel, cl::NullRange, cl::NDRange(size_t(n)), cl::NullRange);
    std::vector<cl_float2> host(n);
    device.queue().enqueueReadBuffer(out, CL_TRUE, 0, sizeof(cl_float2) * n, host.data());
    return host;
}

TEST(Rng, ZSobolPixelsAndPixelQuadsAreNets) {
    for (int log2_spp : {3, 4})
        for (uint32_t draw : {0u, 1u, 7u}) {
            std::vector<cl_float2> v = zsobol_quad(10, 36, log2_spp, draw);
            const int spp = 1 << log2_spp;
            for (int q = 0; q < 4; ++q) {
                std::vector<cl_float2> pixel(v.begin() + q * spp, v.begin() + (q + 1) * spp);
                EXPECT_TRUE(is_net(pixel, log2_spp)) << "pixel " << q << " draw " << draw << " spp " << spp;
            }
            EXPECT_TRUE(is_net(v, log2_spp + 2)) << "quad, draw " << draw << " spp " << spp;
        }
}

TEST(Rng, IndependentSamplerIsNotANet) {
    // 64 uniform random points form a (0,6,2)-net with negligible probability.
    std::vector<cl_float2> v = values({}, 0, 0, 64);
    EXPECT_FALSE(is_net(v, 6));
}

// rng_draws4 (four draws over four SIMD lanes, what the path tracer and random_walk take their
// draws from) gives exactly rng_next2's two values and rng_next's one at each of its draws, for
// every sampler, at draws whose numbers straddle the table's blocks.
TEST(Rng, FourDrawsAtOnceAreTheSingleDraws) {
    const int n = 64;
    for (const char* sampler : {"SAMPLER_SOBOL", "SAMPLER_ZSOBOL", ""}) {
        std::vector<std::string> defines;
        if (*sampler) defines.push_back(sampler);
        DeviceContext& device = test_device();
        const ProgramBuild& build = device.program("kernels/rng_test.cl", defines);
        for (uint32_t first : {0u, 5u, 30u, 61u}) {
            cl::Kernel kernel(build.program, "draws4_values");
            cl::Buffer out(device.context(), CL_MEM_WRITE_ONLY, sizeof(cl_float2) * 8 * n);
            cl::Buffer next1(device.context(), CL_MEM_WRITE_ONLY, sizeof(cl_float) * 4 * n);
            kernel.setArg(0, uint32_t(1234));
            kernel.setArg(1, uint32_t(7));
            kernel.setArg(2, first);
            kernel.setArg(3, out);
            kernel.setArg(4, next1);
            device.queue().enqueueNDRangeKernel(kernel, cl::NullRange, cl::NDRange(size_t(n)), cl::NullRange);
            std::vector<cl_float2> v(size_t(8) * n);
            std::vector<float> one(size_t(4) * n);
            device.queue().enqueueReadBuffer(out, CL_TRUE, 0, sizeof(cl_float2) * v.size(), v.data());
            device.queue().enqueueReadBuffer(next1, CL_TRUE, 0, sizeof(float) * one.size(), one.data());
            int differing = 0, distinct = 0;
            for (int i = 0; i < n; ++i)
                for (int k = 0; k < 4; ++k) {
                    const cl_float2& single = v[size_t(8) * i + k];
                    const cl_float2& lane = v[size_t(8) * i + 4 + k];
                    differing += single.s[0] != lane.s[0] || single.s[1] != lane.s[1] ||
                                 one[size_t(4) * i + k] != lane.s[0];
                    distinct += k > 0 && lane.s[0] != v[size_t(8) * i + 4].s[0];
                }
            EXPECT_EQ(differing, 0) << "sampler '" << sampler << "' draws " << first << "..";
            EXPECT_GT(distinct, 3 * n / 2) << "the four lanes are four different draws";
        }
    }
}

}  // namespace
}  // namespace clbdpt::test
