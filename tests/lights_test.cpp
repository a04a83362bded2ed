// cl/lights.h through cl/kernels/lights_test.cl, on a hand-made scene with one light of every
// kind (a triangle area light, point, spot, directional, and an environment light with a
// 32 x 16 map, or constant):
//  - Sample_Li: pdf_w equals light_pdf_li_area / environment_pdf_w evaluated separately and the
//    double-precision formula; the point, direction and radiance are the light's; E[1/pdf_w] is
//    the solid angle the light covers (the density is normalised);
//  - Sample_Le: pdf_pos / pdf_dir equal light_pdf_le and the formulas; directions are
//    chi-square distributed as claimed (area: cosine, spot: uniform in the cone, point: uniform
//    sphere, environment: the map's distribution), origins of lights at infinity uniform on the
//    scene's bounding disk;
//  - the environment map: sampled directions fall in texels with probability func / sum(func),
//    environment_pdf_w integrates to 1 and matches a port of the distribution;
//  - light selection follows select_pdf.
// Tolerances not stated at a test: positions and unit vectors computed in float from values of
// order 1 (or of the scene radius r) agree with the double reference to 1e-5 (absolute, or
// relative to r): ~100 ulps; radiances copied from the light to 1e-6; chi-square tests at
// kChiSquareSignificance, Monte Carlo means within kSigmas standard errors (kernel_test_util.h).
#include <algorithm>
#include <map>

#include <gtest/gtest.h>

#include "kernel_test_util.h"

