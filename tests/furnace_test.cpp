// White furnace: a closed sphere seen from its centre, every triangle a Lambertian reflector
// of albedo a that also emits Le from its inside face. The radiance field inside is uniform, so
// a path of k bounces carries Le a^k in every direction, and with at most d scattering
// vertices every pixel is exactly
//     L = Le * sum_{k=0..d} a^k
// whatever the strategies: a check of the absolute scale of every (s, t) strategy, of MIS
// weights summing to one, and of the light tracer's splat normalisation (lt at d = 0 sees the
// emitters only through its (1,1) strategy).
#include <gtest/gtest.h>

#include <cmath>
#include <tuple>

#include "test_scenes.h"

namespace clbdpt::test {
namespace {

const Vec3 kLe{0.8f, 1.0f, 0.6f};
const Vec3 kAlbedo{0.5f, 0.7f, 0.3f};  // per channel, so a channel mix-up shows
constexpr int kFilm = 16;
constexpr int kBlocks = 4;
constexpr int kPasses = 48;

// Tolerance: 16 regions and the image mean per render, 15 renders, so about 250 comparisons.
// At 4.5 standard errors a correct renderer fails one with probability ~250 * 6.8e-6 = 1.7e-3
// under a normal model (the seeds are fixed, so a pass stays a pass). With 48 passes the
// standard error is itself estimated from 47 degrees of freedom; Student's t puts the same
// 4.5 at about 5e-5 per comparison, ~1% for the whole set, still rare. A real error of the
// scale of one strategy (a factor pi, a missing cosine) is tens to hundreds of standard errors.
// pt at d = 0 is deterministic (every camera ray hits an emitter); the 1e-5 relative floor in
// expect_matches covers float rounding there.
constexpr double kSigmas = 4.5;

Scene furnace_scene() {
    SceneBuilder b;
    int m = b.material(diffuse_material(kAlbedo, kLe), "furnace");
    b.sphere({0, 0, 0}, 1.0f, 2, /*inward=*/true, m);  // 320 triangles
    b.camera({0, 0, 0}, {0.2f, 0.1f, 1}, 90.0f);
    b.scene.width = b.scene.height = kFilm;
    return b.scene;
}

double furnace_value(int max_depth) {
    double sum = 0;
    for (int c = 0; c < 3; ++c) {
        double a = kAlbedo[c], ak = 1, s = 0;
        for (int k = 0; k <= max_depth; ++k, ak *= a) s += ak;
        sum += kLe[c] * s;
    }
    return sum / 3.0;  // render_region_stats averages the channels
}

struct FurnaceCase {
    Integrator integrator;
    SamplerKind sampler;
    int max_depth;
};

class FurnaceTest : public ::testing::TestWithParam<FurnaceCase> {};

TEST_P(FurnaceTest, EveryPixelIsTheGeometricSeries) {
    const FurnaceCase c = GetParam();
    static const DeviceScene scene = build_device_scene(furnace_scene(), kFilm, kFilm);
    RenderOptions options = make_options(c.integrator, c.max_depth, 11 + uint32_t(c.max_depth), c.sampler);
    options.spp = scaled_passes(kPasses);  // ZSobol orders this many samples per pixel
    const std::string what = options_name(options);
    // The Sobol samplers' passes are stratified, not independent: the spread of per-pass
    // values overestimates the standard error of their mean, so its comparison is conservative.
    RegionStats st = render_stats_or_fail(scene, options, scaled_passes(kPasses), kBlocks, what);
    const double expected = furnace_value(c.max_depth);
    expect_matches(st, expected, kSigmas, what + " vs analytic");
    // Sanity of the statistics themselves: the estimate is not trivially zero or wild.
    EXPECT_GT(st.image_mean, 0.5 * expected) << what;
}

std::vector<FurnaceCase> furnace_cases() {
    std::vector<FurnaceCase> cases;
    for (int d : {0, 1, 3}) {
        cases.push_back({Integrator::Bdpt, SamplerKind::Independent, d});
        cases.push_back({Integrator::Pt, SamplerKind::Independent, d});
        cases.push_back({Integrator::Lt, SamplerKind::Independent, d});
        cases.push_back({Integrator::Bdpt, SamplerKind::Sobol, d});
    }
    cases.push_back({Integrator::Bdpt, SamplerKind::ZSobol, 3});
    cases.push_back({Integrator::Pt, SamplerKind::ZSobol, 3});
    return cases;
}

INSTANTIATE_TEST_SUITE_P(Integrators, FurnaceTest, ::testing::ValuesIn(furnace_cases()),
                         [](const ::testing::TestParamInfo<FurnaceCase>& info) {
                             std::string n = integrator_name(info.param.integrator);
                             if (info.param.sampler != SamplerKind::Independent)
                                 n += std::string("_") + sampler_name(info.param.sampler);
                             return n + "_depth" + std::to_string(info.param.max_depth);
                         });

// The same furnace as a box (flat walls meeting at edges and corners, where ray offsets and
// watertightness are tested) at max depth 3 (the sphere's kernels), every integrator.
class BoxFurnaceTest : public ::testing::TestWithParam<Integrator> {};

TEST_P(BoxFurnaceTest, EveryPixelIsTheGeometricSeries) {
    SceneBuilder b;
    int m = b.material(diffuse_material(kAlbedo, kLe), "furnace");
    b.box({-1, -0.7f, -1.3f}, {1, 0.7f, 1.3f}, /*inward=*/true, m);
    b.camera({0.3f, 0.2f, -0.9f}, {-0.4f, -0.3f, 1}, 100.0f);
    static const DeviceScene scene = build_device_scene(b.scene, kFilm, kFilm);
    RenderOptions options = make_options(GetParam(), 3, 21);
    const std::string what = std::string("box ") + options_name(options);
    RegionStats st = render_stats_or_fail(scene, options, scaled_passes(kPasses), kBlocks, what);
    expect_matches(st, furnace_value(3), kSigmas, what + " vs analytic");
}

INSTANTIATE_TEST_SUITE_P(Integrators, BoxFurnaceTest, ::testing::Values(Integrator::Bdpt, Integrator::Pt, Integrator::Lt),
                         [](const ::testing::TestParamInfo<Integrator>& info) {
                             return std::string(integrator_name(info.param));
                         });

// ---- Glossy furnace -----------------------------------------------------------------------

// The furnace sphere made of a lossless conductor: the glossy material with ks = 1, kd = 0 and
// alpha 0.3 (GGX, no Fresnel: reflectance 1), emitting Le inside. Single-scattering GGX loses
// the energy of light that would scatter between microfacets, more at grazing angles, so the
// field is no longer uniform: a path of k bounces carries between Le E_min^k and Le E_max^k,
// where E(mu) is the lobe's directional albedo (integrated on the host below, in double). Every
// pixel lies between Le sum E_min^k and Le sum E_max^k, and bdpt, pt and lt agree.
constexpr float kGlossyAlpha = 0.3f;

// Directional albedo of the GGX lobe (D G / (4 cos_o cos_i), Smith G) for cos theta_o = mu,
// by a midpoint rule over the hemisphere of wi (800 x 400 cells; the lobe is 0.3 rad wide).
double ggx_albedo(double mu, double alpha) {
    const double pi = 3.14159265358979323846;
    auto lambda = [&](double c) {
        double t2 = (1 - c * c) / (c * c);
        return 0.5 * (-1 + std::sqrt(1 + alpha * alpha * t2));
    };
    const double so = std::sqrt(1 - mu * mu);
    const int nt = 400, np = 800;
    double sum = 0;
    for (int i = 0; i < nt; ++i) {
        const double theta = (i + 0.5) * (pi / 2) / nt, ci = std::cos(theta), si = std::sin(theta);
        for (int j = 0; j < np; ++j) {
            const double phi = (j + 0.5) * 2 * pi / np;
            // wo = (so, 0, mu), wi = (si cos phi, si sin phi, ci); h = normalize(wo + wi).
            double hx = so + si * std::cos(phi), hy = si * std::sin(phi), hz = mu + ci;
            double hl = std::sqrt(hx * hx + hy * hy + hz * hz);
            double ch = hz / hl, c2 = ch * ch, a2 = alpha * alpha;
            double e = 1 + (1 - c2) / c2 / a2;
            double d = 1 / (pi * a2 * c2 * c2 * e * e);
            double g = 1 / (1 + lambda(mu) + lambda(ci));
            sum += d * g / (4 * mu * ci) * ci * si;
        }
    }
    return sum * (pi / 2 / nt) * (2 * pi / np);
}

TEST(GlossyFurnace, EveryPixelWithinTheLobesAlbedoBoundsAndIntegratorsAgree) {
    const int depth = 3;
    SceneBuilder b;
    Material m = diffuse_material({0, 0, 0}, kLe);
    m.kind = MATERIAL_GLOSSY;
    m.ks = float4_of({1, 1, 1});
    m.alpha = kGlossyAlpha;
    int furnace = b.material(m, "conductor furnace");
    b.sphere({0, 0, 0}, 1.0f, 2, /*inward=*/true, furnace);
    b.camera({0.1f, -0.2f, 0.15f}, {0.2f, 0.1f, 1}, 90.0f);
    const DeviceScene scene = build_device_scene(b.scene, kFilm, kFilm);
    double albedo_lo = 1, albedo_hi = 0;
    for (double mu = 0.02; mu <= 1.0; mu += 0.02) {
        double e = ggx_albedo(mu, kGlossyAlpha);
        albedo_lo = std::min(albedo_lo, e);
        albedo_hi = std::max(albedo_hi, e);
    }
    // No albedo above 1 (the lobe conserves energy), and a real loss somewhere.
    ASSERT_LE(albedo_hi, 1.0 + 1e-3);
    ASSERT_LT(albedo_lo, 0.95);
    auto series = [&](double e) {
        double sum = 0, ek = 1;
        for (int k = 0; k <= depth; ++k, ek *= e) sum += ek;
        return sum * (kLe[0] + kLe[1] + kLe[2]) / 3.0;
    };
    const double lo = series(albedo_lo), hi = series(albedo_hi);
    RegionStats bdpt;
    for (Integrator integrator : {Integrator::Bdpt, Integrator::Pt, Integrator::Lt}) {
        RenderOptions options = make_options(integrator, depth, 31 + uint32_t(integrator));
        const std::string what = std::string("glossy ") + options_name(options);
        RegionStats st = render_stats_or_fail(scene, options, scaled_passes(kPasses), kBlocks, what);
        double worst = 0;
        for (size_t r = 0; r <= st.mean.size(); ++r) {
            bool image = r == st.mean.size();
            double v = image ? st.image_mean : st.mean[r], se = image ? st.image_std_error : st.std_error[r];
            double z = std::max({0.0, (lo - v) / se, (v - hi) / se});
            if (!std::isfinite(z)) z = INFINITY;
            worst = std::max(worst, z);
            EXPECT_LE(z, kSigmas) << what << (image ? " image" : " region " + std::to_string(r)) << ": " << v
                                  << " +- " << se << " outside [" << lo << ", " << hi << "]";
        }
        report_stat(what + " within albedo bounds", worst, kSigmas, worst <= kSigmas);
        if (integrator == Integrator::Bdpt) bdpt = st;
        else expect_agree(st, bdpt, kSigmas, what + " vs bdpt");
    }
}

}  // namespace
}  // namespace clbdpt::test
