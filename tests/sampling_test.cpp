// cl/sampling.h through cl/kernels/sampling_test.cl: each warp puts its points where its density
// says (chi-square over cells of equal probability under the claimed density, 2^18 samples,
// significance kChiSquareSignificance), stays inside its domain, and reports that density; and
// find_interval returns the interval holding u, never one of zero width.
// Unit lengths and domain bounds hold to 1e-5 / 1e-6 (float sqrt, cos, sin of values of order 1:
// a few ulps); densities equal the closed forms to 1e-5 relative (one or two float operations).
#include <gtest/gtest.h>

#include <cstdint>
#include <cstring>
#include <limits>
#include <random>

#include "kernel_test_util.h"
#include "render/device_scene.h"

namespace clbdpt::test {
namespace {

enum Warp { kDisk = 0, kCosineHemisphere = 1, kSphere = 2, kCone = 3, kTriangle = 4, kHenyeyGreenstein = 5 };

std::vector<cl_float4> warp(Warp w, float cos_max, size_t n, uint32_t seed) {
    cl::Kernel k = test_kernel("kernels/sampling_test.cl", {}, "warp_test");
    cl::Buffer out = output_buffer<cl_float4>(n);
    k.setArg(0, cl_int(w));
    k.setArg(1, cos_max);
    k.setArg(2, cl_uint(seed));
    k.setArg(3, out);
    launch(k, n);
    return download<cl_float4>(out, n);
}

// The float whose bits are b.
float float_from_bits(uint32_t b) {
    float f;
    std::memcpy(&f, &b, sizeof f);
    return f;
}

constexpr size_t kSamples = 1 << 18;
constexpr int kRadial = 10, kAngular = 20;

// Cells (a, phi) with a in [0, 1) the radial coordinate in which the density is uniform.
int cell(double a, double x, double y) {
    double phi = std::atan2(y, x);
    if (phi < 0) phi += 2 * kPi;
    int i = std::clamp(int(a * kRadial), 0, kRadial - 1);
    int j = std::clamp(int(phi / (2 * kPi) * kAngular), 0, kAngular - 1);
    return i * kAngular + j;
}

void expect_uniform(const std::vector<double>& observed, const char* what) {
    std::vector<double> expected(observed.size(), double(kSamples) / double(observed.size()));
    ChiSquare chi = chi_square(observed, expected);
    EXPECT_GT(chi.p_value, kChiSquareSignificance) << what << ": chi2 " << chi.statistic << " dof " << chi.dof
                                                   << ", worst " << chi.worst;
}

// unit_circle_turns and unit_circle_octant (cl/geometry.h), the renderer's only sine and cosine
// of sampled angles, against double precision on a grid of 2^16 + 1 turns that includes every
// quarter and eighth turn exactly (where the reduction switches quadrant), their float
// neighbours, and the octant's ends. Measured worst: 9.6e-8 (the turns), 7.2e-8 (the octant),
// 7.4e-8 off the unit circle; the bound 2e-7 is 1.7 ulp of 1 (a wrong quadrant errs by 1).
TEST(Sampling, UnitCircleMatchesDoublePrecision) {
    std::vector<float> u, a;
    const int n = 1 << 16;
    for (int i = 0; i <= n; ++i) u.push_back(float(i) / float(n));
    for (int k = 0; k <= 8; ++k) {
        const float eighth = float(k) / 8.0f;
        u.push_back(std::nextafter(eighth, 0.0f));
        if (k < 8) u.push_back(std::nextafter(eighth, 1.0f));
    }
    const float octant = float(kPi / 4);
    for (size_t i = 0; i < u.size(); ++i) a.push_back(octant * (2.0f * float(i) / float(u.size() - 1) - 1.0f));
    a.back() = std::nextafter(octant, 1.0f);  // just past pi/4, as rounding can give
    cl::Kernel k = test_kernel("kernels/sampling_test.cl", {}, "unit_circle_test");
    cl::Buffer ub = upload(u), ab = upload(a);
    cl::Buffer out = output_buffer<cl_float4>(u.size());
    k.setArg(0, ub);
    k.setArg(1, ab);
    k.setArg(2, out);
    launch(k, u.size());
    std::vector<cl_float4> r = download<cl_float4>(out, u.size());
    double worst_turns = 0, worst_octant = 0, worst_norm = 0;
    for (size_t i = 0; i < u.size(); ++i) {
        const double phi = 2 * kPi * double(u[i]);
        worst_turns = std::max({worst_turns, std::abs(r[i].s[0] - std::cos(phi)), std::abs(r[i].s[1] - std::sin(phi))});
        worst_octant = std::max({worst_octant, std::abs(r[i].s[2] - std::cos(double(a[i]))),
                                 std::abs(r[i].s[3] - std::sin(double(a[i])))});
        for (int c : {0, 2}) {
            const double norm = std::hypot(double(r[i].s[c]), double(r[i].s[c + 1]));
            worst_norm = std::max(worst_norm, std::abs(norm - 1));
        }
    }
    EXPECT_LE(worst_turns, 2e-7) << "worst |error| of the turns";
    EXPECT_LE(worst_octant, 2e-7) << "worst |error| in the octant";
    EXPECT_LE(worst_norm, 2e-7) << "worst distance from the unit circle";
}

// atan2_turns and acos_half_turns (cl/geometry.h), which map directions to environment-map
// coordinates, against double precision: points on the unit circle every 2^-16 turn plus the
// axes, the diagonals and their float neighbours (where the reductions switch branch), off-circle
// points of other lengths, and cosines in [-1, 1] on a grid of 2^17 steps plus the ends and the
// neighbours of +-0.5 (the branch point). Measured worst: 6.7e-8 (atan2_turns), 8.5e-8
// (acos_half_turns); the bound 2e-7 is 3.4 ulp of 0.5 (a wrong branch or octant errs by 0.1 or
// more), and far below an environment texel (1e-4 of a turn for a map 10 000 texels wide).
TEST(Sampling, InverseTrigMatchesDoublePrecision) {
    std::vector<cl_float4> in;
    const int n = 1 << 16;
    for (int i = 0; i < n; ++i) {
        const double phi = 2 * kPi * double(i) / n;
        const float c = float(2.0 * i / n - 1.0);
        in.push_back({{float(std::cos(phi)), float(std::sin(phi)), c, 0}});
        in.push_back({{float(3.5 * std::cos(phi)), float(3.5 * std::sin(phi)), float(2.0 * (i + 0.5) / n - 1.0), 0}});
    }
    for (float x : {0.0f, -0.0f, 1.0f, -1.0f, 1e-30f, -1e-30f, 0.5f, -0.5f}) {
        for (float y : {0.0f, 1.0f, -1.0f, 1e-30f, -1e-30f, 0.5f, -0.5f, std::nextafter(0.5f, 1.0f),
                        std::nextafter(0.5f, 0.0f)})
            in.push_back({{x, y, x, 0}});
    }
    for (float c : {1.0f, -1.0f, std::nextafter(1.0f, 0.0f), std::nextafter(-1.0f, 0.0f)}) in.push_back({{1, 0, c, 0}});
    std::vector<cl_float2> r = map_kernel<cl_float2>("kernels/sampling_test.cl", "inverse_trig_test", in);
    double worst_atan2 = 0, worst_acos = 0;
    for (size_t i = 0; i < in.size(); ++i) {
        const double x = in[i].s[0], y = in[i].s[1], c = in[i].s[2];
        double turns = x == 0 && y == 0 ? 0.0 : std::atan2(y, x) / (2 * kPi);
        if (turns < 0) turns += 1;
        // Angles a rounding away from a full turn may come out as 0 or 1.
        double e = std::min(std::abs(r[i].s[0] - turns), std::abs(std::abs(r[i].s[0] - turns) - 1));
        worst_atan2 = std::max(worst_atan2, e);
        worst_acos = std::max(worst_acos, std::abs(r[i].s[1] - std::acos(c) / kPi));
        ASSERT_TRUE(r[i].s[0] >= 0 && r[i].s[0] <= 1) << "atan2_turns(" << y << ", " << x << ") = " << r[i].s[0];
        ASSERT_TRUE(r[i].s[1] >= 0 && r[i].s[1] <= 1) << "acos_half_turns(" << c << ") = " << r[i].s[1];
    }
    EXPECT_LE(worst_atan2, 2e-7) << "worst |error| of atan2_turns";
    EXPECT_LE(worst_acos, 2e-7) << "worst |error| of acos_half_turns";
}

// log_of_normal (cl/geometry.h), the optical depths' logarithm, against double precision over
// the normal floats: every 4096th bit pattern from the smallest normal to the largest float,
// plus 1, the floats next to 1 and to sqrt(1/2) (where the mantissa's reduction switches
// exponent) and 2^-24 (the least 1 - u of a 24-bit draw); and sample_unit_exponential at the
// draws' ends. Measured worst relative error 8.1e-8 over every normal float (a host copy of the
// function); the bound 1.5e-7 is under 1.3 ulp (a wrong exponent errs by ln 2, a wrong
// coefficient by 1e-5 or more).
TEST(Sampling, LogOfNormalMatchesDoublePrecision) {
    std::vector<float> x;
    for (uint64_t b = 0x00800000u; b <= 0x7f7fffffu; b += 4096) x.push_back(float_from_bits(uint32_t(b)));
    const float root_half = float(std::sqrt(0.5));
    for (float v : {1.0f, std::nextafter(1.0f, 0.0f), std::nextafter(1.0f, 2.0f), root_half,
                    std::nextafter(root_half, 0.0f), std::nextafter(root_half, 1.0f), std::ldexp(1.0f, -24),
                    std::numeric_limits<float>::min(), std::numeric_limits<float>::max()})
        x.push_back(v);
    const float last_draw = 1.0f - std::ldexp(1.0f, -24);
    std::vector<float> u(x.size(), 0.5f);
    u[0] = 0.0f;
    u[1] = last_draw;
    cl::Kernel k = test_kernel("kernels/sampling_test.cl", {}, "log_test");
    cl::Buffer xb = upload(x), ub = upload(u);
    cl::Buffer out = output_buffer<cl_float2>(x.size());
    k.setArg(0, xb);
    k.setArg(1, ub);
    k.setArg(2, out);
    launch(k, x.size());
    std::vector<cl_float2> r = download<cl_float2>(out, x.size());
    double worst = 0;
    float worst_x = 0;
    for (size_t i = 0; i < x.size(); ++i) {
        const double expected = std::log(double(x[i]));
        const double e = expected == 0 ? std::abs(double(r[i].s[0])) : std::abs(r[i].s[0] - expected) / std::abs(expected);
        if (e > worst) worst = e, worst_x = x[i];
    }
    EXPECT_LE(worst, 1.5e-7) << "worst relative error of log_of_normal, at x = " << worst_x;
    EXPECT_EQ(r[0].s[1], 0.0f) << "sample_unit_exponential(0)";
    EXPECT_NEAR(r[1].s[1], 24 * std::log(2.0), 24 * std::log(2.0) * 1.5e-7) << "sample_unit_exponential(1 - 2^-24)";
    EXPECT_NEAR(r[2].s[1], std::log(2.0), std::log(2.0) * 1.5e-7) << "sample_unit_exponential(1/2)";
}

// exp_of_nonpositive (cl/geometry.h), the transmittances' exp, against double precision: every
// 256th float bit pattern in [-87, 0] (its three channels take x, x / 2 and x / 4), the ends
// of its range and of reduction intervals, and what it maps to 0 or passes on. Measured worst
// relative error 8.0e-8 (at -6.57); the bound 1.2e-7 is about 1 ulp (a wrong exponent errs by a
// factor 2; with the r^4 coefficient off by 1e-5 the test fails).
TEST(Sampling, ExpOfNonpositiveMatchesDoublePrecision) {
    std::vector<float> x;
    // Negative floats: bits 0x80000000 (-0) upwards grow in magnitude up to -87.
    for (uint64_t b = 0x80000000u; float_from_bits(uint32_t(b)) >= -87.0f; b += 256)
        x.push_back(float_from_bits(uint32_t(b)));
    const float half_ln2 = float(0.5 * std::log(2.0));
    for (float v : {0.0f, -87.0f, -87.29f, -half_ln2, std::nextafter(-half_ln2, 0.0f), std::nextafter(-half_ln2, -1.0f),
                    -3 * half_ln2, std::nextafter(-3 * half_ln2, 0.0f), -1e-30f})
        x.push_back(v);
    const size_t checked = x.size();
    const float nan = std::numeric_limits<float>::quiet_NaN();
    for (float v : {-87.31f, -100.0f, -std::numeric_limits<float>::infinity(), nan}) x.push_back(v);
    std::vector<cl_float4> r = map_kernel<cl_float4>("kernels/sampling_test.cl", "exp_test", x);
    double worst = 0;
    float worst_x = 0;
    for (size_t i = 0; i < checked; ++i)
        for (int c = 0; c < 3; ++c) {
            const float arg = c == 0 ? x[i] : (c == 1 ? 0.5f * x[i] : 0.25f * x[i]);
            const double expected = std::exp(double(arg));
            const double e = std::abs(r[i].s[c] - expected) / expected;
            if (e > worst) worst = e, worst_x = arg;
        }
    EXPECT_LE(worst, 1.2e-7) << "worst relative error of exp_of_nonpositive, at x = " << worst_x;
    for (size_t i = 0; i < checked; ++i) {
        if (x[i] == 0.0f) {
            EXPECT_EQ(r[i].s[0], 1.0f) << "exp(" << x[i] << ")";
        }
    }
    for (size_t i = checked; i + 1 < x.size(); ++i) EXPECT_EQ(r[i].s[0], 0.0f) << "exp(" << x[i] << ")";
    EXPECT_TRUE(std::isnan(r.back().s[0])) << "exp(NaN)";
}

// Concentric disk: area-preserving, so r^2 and phi are uniform.
TEST(Sampling, ConcentricDiskIsUniform) {
    std::vector<cl_float4> s = warp(kDisk, 0, kSamples, 1);
    std::vector<double> obs(kRadial * kAngular, 0.0);
    for (const cl_float4& p : s) {
        double r2 = double(p.s[0]) * p.s[0] + double(p.s[1]) * p.s[1];
        ASSERT_LE(r2, 1 + 1e-6);
        obs[cell(r2, p.s[0], p.s[1])] += 1;
    }
    expect_uniform(obs, "concentric disk");
}

// Cosine hemisphere: density cos(theta)/pi, so P(cos theta < c) = c^2: cos^2 and phi uniform.
TEST(Sampling, CosineHemisphereFollowsCosine) {
    std::vector<cl_float4> s = warp(kCosineHemisphere, 0, kSamples, 2);
    std::vector<double> obs(kRadial * kAngular, 0.0);
    for (const cl_float4& p : s) {
        D3 w = d3(p);
        ASSERT_NEAR(length(w), 1.0, 1e-5);
        ASSERT_GE(w.z, 0.0);
        // Density as reported, to float rounding.
        ASSERT_LE(rel_diff(p.s[3], w.z / kPi, 1e-7), 1e-5);
        obs[cell(w.z * w.z, w.x, w.y)] += 1;
    }
    expect_uniform(obs, "cosine hemisphere");
}

TEST(Sampling, UniformSphereIsUniform) {
    std::vector<cl_float4> s = warp(kSphere, 0, kSamples, 3);
    std::vector<double> obs(kRadial * kAngular, 0.0);
    for (const cl_float4& p : s) {
        D3 w = d3(p);
        ASSERT_NEAR(length(w), 1.0, 1e-5);
        ASSERT_LE(rel_diff(p.s[3], 1 / (4 * kPi)), 1e-6);
        obs[cell(0.5 * (1 - w.z), w.x, w.y)] += 1;
    }
    expect_uniform(obs, "uniform sphere");
}

// Uniform cone: cos theta uniform in [cos_max, 1], density 1 / (2 pi (1 - cos_max)).
TEST(Sampling, UniformConeIsUniformInsideTheCone) {
    for (double degrees : {2.0, 25.0, 90.0, 150.0}) {
        float cos_max = float(std::cos(degrees * kPi / 180));
        std::vector<cl_float4> s = warp(kCone, cos_max, kSamples, 4 + uint32_t(degrees));
        std::vector<double> obs(kRadial * kAngular, 0.0);
        for (const cl_float4& p : s) {
            D3 w = d3(p);
            ASSERT_NEAR(length(w), 1.0, 1e-5);
            // Inside the cone, up to the float rounding of cos theta.
            ASSERT_GE(w.z, double(cos_max) - 1e-6) << degrees;
            ASSERT_LE(rel_diff(p.s[3], 1 / (2 * kPi * (1 - double(cos_max)))), 1e-5) << degrees;
            obs[cell((1 - w.z) / (1 - double(cos_max)), w.x, w.y)] += 1;
        }
        std::string what = "cone " + std::to_string(degrees);
        expect_uniform(obs, what.c_str());
    }
}

// Henyey-Greenstein (cl/phase.h): cos theta from straight on and the azimuth in a 10 x 20 grid
// against the distribution's exact CDF, F(mu) = (1 - g^2) / (2 g) ((1 + g^2 - 2 g mu)^-1/2 -
// 1 / (1 + g)); the density sampling returns is phase_hg's value, and integrates to 1.
TEST(Sampling, HenyeyGreensteinFollowsItsDensity) {
    for (float g : {0.0f, 0.3f, -0.5f, 0.9f}) {
        auto cdf = [g](double mu) {
            if (g == 0.0f) return 0.5 * (mu + 1);
            double gg = g;
            return (1 - gg * gg) / (2 * gg) * (1 / std::sqrt(1 + gg * gg - 2 * gg * mu) - 1 / (1 + gg));
        };
        std::vector<cl_float4> s = warp(kHenyeyGreenstein, g, kSamples, 7 + uint32_t(100 * (g + 1)));
        std::vector<double> obs(kRadial * kAngular, 0.0), expected(kRadial * kAngular, 0.0);
        for (int i = 0; i < kRadial; ++i) {
            double mass = cdf(-1 + 2.0 * (i + 1) / kRadial) - cdf(-1 + 2.0 * i / kRadial);
            for (int j = 0; j < kAngular; ++j) expected[i * kAngular + j] = double(kSamples) * mass / kAngular;
        }
        double pdf_over_density_sum = 0, inverse_pdf_squares = 0;
        for (const cl_float4& p : s) {
            D3 w = d3(p);
            ASSERT_NEAR(length(w), 1.0, 1e-5);
            ASSERT_GT(p.s[3], 0.0f) << "g " << g << ": the density returned differs from phase_hg";
            pdf_over_density_sum += 1.0 / p.s[3];
            inverse_pdf_squares += 1.0 / (double(p.s[3]) * p.s[3]);
            obs[cell((w.z + 1) / 2, w.x, w.y)] += 1;
        }
        ChiSquare chi = chi_square(obs, expected);
        EXPECT_GT(chi.p_value, kChiSquareSignificance) << "g " << g << ": chi2 " << chi.statistic << ", worst " << chi.worst;
        // 1 / pdf averages to 4 pi, the sphere's area: within 5 standard errors of the samples'
        // own spread.
        const double mean = pdf_over_density_sum / double(kSamples);
        const double se = std::sqrt(std::max(0.0, inverse_pdf_squares / double(kSamples) - mean * mean) / double(kSamples));
        EXPECT_LE(std::fabs(mean - 4 * kPi), 5 * se + 1e-6) << "g " << g << ": E[1/pdf] " << mean << " +- " << se;
    }
}

// Uniform triangle: (b0, b1) uniform over {b0, b1 >= 0, b0 + b1 <= 1}. A 16 x 16 grid over
// the unit square: cells below the diagonal hold 2/256 of the mass, cells the diagonal
// halves 1/256, cells above it none.
TEST(Sampling, UniformTriangleIsUniform) {
    const int g = 16;
    std::vector<cl_float4> s = warp(kTriangle, 0, kSamples, 5);
    std::vector<double> obs(g * g, 0.0), expected(g * g, 0.0);
    for (int i = 0; i < g; ++i)
        for (int j = 0; j < g; ++j)
            expected[i * g + j] = double(kSamples) * (i + j < g - 1 ? 2.0 : (i + j == g - 1 ? 1.0 : 0.0)) / (g * g);
    for (const cl_float4& p : s) {
        double b0 = p.s[0], b1 = p.s[1];
        ASSERT_GE(b0, 0.0);
        ASSERT_GE(b1, 0.0);
        ASSERT_LE(b0 + b1, 1 + 1e-6);
        int i = std::clamp(int(b0 * g), 0, g - 1), j = std::clamp(int(b1 * g), 0, g - 1);
        // A point on the diagonal rounded into a cell above it counts for the cell it came from.
        if (i + j > g - 1) (i > j ? i : j) -= 1;
        obs[i * g + j] += 1;
    }
    ChiSquare chi = chi_square(obs, expected);
    EXPECT_GT(chi.p_value, kChiSquareSignificance) << "chi2 " << chi.statistic << ", worst " << chi.worst;
}

// find_interval on a CDF with zero-width intervals (zero weights), at every CDF value, just
// below and above it, and on a fine grid: cdf[i] <= u < cdf[i + 1], so a zero-width interval
// is never returned.
TEST(Sampling, FindIntervalNeverReturnsEmptyIntervals) {
    std::vector<float> weights = {0, 1, 0, 0, 3, 2, 0, 0.5f, 0, 4, 0};
    std::vector<float> cdf(weights.size() + 1, 0.0f);
    double total = 0;
    for (float w : weights) total += w;
    double run = 0;
    for (size_t i = 0; i < weights.size(); ++i) {
        run += weights[i];
        cdf[i + 1] = float(run / total);
    }
    cdf.back() = 1.0f;
    std::vector<float> u;
    for (float c : cdf) {
        if (c < 1) u.push_back(c);
        u.push_back(std::nextafter(c, 0.0f));
        if (c < 1) u.push_back(std::nextafter(c, 1.0f));
    }
    for (int i = 0; i < 1000; ++i) u.push_back(float(i) / 1000.0f);
    u.push_back(std::nextafter(1.0f, 0.0f));
    cl::Kernel k = test_kernel("kernels/sampling_test.cl", {}, "find_interval_test");
    cl::Buffer cdf_buf = upload(cdf), u_buf = upload(u);
    cl::Buffer out = output_buffer<cl_int>(u.size());
    k.setArg(0, cdf_buf);
    k.setArg(1, cl_int(weights.size()));
    k.setArg(2, u_buf);
    k.setArg(3, out);
    launch(k, u.size());
    std::vector<cl_int> idx = download<cl_int>(out, u.size());
    for (size_t i = 0; i < u.size(); ++i) {
        int j = idx[i];
        ASSERT_GE(j, 0);
        ASSERT_LT(j, int(weights.size()));
        EXPECT_LE(cdf[j], u[i]) << "u " << u[i];
        EXPECT_LT(u[i], cdf[j + 1]) << "u " << u[i];
        EXPECT_GT(weights[j], 0) << "u " << u[i] << " gave the empty interval " << j;
    }
}

// find_interval_guided (cl/sampling.h) answers exactly what find_interval does, so the light
// CDF's guide (LIGHT_CDF_GUIDE) leaves every image as it was: CDFs of 1 to 5 000 intervals with
// runs of zero weights and one weight a million times the rest (guide entries far apart),
// queried at every CDF value and its float neighbours, at every k / g and its neighbours and on
// a grid; each with the guide append_cdf_guide builds, and with guides whose entries are wrong
// (all 0, all n - 1, reversed), which may cost steps but must not change an answer.
TEST(Sampling, GuidedSearchAnswersAsThePlainSearch) {
    std::mt19937 rng(7);
    std::uniform_real_distribution<float> weight(0.0f, 1.0f);
    cl::Kernel k = test_kernel("kernels/sampling_test.cl", {}, "find_interval_guided_test");
    int checked = 0;
    for (int n : {1, 2, 17, 300, 5000}) {
        for (int variant = 0; variant < 4; ++variant) {
            std::vector<float> weights(static_cast<size_t>(n));
            for (int i = 0; i < n; ++i) weights[size_t(i)] = (i / 3) % 4 == 1 ? 0.0f : weight(rng);
            if (n > 2) weights[size_t(n / 2)] = 1e6f;
            std::vector<float> buffer(size_t(n) + 1, 0.0f);
            double total = 0, run = 0;
            for (float w : weights) total += w;
            for (int i = 0; i < n; ++i) {
                run += weights[size_t(i)];
                buffer[size_t(i) + 1] = total > 0 ? float(run / total) : float(i + 1) / float(n);
            }
            buffer.back() = 1.0f;
            const std::vector<float> cdf = buffer;
            const int g = n;
            append_cdf_guide(buffer, 0, n, g);
            std::vector<float> guide(buffer.begin() + n + 1, buffer.end());
            ASSERT_EQ(guide.size(), size_t(g) + 1);
            auto set_all = [&](auto entry_of) {
                for (int j = 0; j <= g; ++j) {
                    const int32_t e = entry_of(j);
                    std::memcpy(&guide[size_t(j)], &e, sizeof e);
                }
            };
            if (variant == 1) set_all([](int) { return 0; });
            if (variant == 2) set_all([&](int) { return n - 1; });
            if (variant == 3) set_all([&](int j) { return std::max(0, n - 1 - j); });
            std::vector<float> u;
            for (float c : cdf) {
                for (float v : {c, std::nextafter(c, 0.0f), std::nextafter(c, 1.0f)})
                    if (v >= 0 && v < 1) u.push_back(v);
            }
            for (int j = 0; j <= g; ++j) {
                const float c = float(double(j) / double(g));
                for (float v : {c, std::nextafter(c, 0.0f), std::nextafter(c, 1.0f)})
                    if (v >= 0 && v < 1) u.push_back(v);
            }
            for (int j = 0; j < 4096; ++j) u.push_back(float(j) / 4096.0f);
            cl::Buffer cdf_buf = upload(cdf), guide_buf = upload(guide), u_buf = upload(u);
            cl::Buffer out = output_buffer<cl_int2>(u.size());
            k.setArg(0, cdf_buf);
            k.setArg(1, cl_int(n));
            k.setArg(2, guide_buf);
            k.setArg(3, cl_int(g));
            k.setArg(4, u_buf);
            k.setArg(5, out);
            launch(k, u.size());
            std::vector<cl_int2> r = download<cl_int2>(out, u.size());
            for (size_t i = 0; i < u.size(); ++i) {
                ASSERT_EQ(r[i].s[1], r[i].s[0]) << "n " << n << ", guide variant " << variant << ", u " << u[i];
                ++checked;
            }
        }
    }
    EXPECT_GT(checked, 40000);
}

}  // namespace
}  // namespace clbdpt::test