namespace clbdpt::test {
namespace {

enum LightIndex { kArea = 0, kPoint = 1, kSpot = 2, kDirectional = 3, kEnvironment = 4 };

const D3 kAreaP0(-0.6, 1.9, -0.4), kAreaP1(0.7, 1.95, -0.3), kAreaP2(0.1, 2.1, 0.6);
const D3 kPointPos(0.3, 1.5, 0.2);
const D3 kSpotPos(0, 3, 0), kSpotTarget(0.3, 0, 0.2);
constexpr double kSpotCone = 30, kSpotDelta = 8;
const D3 kDirectionalDir = normalize(D3(0.3, -1, 0.2));

Scene light_scene(bool env_map) {
    Scene s;
    s.path = "lights_test";
    int floor = add_material(s, make_material(MATERIAL_DIFFUSE, {0.5, 0.5, 0.5}));
    int emit = add_material(s, make_material(MATERIAL_DIFFUSE, {0, 0, 0}, {}, {4, 3, 2}));
    add_quad(s, {-2, 0, -2}, {-2, 0, 2}, {2, 0, 2}, {2, 0, -2}, floor);
    add_triangle(s, kAreaP0, kAreaP1, kAreaP2, emit);  // faces down (-y)
    LightDesc point = point_light(v3(kPointPos), {10, 8, 6});
    LightDesc spot = spot_light(v3(kSpotPos), v3(kSpotTarget), {5, 4, 3}, float(kSpotCone), float(kSpotDelta));
    LightDesc dir;
    dir.kind = LightDesc::Kind::Directional;
    dir.direction = v3(kDirectionalDir);
    dir.color = {1, 0.5f, 0.25f};
    LightDesc env;
    env.kind = LightDesc::Kind::Environment;
    env.color = {1.5f, 1.5f, 1.5f};
    s.lights = {point, spot, dir, env};
    if (env_map) s.environment_map = synthetic_environment(32, 16);
    s.camera.eye = {0, 1, -5};
    s.camera.target = {0, 0.5f, 0};
    return s;
}

const TestScene& map_scene() {
    static TestScene scene(light_scene(true), 32, 32);
    return scene;
}
// The same scene as the light tracer has it: the map sampled by luminance (render/device_scene.h).
const TestScene& luminance_map_scene() {
    static TestScene scene(light_scene(true), 32, 32, Integrator::Lt);
    return scene;
}
const TestScene& constant_scene() {
    static TestScene scene(light_scene(false), 32, 32);
    return scene;
}

// ---- Reference formulas ------------------------------------------------------------------------

D3 area_normal() { return normalize(cross(kAreaP1 - kAreaP0, kAreaP2 - kAreaP0)); }
double area_area() { return 0.5 * length(cross(kAreaP1 - kAreaP0, kAreaP2 - kAreaP0)); }

// Solid angle of triangle (a, b, c) seen from r (Van Oosterom and Strackee 1983).
double triangle_solid_angle(D3 r, D3 a, D3 b, D3 c) {
    a = a - r;
    b = b - r;
    c = c - r;
    double la = length(a), lb = length(b), lc = length(c);
    double num = std::fabs(dot(a, cross(b, c)));
    double den = la * lb * lc + dot(a, b) * lc + dot(a, c) * lb + dot(b, c) * la;
    return 2 * std::atan2(num, den);
}

double spot_falloff(const Light& l, D3 w_from_light) {
    double c = dot(w_from_light, d3(l.direction));
    double total = 1 - double(l.one_minus_cos_total), start = 1 - double(l.one_minus_cos_falloff);
    if (c < total) return 0;
    if (c >= start) return 1;
    double d = (c - total) / (start - total);
    return d * d * d * d;
}

// The environment light's sampling distribution: the per-texel weights `func` (row 0 = +y, u =
// phi / 2pi from +x toward +z; README) as the host tabulated them (the first W*H entries of
// env_distribution, whose weighting rule EnvironmentMapSamplingFollowsDocumentedDistribution
// checks), with everything derived from them -- normalisation, texel lookup, the solid-angle
// density func / (integral 2 pi^2 sin theta) -- recomputed here in double.
struct EnvReference {
    int w = 0, h = 0;
    std::vector<double> func;
    double sum = 0;
    explicit EnvReference(const DeviceScene& ds) : w(ds.info.env_width), h(ds.info.env_height) {
        for (int i = 0; i < w * h; ++i) {
            func.push_back(ds.env_distribution[size_t(i)]);
            sum += func.back();
        }
    }
    static void uv(D3 d, double* u, double* v) {
        double phi = std::atan2(d.z, d.x);
        if (phi < 0) phi += 2 * kPi;
        *u = phi / (2 * kPi);
        *v = std::acos(std::clamp(d.y, -1.0, 1.0)) / kPi;
    }
    int texel(D3 d) const {
        double u, v;
        uv(d, &u, &v);
        int x = std::min(int(u * w), w - 1), y = std::min(int(v * h), h - 1);
        return y * w + x;
    }
    // Whether d is within `margin` (in u, v units) of a texel edge, where float and double may
    // pick different texels.
    bool near_edge(D3 d, double margin) const {
        double u, v;
        uv(d, &u, &v);
        auto near = [&](double t, int n) {
            double f = t * n - std::floor(t * n);
            return f < margin * n || f > 1 - margin * n;
        };
        return near(u, w) || near(v, h);
    }
    double pdf_w(D3 d) const {
        double u, v;
        uv(d, &u, &v);
        double st = std::sin(v * kPi);
        if (st == 0) return 0;
        double integral = sum / (double(w) * h);
        return func[texel(d)] / integral / (2 * kPi * kPi * st);
    }
};

// ---- Running the kernels ---------------------------------------------------------------------

struct LiSample {
    D3 wi, p, n, li;
    double pdf_w, pdf_eval;
    bool ok;
};

std::vector<LiSample> sample_li(const TestScene& scene, int light, D3 ref, size_t count, uint32_t seed) {
    cl::Kernel k = scene.kernel("kernels/lights_test.cl", "light_li_test");
    cl::Buffer out = output_buffer<cl_float4>(4 * count);
    cl_uint a = SceneBuffers::kSceneArgCount;
    k.setArg(a, cl_int(light));
    k.setArg(a + 1, f4(ref));
    k.setArg(a + 2, cl_uint(seed));
    k.setArg(a + 3, out);
    launch(k, count);
    std::vector<cl_float4> r = download<cl_float4>(out, 4 * count);
    std::vector<LiSample> s(count);
    for (size_t i = 0; i < count; ++i) {
        const cl_float4* x = &r[4 * i];
        s[i] = {d3(x[0]), d3(x[1]), d3(x[2]), d3(x[3]), x[0].s[3], x[2].s[3], x[1].s[3] != 0};
    }
    return s;
}

struct LeSample {
    D3 origin, dir, n, le;
    double pdf_pos, pdf_dir, pdf_pos_eval, pdf_dir_eval;
    bool ok;
};

std::vector<LeSample> sample_le(const TestScene& scene, int light, size_t count, uint32_t seed) {
    cl::Kernel k = scene.kernel("kernels/lights_test.cl", "light_le_test");
    cl::Buffer out = output_buffer<cl_float4>(5 * count);
    cl_uint a = SceneBuffers::kSceneArgCount;
    k.setArg(a, cl_int(light));
    k.setArg(a + 1, cl_uint(seed));
    k.setArg(a + 2, out);
    launch(k, count);
    std::vector<cl_float4> r = download<cl_float4>(out, 5 * count);
    std::vector<LeSample> s(count);
    for (size_t i = 0; i < count; ++i) {
        const cl_float4* x = &r[5 * i];
        s[i] = {d3(x[0]), d3(x[1]), d3(x[2]), d3(x[3]), x[0].s[3], x[1].s[3], x[4].s[0], x[4].s[1], x[2].s[3] != 0};
    }
    return s;
}

// Points from which the lights are sampled: under the area light, beside it, far away, and
// above it (behind the one-sided emitter).
const std::vector<D3> kRefs = {{0.1, 0.5, 0.3}, {-1, 1, 1}, {1.5, 0.2, -1}, {0.05, 0.02, -0.1}, {0.2, 2.6, 0.1}};

// Densities computed twice by the same float formula agree to rounding; against the double
// reference, ~10 float operations on values of order 1: 1e-4 relative (the brief's bound).
constexpr double kPdfTolerance = 1e-4;

// Chi-square cells in (a, phi) with a the radial coordinate in which the density is uniform.
constexpr int kRadial = 10, kAngular = 20;
int polar_cell(double a, D3 local) {
    double phi = std::atan2(local.y, local.x);
    if (phi < 0) phi += 2 * kPi;
    int i = std::clamp(int(a * kRadial), 0, kRadial - 1);
    int j = std::clamp(int(phi / (2 * kPi) * kAngular), 0, kAngular - 1);
    return i * kAngular + j;
}

void expect_fit(const std::vector<double>& observed, const std::vector<double>& expected, const std::string& what) {
    ChiSquare chi = chi_square(observed, expected);
    EXPECT_GT(chi.p_value, kChiSquareSignificance)
        << what << ": chi2 " << chi.statistic << " dof " << chi.dof << ", worst " << chi.worst;
}

void expect_uniform(const std::vector<double>& observed, double n, const std::string& what) {
    expect_fit(observed, std::vector<double>(observed.size(), n / double(observed.size())), what);
}

// ---- Tests -----------------------------------------------------------------------------------

TEST(Lights, SceneHasEveryKind) {
    const DeviceScene& ds = map_scene().ds;
    ASSERT_EQ(ds.lights.size(), 5u);
    EXPECT_EQ(ds.lights[kArea].kind, LIGHT_AREA);
    EXPECT_EQ(ds.lights[kPoint].kind, LIGHT_POINT);
    EXPECT_EQ(ds.lights[kSpot].kind, LIGHT_SPOT);
    EXPECT_EQ(ds.lights[kDirectional].kind, LIGHT_DIRECTIONAL);
    EXPECT_EQ(ds.lights[kEnvironment].kind, LIGHT_ENVIRONMENT);
    EXPECT_LT(area_normal().y, -0.9) << "the area light must face down";
}

// Area light Sample_Li: a uniform point on the triangle, pdf_w = d^2 / (|cos| A), radiance Ke
// only on the front side, and E[1/pdf_w] = the triangle's solid angle (within kSigmas standard
// errors; 2^16 samples).
TEST(Lights, AreaSampleLi) {
    const TestScene& scene = map_scene();
    const size_t n = 1 << 16;
    const D3 nrm = area_normal();
    for (D3 ref : kRefs) {
        std::vector<LiSample> s = sample_li(scene, kArea, ref, n, 17);
        D3 ref_f = as_float(ref);
        bool front = dot(ref_f - kAreaP0, nrm) > 0;
        for (const LiSample& x : s) {
            ASSERT_EQ(x.ok, front);
            ASSERT_LT(std::fabs(dot(x.p - kAreaP0, nrm)), 1e-5) << "sampled point off the triangle's plane";
            ASSERT_LT(length(x.n - nrm), 1e-5);
            D3 d = x.p - ref_f;
            ASSERT_LT(length(x.wi - normalize(d)), 1e-5);
            double expect = dot(d, d) / (std::fabs(dot(nrm, normalize(d))) * area_area());
            ASSERT_LE(rel_diff(x.pdf_w, x.pdf_eval), kPdfTolerance) << "light_pdf_li_area";
            ASSERT_LE(rel_diff(x.pdf_w, expect), kPdfTolerance);
            if (front) {
                ASSERT_LE(length(x.li - D3(4, 3, 2)), 1e-6);
            } else {
                ASSERT_EQ(length(x.li), 0.0);
            }
        }
        MeanEstimate omega = mean_estimate(n, [&](size_t i) { return 1 / s[i].pdf_w; });
        double exact = triangle_solid_angle(ref_f, kAreaP0, kAreaP1, kAreaP2);
        EXPECT_NEAR(omega.mean, exact, kSigmas * omega.std_error + 1e-6 * exact)
            << "E[1/pdf_w] against the solid angle from (" << ref.x << ", " << ref.y << ", " << ref.z << ")";
    }
}

// Point and spot Sample_Li: p the light's position, pdf_w 1 (delta), li = I falloff / d^2 with
// the spot's quartic falloff (pbrt-v3 SpotLight::Falloff). Refs inside the inner cone, in the
// falloff band and outside the cone (nothing returned).
TEST(Lights, PointAndSpotSampleLi) {
    const TestScene& scene = map_scene();
    const Light& spot = scene.ds.lights[kSpot];
    D3 axis = normalize(kSpotTarget - kSpotPos);
    DFrame f(axis);
    std::vector<D3> refs = kRefs;
    // On the floor-ish at 10, 25 (band), 28 (band) and 35 (outside) degrees off the axis.
    for (double deg : {10.0, 25.0, 28.0, 35.0})
        refs.push_back(kSpotPos + 2.5 * f.from_local(spherical(std::cos(deg * kPi / 180), 0.4)));
    for (D3 ref : refs) {
        D3 ref_f = as_float(ref);
        for (int light : {int(kPoint), int(kSpot)}) {
            D3 pos = light == kPoint ? kPointPos : kSpotPos;
            D3 intensity = light == kPoint ? D3(10, 8, 6) : D3(5, 4, 3);
            std::vector<LiSample> s = sample_li(scene, light, ref, 16, 3);
            D3 d = as_float(pos) - ref_f;
            double falloff = light == kSpot ? spot_falloff(spot, normalize(-d)) : 1.0;
            D3 li = intensity * (falloff / dot(d, d));
            for (const LiSample& x : s) {
                EXPECT_EQ(x.ok, falloff > 0);
                EXPECT_LT(length(x.p - as_float(pos)), 1e-6);
                EXPECT_LT(length(x.wi - normalize(d)), 1e-6);
                EXPECT_EQ(x.pdf_w, 1.0);
                EXPECT_LE(length(x.li - li), 1e-5 * length(li) + 1e-7);
            }
        }
    }
}

// Directional Sample_Li: wi = -direction, pdf 1, li = radiance, p two scene radii away.
TEST(Lights, DirectionalSampleLi) {
    const TestScene& scene = map_scene();
    double r = scene.ds.info.world_center.s[3];
    for (D3 ref : kRefs) {
        std::vector<LiSample> s = sample_li(scene, kDirectional, ref, 16, 3);
        for (const LiSample& x : s) {
            EXPECT_TRUE(x.ok);
            EXPECT_LT(length(x.wi + kDirectionalDir), 1e-6);
            EXPECT_EQ(x.pdf_w, 1.0);
            EXPECT_LE(length(x.li - D3(1, 0.5, 0.25)), 1e-6);
            EXPECT_LT(length(x.p - (as_float(ref) - kDirectionalDir * (2 * r))), 1e-4 * r);
        }
    }
}

// Environment map Sample_Li: pdf_w equals environment_pdf_w at the returned direction and the
// port of the distribution; li is the texel times the scale; E[1/pdf_w] is the solid angle of
// the texels the distribution samples: 4 pi by luminance (all texels are positive), those above
// the map's mean compensated. Samples within 1e-4 (in u, v) of a texel edge may be assigned to
// the neighbouring texel by float rounding and are left out of the pointwise comparisons; so are samples with sin(theta) < 0.05, where acos(w.y) loses 6e-8/theta^2 of
// relative precision (pdf_w divides by sin theta).
void check_environment_sample_li(const TestScene& scene) {
    EnvReference env(scene.ds);
    double support = 0;  // the sampled texels' solid angle
    for (int y = 0; y < env.h; ++y)
        for (int x = 0; x < env.w; ++x)
            if (env.func[size_t(y * env.w + x)] > 0)
                support += 2 * kPi / env.w * (std::cos(kPi * y / env.h) - std::cos(kPi * (y + 1) / env.h));
    if (scene.ds.env_sampling == EnvironmentSampling::Luminance) {
        EXPECT_NEAR(support, 4 * kPi, 1e-9);
    }
    const size_t n = 1 << 17;
    std::vector<LiSample> s = sample_li(scene, kEnvironment, kRefs[0], n, 23);
    size_t compared = 0;
    for (const LiSample& x : s) {
        ASSERT_TRUE(x.ok);
        ASSERT_NEAR(length(x.wi), 1.0, 1e-5);
        double st = std::sqrt(std::max(0.0, 1 - x.wi.y * x.wi.y));
        if (env.near_edge(x.wi, 1e-4) || st < 0.05) continue;
        ++compared;
        ASSERT_LE(rel_diff(x.pdf_w, x.pdf_eval), kPdfTolerance) << "environment_pdf_w";
        ASSERT_LE(rel_diff(x.pdf_w, env.pdf_w(x.wi)), kPdfTolerance) << "port of the distribution";
        const cl_float4& t = scene.ds.env_texels[env.texel(x.wi)];
        ASSERT_LE(length(x.li - 1.5 * d3(t)), 1e-5 * length(x.li));
    }
    EXPECT_GT(compared, n * 9 / 10);
    MeanEstimate omega = mean_estimate(n, [&](size_t i) { return 1 / s[i].pdf_w; });
    EXPECT_NEAR(omega.mean, support, kSigmas * omega.std_error) << "E[1/pdf_w]";
}

TEST(Lights, EnvironmentMapSampleLi) {
    {
        SCOPED_TRACE("compensated");
        check_environment_sample_li(map_scene());
    }
    SCOPED_TRACE("by luminance");
    check_environment_sample_li(luminance_map_scene());
}

// The environment map's sampled directions land in texel i with probability func_i / sum(func)
// (the piecewise-constant 2D distribution in (u, v)): chi-square over the 512 texels, 2^18
// samples. Through Sample_Li and Sample_Le (which emits along -w).
TEST(Lights, EnvironmentMapSamplesFollowTheMapDistribution) {
    const TestScene& scene = map_scene();
    EnvReference env(scene.ds);
    const size_t n = 1 << 18;
    std::vector<double> expected(env.func.size());
    for (size_t i = 0; i < env.func.size(); ++i) expected[i] = double(n) * env.func[i] / env.sum;
    std::vector<double> obs_li(env.func.size(), 0.0), obs_le(env.func.size(), 0.0);
    for (const LiSample& x : sample_li(scene, kEnvironment, kRefs[1], n, 29)) obs_li[env.texel(x.wi)] += 1;
    for (const LeSample& x : sample_le(scene, kEnvironment, n, 31)) obs_le[env.texel(-x.dir)] += 1;
    expect_fit(obs_li, expected, "environment Sample_Li texels");
    expect_fit(obs_le, expected, "environment Sample_Le texels");
}

// The environment map's sampling distribution is the documented one (README "Environment
// maps", render/device_scene.h): Rec. 709 luminance x sin(theta) for the light tracer, and for
// bdpt and pt the luminance's excess over the map's mean radiance (texels weighted by sin theta),
// so that the texels at or below the mean are never sampled (on this map 204 of the 512 texels
// are above it: the spot and the brighter upper rows). Each weighting is checked against the
// texels that the kernel's Sample_Li picks (2^18 draws, chi-square; a sample in a texel of
// weight 0 fails at once); the other rule is rejected as well, so the test tells the two apart.
std::vector<double> documented_env_weights(const DeviceScene& ds, EnvironmentSampling how) {
    const int w = ds.info.env_width, h = ds.info.env_height;
    auto lum = [&](int x, int y) {
        const cl_float4& t = ds.env_texels[size_t(y) * w + x];
        return 0.2126 * t.s[0] + 0.7152 * t.s[1] + 0.0722 * t.s[2];
    };
    auto sin_theta = [&](int y) { return std::sin(kPi * (y + 0.5) / h); };
    double mean = 0, weight = 0;
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) mean += lum(x, y) * sin_theta(y), weight += sin_theta(y);
    mean = how == EnvironmentSampling::Compensated ? mean / weight : 0.0;
    std::vector<double> weights;
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) weights.push_back(std::max(lum(x, y) - mean, 0.0) * sin_theta(y));
    return weights;
}

