// Shared by the kernel unit tests (sampling, bsdf, lights, camera, geometry, MIS brute force):
// double-precision vector helpers for host-side reference formulas, buffer up/download and
// launch helpers for the tiny wrapper kernels in cl/kernels/*_test.cl, hand-made scenes, and a
// chi-square goodness-of-fit test (pbrt-v4 sampling_test.cpp / Mitsuba's ChiSquare).
#pragma once

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <memory>
#include <numeric>
#include <random>
#include <string>
#include <vector>

#include "bvh/bvh.h"
#include "render/device_scene.h"
#include "render/features.h"
#include "render/scene_buffers.h"
#include "render_test_util.h"
#include "scene/scene.h"

namespace clbdpt::test {

constexpr double kPi = 3.14159265358979323846;

// ---- Double-precision vectors ------------------------------------------------------------

struct D3 {
    double x = 0, y = 0, z = 0;
    D3() = default;
    D3(double x_, double y_, double z_) : x(x_), y(y_), z(z_) {}
};
inline D3 operator+(D3 a, D3 b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
inline D3 operator-(D3 a, D3 b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
inline D3 operator-(D3 a) { return {-a.x, -a.y, -a.z}; }
inline D3 operator*(D3 a, double s) { return {a.x * s, a.y * s, a.z * s}; }
inline D3 operator*(double s, D3 a) { return a * s; }
inline D3 operator/(D3 a, double s) { return {a.x / s, a.y / s, a.z / s}; }
inline double dot(D3 a, D3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
inline D3 cross(D3 a, D3 b) { return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x}; }
inline double length(D3 a) { return std::sqrt(dot(a, a)); }
inline D3 normalize(D3 a) { return a / length(a); }
inline bool is_zero(D3 a) { return a.x == 0 && a.y == 0 && a.z == 0; }

inline D3 d3(const cl_float4& v) { return {v.s[0], v.s[1], v.s[2]}; }
inline D3 d3(Vec3 v) { return {v.x, v.y, v.z}; }
inline cl_float4 f4(D3 v, double w = 0) {
    cl_float4 r;
    r.s[0] = float(v.x);
    r.s[1] = float(v.y);
    r.s[2] = float(v.z);
    r.s[3] = float(w);
    return r;
}
inline Vec3 v3(D3 v) { return {float(v.x), float(v.y), float(v.z)}; }
// v rounded to float, back in double: the exact value the device will see.
inline D3 as_float(D3 v) { return {double(float(v.x)), double(float(v.y)), double(float(v.z))}; }

// Orthonormal frame around a unit normal (any frame: the reference formulas are isotropic).
struct DFrame {
    D3 s, t, n;
    explicit DFrame(D3 n_) : n(normalize(n_)) {
        D3 a = std::fabs(n.x) > 0.9 ? D3(0, 1, 0) : D3(1, 0, 0);
        s = normalize(cross(a, n));
        t = cross(n, s);
    }
    D3 to_local(D3 v) const { return {dot(v, s), dot(v, t), dot(v, n)}; }
    D3 from_local(D3 v) const { return s * v.x + t * v.y + n * v.z; }
};

inline D3 spherical(double cos_theta, double phi) {
    double sin_theta = std::sqrt(std::max(0.0, 1 - cos_theta * cos_theta));
    return {sin_theta * std::cos(phi), sin_theta * std::sin(phi), cos_theta};
}

// Relative difference, with a floor so that two tiny values compare by absolute difference.
inline double rel_diff(double a, double b, double floor = 1e-30) {
    return std::fabs(a - b) / std::max({std::fabs(a), std::fabs(b), floor});
}

// ---- OpenCL helpers -------------------------------------------------------------------------

template <typename T>
cl::Buffer upload(const std::vector<T>& data, cl_mem_flags flags = CL_MEM_READ_ONLY) {
    T zero{};
    const void* src = data.empty() ? static_cast<const void*>(&zero) : static_cast<const void*>(data.data());
    size_t bytes = sizeof(T) * std::max<size_t>(1, data.size());
    return cl::Buffer(test_device().context(), flags | CL_MEM_COPY_HOST_PTR, bytes, const_cast<void*>(src));
}

template <typename T>
cl::Buffer output_buffer(size_t count) {
    return cl::Buffer(test_device().context(), CL_MEM_READ_WRITE, sizeof(T) * std::max<size_t>(1, count));
}

template <typename T>
std::vector<T> download(const cl::Buffer& buffer, size_t count) {
    std::vector<T> out(count);
    if (count) test_device().queue().enqueueReadBuffer(buffer, CL_TRUE, 0, sizeof(T) * count, out.data());
    return out;
}

inline void launch(cl::Kernel& kernel, size_t items) {
    test_device().queue().enqueueNDRangeKernel(kernel, cl::NullRange, cl::NDRange(items), cl::NullRange);
    test_device().queue().finish();
}

inline cl::Kernel test_kernel(const std::string& file, const std::vector<std::string>& defines, const char* name) {
    const ProgramBuild& build = test_device().program(file, defines);
    return cl::Kernel(build.program, name);
}

// Runs kernel `name` of `file` (no defines) as out[i] = f(in[i]): its arguments are the input
// and the output buffer, one work item per element. Returns out.
template <typename Out, typename In>
std::vector<Out> map_kernel(const std::string& file, const char* name, const std::vector<In>& in) {
    cl::Kernel k = test_kernel(file, {}, name);
    cl::Buffer in_buffer = upload(in);
    cl::Buffer out = output_buffer<Out>(in.size());
    k.setArg(0, in_buffer);
    k.setArg(1, out);
    launch(k, in.size());
    return download<Out>(out, in.size());
}

// ---- Hand-made scenes -----------------------------------------------------------------------
// Built through the real loader path (Scene -> build_device_scene), so lights, selection
// probabilities and the environment distribution are the renderer's.

inline Material make_material(int kind, D3 kd, D3 ks = {}, D3 ke = {}, float alpha = 0.1f, float ior = 1.5f) {
    Material m{};
    m.kind = kind;
    m.kd = f4(kd);
    m.ks = f4(ks);
    m.ke = f4(ke);
    m.alpha = alpha;
    m.ior = ior;
    return m;
}

inline int add_material(Scene& scene, const Material& m) { return add_scene_material(scene, m); }

inline void add_triangle(Scene& scene, D3 p0, D3 p1, D3 p2, int material) {
    add_scene_triangle(scene, v3(p0), v3(p1), v3(p2), material);
}

// Quad p0 p1 p2 p3 (counter-clockwise seen from the front) as two triangles.
inline void add_quad(Scene& scene, D3 p0, D3 p1, D3 p2, D3 p3, int material) {
    add_triangle(scene, p0, p1, p2, material);
    add_triangle(scene, p0, p2, p3, material);
}

// A lat-long map with smooth variation, a bright spot and coloured texels (so luminance and
// the mean of rgb differ), every texel positive.
inline EnvironmentMap synthetic_environment(int width, int height) {
    EnvironmentMap map;
    map.width = width;
    map.height = height;
    map.rgb.resize(size_t(width) * height * 3);
    for (int y = 0; y < height; ++y)
        for (int x = 0; x < width; ++x) {
            double u = (x + 0.5) / width, v = (y + 0.5) / height;
            double base = 0.2 + 0.8 * (1 - v) * (1 - v) + 0.3 * std::sin(2 * kPi * u) * std::sin(2 * kPi * u);
            double spot = std::exp(-((u - 0.3) * (u - 0.3) + (v - 0.35) * (v - 0.35)) / 0.004);
            float* px = &map.rgb[(size_t(y) * width + x) * 3];
            px[0] = float(base + 6 * spot);
            px[1] = float(base * (0.5 + 0.5 * u) + 3 * spot);
            px[2] = float(base * (1.5 - v) + 0.5 * spot);
        }
    return map;
}

// A device scene with its buffers on the test device and the kernel flags its features need.
// Not movable: SceneBuffers keeps a reference to `ds`.
struct TestScene {
    DeviceScene ds;
    std::vector<std::string> defines;
    std::unique_ptr<SceneBuffers> buffers;

    TestScene(const Scene& scene, int width, int height, Integrator integrator = Integrator::Bdpt,
              int max_depth = 5)
        : ds(build_device_scene(scene, width, height, environment_sampling_for(integrator))) {
        defines = kernel_defines(ds, integrator, max_depth);
        buffers = std::make_unique<SceneBuffers>(test_device().context(), ds);
    }
    explicit TestScene(DeviceScene device_scene, std::vector<std::string> flags)
        : ds(std::move(device_scene)), defines(std::move(flags)) {
        buffers = std::make_unique<SceneBuffers>(test_device().context(), ds);
    }
    TestScene(const TestScene&) = delete;
    TestScene& operator=(const TestScene&) = delete;

    // A kernel from `file` with the scene's arguments set (0 .. kSceneArgCount - 1).
    cl::Kernel kernel(const std::string& file, const char* name, const std::vector<std::string>& extra = {}) const {
        std::vector<std::string> d = defines;
        d.insert(d.end(), extra.begin(), extra.end());
        cl::Kernel k = test_kernel(file, d, name);
        buffers->set_args(k);
        return k;
    }
};

// ---- Statistics -----------------------------------------------------------------------------

// Regularised upper incomplete gamma function Q(a, x) (Numerical Recipes 6.2: series for
// x < a + 1, Lentz continued fraction otherwise).
inline double gamma_q(double a, double x) {
    if (x <= 0) return 1.0;
    const double gln = std::lgamma(a);
    if (x < a + 1) {
        double ap = a, sum = 1.0 / a, del = sum;
        for (int n = 0; n < 100000; ++n) {
            ap += 1;
            del *= x / ap;
            sum += del;
            if (std::fabs(del) < std::fabs(sum) * 1e-15) break;
        }
        return std::max(0.0, 1.0 - sum * std::exp(-x + a * std::log(x) - gln));
    }
    const double tiny = 1e-300;
    double b = x + 1 - a, c = 1 / tiny, d = 1 / b, h = d;
    for (int i = 1; i < 100000; ++i) {
        double an = -i * (i - a);
        b += 2;
        d = an * d + b;
        if (std::fabs(d) < tiny) d = tiny;
        c = b + an / c;
        if (std::fabs(c) < tiny) c = tiny;
        d = 1 / d;
        double del = d * c;
        h *= del;
        if (std::fabs(del - 1) < 1e-15) break;
    }
    return std::exp(-x + a * std::log(x) - gln) * h;
}

struct ChiSquare {
    double statistic = 0;
    int dof = 0;
    double p_value = 1;
    int cells = 0;  // after merging
    std::string worst;  // the cell with the largest contribution, for failure messages
};

// Pearson's chi-square test of observed counts against expected counts (same total up to the
// expected mass the sampler may lose, which the caller puts in a cell of its own). Cells with
// expected < min_expected are pooled, smallest first, until every cell reaches it (the usual
// validity condition of the chi-square approximation; pbrt-v4 and Mitsuba do the same). A cell
// with expected 0 and observed > 0 is an impossible sample: p = 0.
inline ChiSquare chi_square(const std::vector<double>& observed, const std::vector<double>& expected,
                            double min_expected = 5.0) {
    ChiSquare r;
    std::vector<size_t> order(observed.size());
    std::iota(order.begin(), order.end(), size_t(0));
    std::sort(order.begin(), order.end(), [&](size_t a, size_t b) { return expected[a] < expected[b]; });
    double pool_obs = 0, pool_exp = 0;
    double worst = -1;
    auto add_cell = [&](double o, double e, size_t index) {
        double d = (o - e) * (o - e) / e;
        r.statistic += d;
        ++r.cells;
        if (d > worst) {
            worst = d;
            r.worst = "cell " + std::to_string(index) + ": observed " + std::to_string(o) + ", expected " +
                      std::to_string(e);
        }
    };
    for (size_t k = 0; k < order.size(); ++k) {
        size_t i = order[k];
        if (expected[i] <= 0) {
            if (observed[i] > 0) {
                r.p_value = 0;
                r.worst = "cell " + std::to_string(i) + " has " + std::to_string(observed[i]) +
                          " samples where the density is 0";
                return r;
            }
            continue;
        }
        if (pool_exp > 0 || expected[i] < min_expected) {
            pool_obs += observed[i];
            pool_exp += expected[i];
            if (pool_exp >= min_expected) {
                add_cell(pool_obs, pool_exp, i);
                pool_obs = pool_exp = 0;
            }
            continue;
        }
        add_cell(observed[i], expected[i], i);
    }
    if (pool_exp > 0) add_cell(pool_obs, pool_exp, size_t(-1));
    r.dof = r.cells - 1;
    r.p_value = r.dof > 0 ? gamma_q(0.5 * r.dof, 0.5 * r.statistic) : 1.0;
    return r;
}

// Significance level of every chi-square test in these files. The seeds are fixed, so a pass
// stays a pass; with a few dozen tests a correct sampler fails one of them on a fresh seed with
// probability about 0.5%, while a wrong density (a missing cosine, a wrong normalisation, a
// swapped lobe) gives p-values below 1e-20 at these sample counts.
constexpr double kChiSquareSignificance = 1e-4;

// Mean and standard error of a sample of estimator values.
struct MeanEstimate {
    double mean = 0;
    double std_error = 0;
};

template <typename F>
MeanEstimate mean_estimate(size_t n, F value) {
    double sum = 0, sum2 = 0;
    for (size_t i = 0; i < n; ++i) {
        double v = value(i);
        sum += v;
        sum2 += v * v;
    }
    MeanEstimate m;
    m.mean = sum / double(n);
    double var = std::max(0.0, sum2 / double(n) - m.mean * m.mean) * double(n) / double(n - 1);
    m.std_error = std::sqrt(var / double(n));
    return m;
}

// Monte Carlo estimates must land within this many standard errors of the exact value: a
// two-sided 5-sigma band fails a correct estimator with probability 6e-7.
constexpr double kSigmas = 5.0;

}  // namespace clbdpt::test
