// The table of sample draws (cl/sample_dimensions.h): every decision of a BDPT sample has draws
// of its own, at every max depth, and the values they give are uncorrelated.
//
// The header is included with MAX_DEPTH bound to a variable (for the rest of this file), so one
// build checks every depth.
#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <string>
#include <vector>

#include "device/opencl.h"
#include "render_test_util.h"

namespace {
int g_max_depth = 5;
}
#define MAX_DEPTH g_max_depth
#include "sample_dimensions.h"

namespace clbdpt::test {
namespace {

// One decision: a name and the draws [first, first + count) it reads. (A draw is one 1D or 2D
// value; a decision of several values reads consecutive draws.)
struct Decision {
    std::string name;
    unsigned first = 0, count = 1;
};

// Every decision a sample can make at the current g_max_depth (see the table in the header):
// camera subpaths sample at most max_depth bounces, light subpaths max_depth - 1; t = 1 joins
// s = 1 .. max_depth + 1 light vertices to the lens, s = 1 joins t = 2 .. max_depth + 1 camera
// vertices to a light.
std::vector<Decision> decisions() {
    const int d = g_max_depth;
    std::vector<Decision> v = {{"pixel", SAMPLE_DRAW_PIXEL},
                               {"lens", SAMPLE_DRAW_LENS},
                               {"trace light subpath", SAMPLE_DRAW_TRACE_LIGHT_SUBPATH},
                               {"light and its point", SAMPLE_DRAW_LIGHT_POSITION},
                               {"light direction", SAMPLE_DRAW_LIGHT_DIRECTION}};
    for (int k = 0; k < d; ++k)
        v.push_back({"camera bounce " + std::to_string(k), sample_draw_camera_bounce(k), SAMPLE_DRAWS_PER_BOUNCE});
    for (int k = 0; k + 1 < d; ++k)
        v.push_back({"light bounce " + std::to_string(k), sample_draw_light_bounce(k), SAMPLE_DRAWS_PER_BOUNCE});
    for (int s = 1; s <= d + 1; ++s) v.push_back({"lens for s=" + std::to_string(s), sample_draw_lens_connection(s)});
    for (int t = 2; t <= d + 1; ++t)
        v.push_back({"light for t=" + std::to_string(t), sample_draw_light_connection(t), SAMPLE_DRAWS_PER_LIGHT_CONNECTION});
    return v;
}

// The first pair of decisions that share a draw, or "" if none does; also fails on a draw past
// `count` (the kernels' vectors end there).
std::string first_overlap(const std::vector<Decision>& ds, unsigned count) {
    std::map<unsigned, std::string> owner;
    for (const Decision& d : ds)
        for (unsigned k = d.first; k < d.first + d.count; ++k) {
            if (k >= count) return d.name + " reads draw " + std::to_string(k) + " past the end";
            auto [it, fresh] = owner.emplace(k, d.name);
            if (!fresh) return it->second + " and " + d.name + " share draw " + std::to_string(k);
        }
    return "";
}

// The layout before the table (render.cl's hand arithmetic, in the units of the independent
// sampler that was the default, where a 2D value took two dimensions): the camera subpath
// 2 + 2 per vertex, then connection (s, t) at 2 + 2 (max_depth + 2) + 2 (s (max_depth + 3) + t),
// s = 1 reading three dimensions (light choice, 2D point), t = 1 two (lens point).
std::vector<Decision> old_connection_layout() {
    const int d = g_max_depth;
    const unsigned base = 2 + 2 * (d + 2);
    std::vector<Decision> v;
    for (int s = 1; s <= d + 1; ++s) v.push_back({"lens for s=" + std::to_string(s), base + 2u * (s * (d + 3) + 1), 2});
    for (int t = 2; t <= d + 1; ++t) v.push_back({"light for t=" + std::to_string(t), base + 2u * (d + 3 + t), 3});
    return v;
}

TEST(SampleDimensions, EveryDecisionHasItsOwnDraws) {
    for (g_max_depth = 0; g_max_depth <= 16; ++g_max_depth)
        EXPECT_EQ(first_overlap(decisions(), SAMPLE_DRAW_COUNT), "") << "max depth " << g_max_depth;
    g_max_depth = 5;
}

TEST(SampleDimensions, TheOldLayoutFailsTheCheck) {
    // What the table replaced: neighbouring s = 1 connections shared a random number.
    // (At max depth 1 there is one s = 1 connection, t = 2, so nothing to collide with.)
    for (g_max_depth = 2; g_max_depth <= 8; ++g_max_depth)
        EXPECT_NE(first_overlap(old_connection_layout(), 1u << 20), "") << "max depth " << g_max_depth;
    g_max_depth = 5;
}

// Pearson correlation of two value sequences.
double correlation(const std::vector<double>& a, const std::vector<double>& b) {
    const double n = double(a.size());
    double ma = 0, mb = 0;
    for (size_t i = 0; i < a.size(); ++i) ma += a[i] / n, mb += b[i] / n;
    double sab = 0, saa = 0, sbb = 0;
    for (size_t i = 0; i < a.size(); ++i) {
        sab += (a[i] - ma) * (b[i] - mb);
        saa += (a[i] - ma) * (a[i] - ma);
        sbb += (b[i] - mb) * (b[i] - mb);
    }
    return sab / std::sqrt(saa * sbb);
}

// Statistical: over 1024 samples of one pixel, the values of any two decisions (each component
// of each draw they read) are uncorrelated. The limit is 8 standard errors of a correlation of
// independent variables, 8 / sqrt(n) = 0.25: independent numbers stay within 3.7 SE over the
// ~3200 pairs, but the padded Sobol sampler's hash-based (not fully random) Owen scrambles
// spread pairwise correlations 1.26x wider (measured: worst 5.8 SE; a stronger-looking hash,
// Vegdahl's LK variant, spread them further). A layout that gives two decisions one random
// number has r = 1 there, which the same check catches (the last part: one draw read twice).
void expect_uncorrelated(SamplerKind sampler) {
    constexpr int kSamples = 1024;
    g_max_depth = 5;
    const unsigned draws = SAMPLE_DRAW_COUNT;
    DeviceContext& device = test_device();
    std::vector<std::string> defines = {"MAX_DEPTH=5"};
    if (sampler == SamplerKind::Sobol) defines.push_back("SAMPLER_SOBOL");
    const ProgramBuild& build = device.program("kernels/sample_dimensions_test.cl", defines);
    cl::Kernel kernel(build.program, "sample_vector");
    const size_t floats = size_t(kSamples) * draws * 2;
    cl::Buffer out(device.context(), CL_MEM_WRITE_ONLY, sizeof(float) * floats);
    kernel.setArg(0, cl_uint(77));
    kernel.setArg(1, cl_uint(5));
    kernel.setArg(2, out);
    device.queue().enqueueNDRangeKernel(kernel, cl::NullRange, cl::NDRange(kSamples), cl::NullRange);
    std::vector<float> v(floats);
    device.queue().enqueueReadBuffer(out, CL_TRUE, 0, sizeof(float) * floats, v.data());

    auto component = [&](unsigned draw, int c) {
        std::vector<double> x(kSamples);
        for (int i = 0; i < kSamples; ++i) x[size_t(i)] = v[(size_t(i) * draws + draw) * 2 + size_t(c)];
        return x;
    };
    struct Variable {
        std::string name;
        std::vector<double> values;
    };
    std::vector<Variable> vars;
    for (const Decision& d : decisions())
        for (unsigned k = d.first; k < d.first + d.count; ++k)
            for (int c = 0; c < 2; ++c)
                vars.push_back({d.name + " draw " + std::to_string(k) + "." + std::to_string(c), component(k, c)});
    const double limit = 8.0 / std::sqrt(double(kSamples));
    double worst = 0;
    for (size_t a = 0; a < vars.size(); ++a)
        for (size_t b = a + 1; b < vars.size(); ++b) {
            const double r = correlation(vars[a].values, vars[b].values);
            worst = std::max(worst, std::abs(r));
            EXPECT_LT(std::abs(r), limit) << sampler_name(sampler) << ": " << vars[a].name << " vs " << vars[b].name;
        }
    std::printf("[ stat ] %s: worst |r| %.4f over %zu variables (limit %.4f)\n", sampler_name(sampler), worst,
                vars.size(), limit);
    // The check can fail: one draw read by two decisions.
    EXPECT_GT(correlation(component(SAMPLE_DRAW_LENS, 0), component(SAMPLE_DRAW_LENS, 0)), 1.0 - 1e-9);
}

TEST(SampleDimensions, DecisionsAreUncorrelatedSobol) { expect_uncorrelated(SamplerKind::Sobol); }
TEST(SampleDimensions, DecisionsAreUncorrelatedIndependent) { expect_uncorrelated(SamplerKind::Independent); }

}  // namespace
}  // namespace clbdpt::test