ChiSquare env_texels_against(const TestScene& scene, const std::vector<double>& weights) {
    EnvReference env(scene.ds);
    const size_t n = 1 << 18;
    double sum = 0;
    for (double x : weights) sum += x;
    std::vector<double> expected(weights.size()), observed(weights.size(), 0.0);
    for (size_t i = 0; i < weights.size(); ++i) expected[i] = double(n) * weights[i] / sum;
    for (const LiSample& x : sample_li(scene, kEnvironment, kRefs[1], n, 29)) observed[env.texel(x.wi)] += 1;
    return chi_square(observed, expected);
}

TEST(Lights, EnvironmentMapSamplingFollowsDocumentedDistribution) {
    const TestScene& compensated = map_scene();
    const TestScene& by_luminance = luminance_map_scene();
    ASSERT_EQ(compensated.ds.env_sampling, EnvironmentSampling::Compensated);
    ASSERT_EQ(by_luminance.ds.env_sampling, EnvironmentSampling::Luminance);
    const std::vector<double> excess = documented_env_weights(compensated.ds, EnvironmentSampling::Compensated);
    const std::vector<double> luminance = documented_env_weights(compensated.ds, EnvironmentSampling::Luminance);
    const size_t above_mean = size_t(std::count_if(excess.begin(), excess.end(), [](double x) { return x > 0; }));
    EXPECT_GT(above_mean, 8u);
    EXPECT_LT(above_mean, excess.size() / 2);

    ChiSquare c = env_texels_against(compensated, excess);
    EXPECT_GT(c.p_value, kChiSquareSignificance) << "compensated: chi2 " << c.statistic << ", worst " << c.worst;
    c = env_texels_against(by_luminance, luminance);
    EXPECT_GT(c.p_value, kChiSquareSignificance) << "luminance: chi2 " << c.statistic << ", worst " << c.worst;
    EXPECT_LT(env_texels_against(compensated, luminance).p_value, kChiSquareSignificance);
    EXPECT_LT(env_texels_against(by_luminance, excess).p_value, kChiSquareSignificance);
}

// A map whose texels all equal their mean has no excess to sample: it is sampled by luminance.
TEST(Lights, ConstantEnvironmentMapIsSampledByLuminance) {
    EnvironmentMap map;
    map.width = 8;
    map.height = 4;
    map.rgb.assign(size_t(map.width) * map.height * 3, 0.75f);
    EXPECT_EQ(environment_distribution(map, EnvironmentSampling::Compensated),
              environment_distribution(map, EnvironmentSampling::Luminance));
    map.rgb[0] = 2.0f;  // one texel above the mean: only it is sampled
    const std::vector<float> d = environment_distribution(map, EnvironmentSampling::Compensated);
    EXPECT_GT(d[0], 0.0f);
    for (int i = 1; i < map.width * map.height; ++i) EXPECT_EQ(d[size_t(i)], 0.0f) << "texel " << i;
}

// environment_pdf_w is a normalised density: at texel centres it is func/(integral 2 pi^2
// sin theta), so sum over texels of pdf * sin(theta_c) * (pi/H) * (2 pi/W) = 1 exactly; float
// rounding over 512 texels: 1e-4. Each value also matches the port (1e-4 relative), and
// environment_radiance returns the texel times the scale.
TEST(Lights, EnvironmentPdfIsNormalised) {
    const TestScene& scene = map_scene();
    EnvReference env(scene.ds);
    std::vector<cl_float4> dirs;
    std::vector<D3> d;
    for (int y = 0; y < env.h; ++y)
        for (int x = 0; x < env.w; ++x) {
            double theta = kPi * (y + 0.5) / env.h, phi = 2 * kPi * (x + 0.5) / env.w;
            D3 w(std::sin(theta) * std::cos(phi), std::cos(theta), std::sin(theta) * std::sin(phi));
            d.push_back(as_float(w));
            dirs.push_back(f4(w));
        }
    cl::Kernel k = scene.kernel("kernels/lights_test.cl", "environment_eval_test");
    cl::Buffer in = upload(dirs), out = output_buffer<cl_float4>(dirs.size());
    k.setArg(SceneBuffers::kSceneArgCount, in);
    k.setArg(SceneBuffers::kSceneArgCount + 1, out);
    launch(k, dirs.size());
    std::vector<cl_float4> r = download<cl_float4>(out, dirs.size());
    double integral = 0;
    for (size_t i = 0; i < d.size(); ++i) {
        int y = int(i) / env.w;
        double st = std::sin(kPi * (y + 0.5) / env.h);
        integral += r[i].s[0] * st * (kPi / env.h) * (2 * kPi / env.w);
        EXPECT_LE(rel_diff(r[i].s[0], env.pdf_w(d[i])), kPdfTolerance) << "texel " << i;
        EXPECT_EQ(env.texel(d[i]), int(i));
        D3 radiance(r[i].s[1], r[i].s[2], r[i].s[3]);
        EXPECT_LE(length(radiance - 1.5 * d3(scene.ds.env_texels[i])), 1e-5 * length(radiance));
    }
    EXPECT_NEAR(integral, 1.0, 1e-4);
}

// Constant environment: uniform directions, pdf_w = 1/(4 pi), li = radiance.
TEST(Lights, ConstantEnvironmentIsUniform) {
    const TestScene& scene = constant_scene();
    ASSERT_EQ(scene.ds.info.env_width, 0);
    const size_t n = 1 << 17;
    std::vector<LiSample> s = sample_li(scene, kEnvironment, kRefs[0], n, 37);
    std::vector<double> obs(kRadial * kAngular, 0.0);
    for (const LiSample& x : s) {
        ASSERT_TRUE(x.ok);
        ASSERT_LE(rel_diff(x.pdf_w, 1 / (4 * kPi)), 1e-6);
        ASSERT_LE(rel_diff(x.pdf_eval, 1 / (4 * kPi)), 1e-6);
        ASSERT_LE(length(x.li - D3(1.5, 1.5, 1.5)), 1e-6);
        obs[polar_cell(0.5 * (1 - x.wi.z), x.wi)] += 1;
    }
    expect_uniform(obs, double(n), "constant environment directions");
    std::vector<LeSample> e = sample_le(scene, kEnvironment, 1024, 41);
    for (const LeSample& x : e) {
        ASSERT_LE(rel_diff(x.pdf_dir, 1 / (4 * kPi)), 1e-6);
        ASSERT_LE(rel_diff(x.pdf_dir_eval, 1 / (4 * kPi)), 1e-6);
    }
}

// Area light Sample_Le: origin on the triangle, pdf_pos = 1/A, cosine-distributed directions
// about the normal (chi-square in (cos^2 theta, phi), where the density is uniform), pdf_dir =
// cos/pi, both equal to light_pdf_le; le = Ke.
TEST(Lights, AreaSampleLe) {
    const TestScene& scene = map_scene();
    const size_t n = 1 << 17;
    const D3 nrm = area_normal();
    DFrame f(nrm);
    std::vector<LeSample> s = sample_le(scene, kArea, n, 43);
    std::vector<double> obs(kRadial * kAngular, 0.0);
    for (const LeSample& x : s) {
        ASSERT_TRUE(x.ok);
        ASSERT_LT(std::fabs(dot(x.origin - kAreaP0, nrm)), 1e-5);
        ASSERT_LT(length(x.n - nrm), 1e-5);
        double c = dot(x.dir, nrm);
        ASSERT_GT(c, 0);
        ASSERT_LE(rel_diff(x.pdf_pos, 1 / area_area()), kPdfTolerance);
        ASSERT_LE(rel_diff(x.pdf_pos_eval, x.pdf_pos), kPdfTolerance);
        ASSERT_LE(rel_diff(x.pdf_dir, c / kPi), kPdfTolerance);
        ASSERT_LE(rel_diff(x.pdf_dir_eval, x.pdf_dir), kPdfTolerance);
        ASSERT_LE(length(x.le - D3(4, 3, 2)), 1e-6);
        obs[polar_cell(c * c, f.to_local(x.dir))] += 1;
    }
    expect_uniform(obs, double(n), "area light emitted directions");
}

// Point Sample_Le: uniform sphere, pdf_dir 1/(4 pi) as light_pdf_le says. (pdf_pos: Sample_Le
// reports 1 and light_pdf_le 0 for a delta position, pbrt-v3's convention; neither enters a MIS
// weight, see mis_brute_force_test.cpp.)
TEST(Lights, PointSampleLe) {
    const TestScene& scene = map_scene();
    const size_t n = 1 << 17;
    std::vector<LeSample> s = sample_le(scene, kPoint, n, 47);
    std::vector<double> obs(kRadial * kAngular, 0.0);
    for (const LeSample& x : s) {
        ASSERT_TRUE(x.ok);
        ASSERT_LT(length(x.origin - as_float(kPointPos)), 1e-6);
        ASSERT_LE(rel_diff(x.pdf_dir, 1 / (4 * kPi)), 1e-6);
        ASSERT_LE(rel_diff(x.pdf_dir_eval, 1 / (4 * kPi)), 1e-6);
        ASSERT_LE(length(x.le - D3(10, 8, 6)), 1e-5);
        obs[polar_cell(0.5 * (1 - x.dir.z), x.dir)] += 1;
    }
    expect_uniform(obs, double(n), "point light directions");
}

// Spot Sample_Le: uniform in the cone (chi-square in ((1 - cos)/(1 - cos_total), phi)), pdf_dir =
// 1/(2 pi (1 - cos_total)) = light_pdf_le's, le = I falloff(dir).
TEST(Lights, SpotSampleLe) {
    const TestScene& scene = map_scene();
    const Light& spot = scene.ds.lights[kSpot];
    const size_t n = 1 << 17;
    const double cos_total = 1 - double(spot.one_minus_cos_total);
    EXPECT_NEAR(cos_total, std::cos(kSpotCone * kPi / 180), 1e-6);
    EXPECT_NEAR(1 - double(spot.one_minus_cos_falloff), std::cos((kSpotCone - kSpotDelta) * kPi / 180), 1e-6);
    DFrame f(d3(spot.direction));
    std::vector<LeSample> s = sample_le(scene, kSpot, n, 53);
    std::vector<double> obs(kRadial * kAngular, 0.0);
    for (const LeSample& x : s) {
        double c = dot(x.dir, d3(spot.direction));
        ASSERT_GE(c, cos_total - 1e-6);
        double expect = 1 / (2 * kPi * (1 - cos_total));
        ASSERT_LE(rel_diff(x.pdf_dir, expect), kPdfTolerance);
        ASSERT_LE(rel_diff(x.pdf_dir_eval, expect), kPdfTolerance);
        double falloff = spot_falloff(spot, x.dir);
        ASSERT_LE(length(x.le - D3(5, 4, 3) * falloff), 1e-4 * length(D3(5, 4, 3)));
        obs[polar_cell((1 - c) / (1 - cos_total), f.to_local(x.dir))] += 1;
    }
    expect_uniform(obs, double(n), "spot light directions");
}

// Lights at infinity emit from a disk of the scene's radius r perpendicular to the direction,
// r away from the centre toward the light: origin uniform on it (chi-square over (|offset|^2/r^2,
// phi)), pdf_pos = 1/(pi r^2) = light_pdf_le's. Directional: dir = the light's direction;
// environment: pdf_dir = light_pdf_le's = environment_pdf_w(-dir).
TEST(Lights, InfiniteLightsSampleLeFromTheBoundingDisk) {
    const TestScene& scene = map_scene();
    const size_t n = 1 << 17;
    D3 centre = d3(scene.ds.info.world_center);
    double r = scene.ds.info.world_center.s[3];
    for (int light : {int(kDirectional), int(kEnvironment)}) {
        std::vector<LeSample> s = sample_le(scene, light, n, 59 + light);
        std::vector<double> obs(kRadial * kAngular, 0.0);
        size_t compared = 0;
        EnvReference env(scene.ds);
        for (const LeSample& x : s) {
            ASSERT_TRUE(x.ok);
            D3 w_light = -x.dir;
            if (light == kDirectional) {
                ASSERT_LT(length(x.dir - kDirectionalDir), 1e-6);
            }
            D3 off = x.origin - centre;
            ASSERT_NEAR(dot(off, w_light), r, 1e-5 * r) << "origin not on the disk r from the centre";
            D3 lateral = off - dot(off, w_light) * w_light;
            ASSERT_LE(length(lateral), r * (1 + 1e-5));
            ASSERT_LE(rel_diff(x.pdf_pos, 1 / (kPi * r * r)), kPdfTolerance);
            ASSERT_LE(rel_diff(x.pdf_pos_eval, x.pdf_pos), kPdfTolerance);
            if (light == kEnvironment && !env.near_edge(w_light, 1e-4) && std::fabs(w_light.y) < 0.998) {
                ++compared;
                ASSERT_LE(rel_diff(x.pdf_dir, x.pdf_dir_eval), kPdfTolerance);
                ASSERT_LE(rel_diff(x.pdf_dir, env.pdf_w(w_light)), kPdfTolerance);
            }
            DFrame f(w_light);
            obs[polar_cell(dot(lateral, lateral) / (r * r), f.to_local(lateral))] += 1;
        }
        if (light == kEnvironment) {
            EXPECT_GT(compared, n * 9 / 10);
        }
        expect_uniform(obs, double(n), light == kDirectional ? "directional disk" : "environment disk");
    }
}

// light_scene with a spot among 5 lights, and a medium, which rules out NEE_EVERY_LIGHT, so a
// light sample from a point chooses its light by NEE_CONE_AWARE (nothing is in the medium).
const TestScene& cone_aware_scene() {
    static const TestScene scene = [] {
        Scene s = light_scene(true);
        MediumDesc fog;
        fog.name = "fog";
        fog.sigma_a = {0.1f, 0.1f, 0.1f};
        s.media.push_back(fog);
        return TestScene(s, 32, 32);
    }();
    return scene;
}

// Two area lights of different power, a point and a spot light: 3 light groups, so a light
// sample is taken of each (NEE_EVERY_LIGHT).
const TestScene& light_groups_scene() {
    static const TestScene scene = [] {
        Scene s = light_scene(false);
        int dim = add_material(s, make_material(MATERIAL_DIFFUSE, {0, 0, 0}, {}, {1, 1, 2}));
        add_triangle(s, {-1.6, 1.8, 0.4}, {-0.8, 1.8, 0.5}, {-1.2, 1.9, 1.2}, dim);
        s.lights.resize(2);  // point, spot
        return TestScene(s, 32, 32);
    }();
    return scene;
}

// Light selection by power: the index frequencies follow select_pdf (chi-square), the reported
// probability is the light's select_pdf, and select_pdf is proportional to Light::power.
TEST(Lights, SelectionFollowsSelectPdf) {
    const TestScene& scene = map_scene();
    const size_t n = 1 << 16;
    cl::Kernel k = scene.kernel("kernels/lights_test.cl", "light_select_test");
    cl::Buffer out = output_buffer<cl_float2>(n);
    k.setArg(SceneBuffers::kSceneArgCount, cl_uint(61));
    k.setArg(SceneBuffers::kSceneArgCount + 1, out);
    launch(k, n);
    std::vector<cl_float2> r = download<cl_float2>(out, n);
    const std::vector<Light>& lights = scene.ds.lights;
    std::vector<double> obs(lights.size(), 0.0), expected(lights.size());
    double power = 0;
    for (float p : scene.ds.light_power) power += p;
    for (size_t i = 0; i < lights.size(); ++i) {
        expected[i] = double(n) * lights[i].select_pdf;
        EXPECT_LE(rel_diff(lights[i].select_pdf, scene.ds.light_power[i] / power), 1e-5);
    }
    for (const cl_float2& x : r) {
        int i = int(x.s[0]);
        ASSERT_GE(i, 0);
        ASSERT_LT(i, int(lights.size()));
        ASSERT_EQ(x.s[1], lights[i].select_pdf);
        obs[i] += 1;
    }
    expect_fit(obs, expected, "light selection");
}

// A light sample from a point (NEE_CONE_AWARE: this scene has a spot among 5 lights, and a
// medium, which rules out NEE_EVERY_LIGHT; nothing is in the medium) picks lights in proportion
// to select_pdf, but a spot by 4 pi I over the total power where its cone holds the point and
// never where it does not (chi-square on the index frequencies); it reports that probability,
// and light_sample_selection_ratio is it over select_pdf.
TEST(Lights, LightSampleSkipsSpotsThatCannotReachThePoint) {
    const TestScene& scene = cone_aware_scene();
    ASSERT_NE(std::find(scene.defines.begin(), scene.defines.end(), "NEE_CONE_AWARE"), scene.defines.end());
    ASSERT_EQ(std::find(scene.defines.begin(), scene.defines.end(), "NEE_EVERY_LIGHT"), scene.defines.end());
    const std::vector<Light>& lights = scene.ds.lights;
    double total_power = 0;
    for (float p : scene.ds.light_power) total_power += p;
    const D3 spot_axis = normalize(kSpotTarget - kSpotPos);
    const D3 inside = kSpotPos + 2.5 * spot_axis;                      // on the cone's axis
    const D3 outside = kSpotPos + 2.5 * normalize(D3(1, -0.2, 0.1));   // 80 degrees off it
    for (D3 x : {inside, outside}) {
        const bool in_cone = dot(normalize(x - kSpotPos), spot_axis) >= 1 - double(lights[kSpot].one_minus_cos_total);
        ASSERT_EQ(in_cone, x.x == inside.x);
        std::vector<double> weight(lights.size());
        double total = 0;
        for (size_t i = 0; i < lights.size(); ++i) {
            weight[i] = lights[i].select_pdf;
            if (int(i) == kSpot) weight[i] = in_cone ? 4 * kPi * luminance({5, 4, 3}) / total_power : 0.0;
            total += weight[i];
        }
        const size_t n = 1 << 16;
        cl::Kernel k = scene.kernel("kernels/lights_test.cl", "light_select_at_point_test");
        k.setArg(SceneBuffers::kSceneArgCount, cl_uint(73));
        k.setArg(SceneBuffers::kSceneArgCount + 1, cl_float4{{float(x.x), float(x.y), float(x.z), 0.0f}});
        cl::Buffer out = output_buffer<cl_float4>(n);
        k.setArg(SceneBuffers::kSceneArgCount + 2, out);
        launch(k, n);
        std::vector<double> obs(lights.size(), 0.0), expected(lights.size());
        for (const cl_float4& r : download<cl_float4>(out, n)) {
            const int i = int(r.s[0]);
            ASSERT_GE(i, 0);
            ASSERT_LT(i, int(lights.size()));
            ASSERT_GT(weight[size_t(i)], 0.0) << "picked light " << i << ", which cannot reach the point";
            ASSERT_LE(rel_diff(r.s[1], weight[size_t(i)] / total), 1e-5);
            ASSERT_LE(rel_diff(r.s[2], weight[size_t(i)] / total / lights[size_t(i)].select_pdf), 1e-5);
            obs[size_t(i)] += 1;
        }
        for (size_t i = 0; i < lights.size(); ++i) expected[i] = double(n) * weight[i] / total;
        if (!in_cone) expected.erase(expected.begin() + kSpot), obs.erase(obs.begin() + kSpot);
        expect_fit(obs, expected, in_cone ? "light sample inside the cone" : "light sample outside the cone");
    }
}

// Two area lights of different power, a point and a spot light: 3 light groups, so a light
// sample is taken of each (NEE_EVERY_LIGHT). Group 0 picks an area light by select_pdf among
// the area lights (chi-square on the index frequencies), group 1 is the point light and group 2
// the spot, each with probability 1, the spot only inside its cone; each reports its
// probability, and light_sample_selection_ratio is it over select_pdf.
TEST(Lights, LightSamplesTakeEveryLightGroup) {
    const TestScene& scene = light_groups_scene();
    const std::vector<std::string>& flags = scene.defines;
    ASSERT_NE(std::find(flags.begin(), flags.end(), "NEE_EVERY_LIGHT"), flags.end());
    ASSERT_EQ(std::find(flags.begin(), flags.end(), "NEE_CONE_AWARE"), flags.end());
    const std::vector<Light>& lights = scene.ds.lights;
    ASSERT_EQ(lights.size(), 4u);
    ASSERT_EQ(scene.ds.info.area_light_count, 2);
    ASSERT_EQ(lights[2].kind, LIGHT_POINT);
    ASSERT_EQ(lights[3].kind, LIGHT_SPOT);
    const double area_total = double(lights[0].select_pdf) + lights[1].select_pdf;
    const D3 spot_axis = normalize(kSpotTarget - kSpotPos);
    const D3 inside = kSpotPos + 2.5 * spot_axis;
    const D3 outside = kSpotPos + 2.5 * normalize(D3(1, -0.2, 0.1));
    for (D3 x : {inside, outside}) {
        const bool in_cone = x.x == inside.x;
        const size_t n = 1 << 14;
        cl::Kernel k = scene.kernel("kernels/lights_test.cl", "light_groups_at_point_test");
        k.setArg(SceneBuffers::kSceneArgCount, cl_uint(79));
        k.setArg(SceneBuffers::kSceneArgCount + 1, cl_float4{{float(x.x), float(x.y), float(x.z), 0.0f}});
        cl::Buffer out = output_buffer<cl_float4>(4 * n);
        k.setArg(SceneBuffers::kSceneArgCount + 2, out);
        launch(k, n);
        std::vector<cl_float4> r = download<cl_float4>(out, 4 * n);
        std::vector<double> obs(2, 0.0);
        for (size_t j = 0; j < n; ++j) {
            const cl_float4* g = &r[4 * j];
            ASSERT_EQ(g[0].s[3], 3.0f) << "light groups";
            const int area = int(g[0].s[0]);
            ASSERT_TRUE(area == 0 || area == 1) << area;
            const double p = lights[size_t(area)].select_pdf / area_total;
            ASSERT_LE(rel_diff(g[0].s[1], p), 1e-5);
            ASSERT_LE(rel_diff(g[0].s[2], p / lights[size_t(area)].select_pdf), 1e-5);
            obs[size_t(area)] += 1;
            ASSERT_EQ(int(g[1].s[0]), 2);
            ASSERT_EQ(g[1].s[1], 1.0f);
            ASSERT_LE(rel_diff(g[1].s[2], 1.0 / lights[2].select_pdf), 1e-5);
            if (in_cone) {
                ASSERT_EQ(int(g[2].s[0]), 3);
                ASSERT_EQ(g[2].s[1], 1.0f);
                ASSERT_LE(rel_diff(g[2].s[2], 1.0 / lights[3].select_pdf), 1e-5);
            } else {
                ASSERT_EQ(int(g[2].s[0]), -1) << "the spot cannot reach the point";
            }
        }
        expect_fit(obs, {double(n) * lights[0].select_pdf / area_total, double(n) * lights[1].select_pdf / area_total},
                   "area light picks");
    }
}

// A light choice hands what is left of its draw to the chosen light's point (rest_of_choice):
// on n evenly spaced draws, each light's rests are evenly spaced over [0, 1) too, as many in
// every sixteenth of it within rounding (a count off by at most 2), for the choice by power
// (light subpaths), the choice from a point (NEE_CONE_AWARE) and the area lights' group
// (NEE_EVERY_LIGHT). Then a stratified 2D light draw stays stratified over the lights' points
// together. Handing on the draw itself, as before, puts each light's values in its own
// interval of the CDF and fails every light's bins but one's.
TEST(Lights, ChoiceLeavesItsDrawStratifiedForThePoint) {
    constexpr int kBins = 16;
    constexpr cl_uint n = 1 << 14;
    const D3 x = kSpotPos + 2.5 * normalize(kSpotTarget - kSpotPos);  // inside the spot's cone
    // map_scene has one area light, the only one its group 0 (NEE_EVERY_LIGHT) can pick.
    const std::pair<const TestScene*, size_t> scenes[] = {{&map_scene(), 1}, {&cone_aware_scene(), 5}, {&light_groups_scene(), 2}};
    for (const auto& [scene, lights_from_point] : scenes) {
        cl::Kernel k = scene->kernel("kernels/lights_test.cl", "light_choice_rest_test");
        k.setArg(SceneBuffers::kSceneArgCount, n);
        k.setArg(SceneBuffers::kSceneArgCount + 1, cl_float4{{float(x.x), float(x.y), float(x.z), 0.0f}});
        cl::Buffer out = output_buffer<cl_float4>(n);
        k.setArg(SceneBuffers::kSceneArgCount + 2, out);
        launch(k, n);
        const std::vector<cl_float4> r = download<cl_float4>(out, n);
        for (int choice : {0, 1}) {
            std::map<int, std::vector<int>> bins;  // light -> counts per bin of its rests
            for (const cl_float4& v : r) {
                const int light = int(v.s[2 * choice]);
                const float rest = v.s[2 * choice + 1];
                ASSERT_GE(light, 0);
                ASSERT_GE(rest, 0.0f);
                ASSERT_LT(rest, 1.0f);
                std::vector<int>& b = bins[light];
                b.resize(kBins);
                ++b[size_t(std::min(kBins - 1, int(rest * kBins)))];
            }
            ASSERT_EQ(bins.size(), choice ? lights_from_point : scene->ds.lights.size()) << "lights picked";
            for (const auto& [light, counts] : bins) {
                const auto [lo, hi] = std::minmax_element(counts.begin(), counts.end());
                EXPECT_LE(*hi - *lo, 2) << (choice ? "choice from a point" : "choice by power") << ", light " << light
                                        << ": rests per bin from " << *lo << " to " << *hi;
            }
        }
    }
}

}  // namespace
}  // namespace clbdpt::test
