// cl/bsdf.h through cl/kernels/bsdf_test.cl: for every material kind and both transport modes,
//  - bsdf_sample's pdf and f equal bsdf_pdf and bsdf_f evaluated separately;
//  - bsdf_pdf and bsdf_f equal a double-precision port of the formulas (README "Materials");
//  - the sampled directions follow bsdf_pdf (chi-square; the mass the sampler loses below the
//    horizon is a cell of its own, so the pdf's normalisation is tested too);
//  - mirror and glass: the reflection law, Snell's law, the Fresnel lobe probabilities and the
//    lobe weights (with the (eta_i/eta_t)^2 radiance scaling on refraction only in radiance mode).
#include <gtest/gtest.h>

#include <cstring>
#include <functional>

#include "kernel_test_util.h"

namespace clbdpt::test {
namespace {

constexpr int kRadiance = 0;   // TRANSPORT_RADIANCE
constexpr int kImportance = 1; // TRANSPORT_IMPORTANCE

// The tests give shading normals apart from geometric ones, so the kernels are built as for a
// scene with shading normals (without them, bsdf_f leaves out the geometric side test, which is
// then the same test: FlatShadingDropsOnlyARepeatedTest).
const std::vector<std::string> kDefines = {"HAS_GLOSSY", "HAS_MIRROR", "HAS_GLASS", "HAS_SHADING_NORMALS"};

// ---- Reference formulas in double (the README's material model, pbrt-v3 microfacet.cpp) ----

double luminance(D3 c) { return 0.2126 * c.x + 0.7152 * c.y + 0.0722 * c.z; }

double ggx_d(double cos_h, double alpha) {
    double c2 = cos_h * cos_h;
    if (c2 == 0) return 0;
    double a2 = alpha * alpha, tan2 = (1 - c2) / c2, e = 1 + tan2 / a2;
    return 1 / (kPi * a2 * c2 * c2 * e * e);
}

double ggx_lambda(double cos_t, double alpha) {
    double c2 = cos_t * cos_t;
    if (c2 == 0) return 0;
    double tan2 = (1 - c2) / c2;
    return 0.5 * (-1 + std::sqrt(1 + alpha * alpha * tan2));
}

struct RefBsdf {
    int kind;
    D3 kd, ks;
    double alpha = 0.1, ior = 1.5;
    D3 n;  // shading = geometric normal in these tests

    double p_diffuse() const {
        double d = luminance(kd), s = luminance(ks);
        return kind == MATERIAL_GLOSSY ? (d + s > 0 ? d / (d + s) : 1.0) : 1.0;
    }
    // The visible normals' density (Heitz 2018) carried to wi: G1(wo) D(h) / (4 |cos theta_o|).
    double glossy_pdf(D3 wo, D3 wi) const {
        D3 h = normalize(wo + wi);
        const double co = dot(wo, n);
        return ggx_d(dot(h, n), alpha) / ((1 + ggx_lambda(co, alpha)) * 4 * std::fabs(co));
    }
    double pdf(D3 wo, D3 wi) const {
        double co = dot(wo, n), ci = dot(wi, n);
        if (co * ci <= 0) return 0;
        double pd = p_diffuse();
        double p = pd * std::fabs(ci) / kPi;
        if (kind == MATERIAL_GLOSSY && pd < 1) p += (1 - pd) * glossy_pdf(wo, wi);
        return p;
    }
    D3 f(D3 wo, D3 wi) const {
        double co = dot(wo, n), ci = dot(wi, n);
        if (co * ci <= 0) return {};
        D3 r = kd / kPi;
        if (kind == MATERIAL_GLOSSY) {
            D3 h = normalize(wo + wi);
            double g = 1 / (1 + ggx_lambda(co, alpha) + ggx_lambda(ci, alpha));
            r = r + ks * (ggx_d(dot(h, n), alpha) * g / (4 * std::fabs(co) * std::fabs(ci)));
        }
        return r;
    }
};

// Unpolarised Fresnel reflectance of a dielectric (pbrt-v3 FrDielectric), cos_i > 0 outside.
double fresnel(double cos_i, double eta_inside) {
    double eta_i = 1, eta_t = eta_inside;
    if (cos_i < 0) {
        std::swap(eta_i, eta_t);
        cos_i = -cos_i;
    }
    double sin_t = eta_i / eta_t * std::sqrt(std::max(0.0, 1 - cos_i * cos_i));
    if (sin_t >= 1) return 1;
    double cos_t = std::sqrt(std::max(0.0, 1 - sin_t * sin_t));
    double rpar = (eta_t * cos_i - eta_i * cos_t) / (eta_t * cos_i + eta_i * cos_t);
    double rper = (eta_i * cos_i - eta_t * cos_t) / (eta_i * cos_i + eta_t * cos_t);
    return 0.5 * (rpar * rpar + rper * rper);
}

// ---- Running the kernels ---------------------------------------------------------------------

struct Sample {
    D3 wi;
    double pdf;
    D3 f;
    bool ok, specular;
    double pdf_eval;
    D3 f_eval;
};

std::vector<Sample> sample_bsdf(const Material& m, D3 n, D3 wo, int mode, size_t count, uint32_t seed,
                                const D3* geometric_normal = nullptr) {
    std::vector<Material> materials = {m};
    cl::Buffer mat = upload(materials);
    cl::Buffer out = output_buffer<cl_float4>(3 * count);
    cl::Kernel k = test_kernel("kernels/bsdf_test.cl", kDefines, "bsdf_sample_test");
    k.setArg(0, mat);
    k.setArg(1, cl_int(0));
    k.setArg(2, f4(n));
    k.setArg(3, f4(geometric_normal ? *geometric_normal : n));
    k.setArg(4, f4(wo));
    k.setArg(5, cl_int(mode));
    k.setArg(6, cl_uint(seed));
    k.setArg(7, out);
    launch(k, count);
    std::vector<cl_float4> raw = download<cl_float4>(out, 3 * count);
    std::vector<Sample> s(count);
    for (size_t i = 0; i < count; ++i) {
        const cl_float4* r = &raw[3 * i];
        s[i].wi = d3(r[0]);
        s[i].pdf = r[0].s[3];
        s[i].f = d3(r[1]);
        int flags = int(r[1].s[3]);
        s[i].ok = flags & 1;
        s[i].specular = flags & 2;
        s[i].pdf_eval = r[2].s[0];
        s[i].f_eval = {r[2].s[1], r[2].s[2], r[2].s[3]};
    }
    return s;
}

// bsdf_eval_test over n direction pairs: per pair (bsdf_pdf, bsdf_f) as (pdf, f.x, f.y, f.z).
std::vector<cl_float4> eval_bsdf(const Material& m, D3 ns, D3 ng, const cl::Buffer& wo, const cl::Buffer& wi, size_t n,
                                 const std::vector<std::string>& defines = kDefines) {
    std::vector<Material> materials = {m};
    cl::Buffer mat = upload(materials);
    cl::Buffer out = output_buffer<cl_float4>(n);
    cl::Kernel k = test_kernel("kernels/bsdf_test.cl", defines, "bsdf_eval_test");
    k.setArg(0, mat);
    k.setArg(1, cl_int(0));
    k.setArg(2, f4(ns));
    k.setArg(3, f4(ng));
    k.setArg(4, wo);
    k.setArg(5, wi);
    k.setArg(6, out);
    launch(k, n);
    return download<cl_float4>(out, n);
}

// Unit vector at angle theta from n (theta > pi/2: below the surface).
D3 direction_at(D3 n, double theta, double phi) {
    return normalize(DFrame(n).from_local(spherical(std::cos(theta), phi)));
}

// The tilted normal every test uses, so no frame is axis-aligned by accident.
const D3 kNormal = normalize(D3(0.3, 0.8, -0.5));

struct Lobe {
    const char* name;
    Material material;
    RefBsdf ref;
};

Lobe make_lobe(const char* name, int kind, D3 kd, D3 ks, double alpha) {
    Lobe l{name, make_material(kind, kd, ks, {}, float(alpha)), {}};
    l.ref.kind = kind;
    l.ref.kd = kd;
    l.ref.ks = ks;
    l.ref.alpha = double(float(alpha));
    l.ref.n = as_float(kNormal);
    return l;
}

std::vector<Lobe> non_delta_lobes() {
    return {
        make_lobe("diffuse", MATERIAL_DIFFUSE, {0.5, 0.6, 0.7}, {}, 0.1),
        make_lobe("glossy a=0.5 + diffuse", MATERIAL_GLOSSY, {0.2, 0.25, 0.3}, {0.5, 0.5, 0.4}, 0.5),
        make_lobe("glossy a=0.2", MATERIAL_GLOSSY, {0, 0, 0}, {0.9, 0.8, 0.7}, 0.2),
        make_lobe("glossy a=0.05", MATERIAL_GLOSSY, {0, 0, 0}, {0.8, 0.8, 0.8}, 0.05),
        make_lobe("glossy a=0.05 + diffuse", MATERIAL_GLOSSY, {0.3, 0.2, 0.1}, {0.5, 0.6, 0.7}, 0.05),
    };
}

// Outgoing directions: near normal, oblique, grazing, and from below the surface.
const std::vector<double> kWoThetaDegrees = {25, 60, 84, 130};

// ---- Chi-square binning ------------------------------------------------------------------------
// Cells are rings around a centre direction (the mirror direction of wo, where a glossy lobe
// peaks) times sectors in azimuth. Ring edges grow quadratically in angle (theta_k = pi (k/R)^2),
// so a lobe of width 0.05 rad still spreads over several rings while the far rings stay large.
// Expected counts come from nested adaptive Gauss-Legendre integration of the reference pdf over
// each cell, clipped analytically to wo's hemisphere (the pdf jumps to 0 at the horizon, which
// cuts through cells; clipping keeps the integrand smooth, so the quadrature converges fast).

constexpr int kRings = 20, kSectors = 24;

double ring_edge(int k) { return kPi * double(k) * k / (double(kRings) * kRings); }

struct Binning {
    DFrame frame;
    explicit Binning(D3 centre) : frame(centre) {}
    int cell(D3 w) const {
        D3 l = frame.to_local(w);
        double theta = std::acos(std::clamp(l.z, -1.0, 1.0));
        double phi = std::atan2(l.y, l.x);
        if (phi < 0) phi += 2 * kPi;
        int ring = std::min(kRings - 1, int(std::sqrt(theta / kPi) * kRings));
        // Guard the floating-point edge cases of the inverse of ring_edge.
        while (ring > 0 && theta < ring_edge(ring)) --ring;
        while (ring < kRings - 1 && theta >= ring_edge(ring + 1)) ++ring;
        int sector = std::min(kSectors - 1, int(phi / (2 * kPi) * kSectors));
        return ring * kSectors + sector;
    }
    D3 dir(double theta, double phi) const { return frame.from_local(spherical(std::cos(theta), phi)); }
};

// 4-point Gauss-Legendre on [-1, 1].
constexpr double kGlX[4] = {-0.8611363115940526, -0.3399810435848563, 0.3399810435848563, 0.8611363115940526};
constexpr double kGlW[4] = {0.3478548451374538, 0.6521451548625461, 0.6521451548625461, 0.3478548451374538};

template <typename F>
double gl4(const F& f, double a, double b) {
    double m = 0.5 * (a + b), h = 0.5 * (b - a), s = 0;
    for (int i = 0; i < 4; ++i) s += kGlW[i] * f(m + h * kGlX[i]);
    return s * h;
}

// Adaptive 1D Gauss-Legendre: halves until the two halves agree with the whole to tol.
template <typename F>
double adaptive_gl(const F& f, double a, double b, double whole, double tol, int depth = 0) {
    double m = 0.5 * (a + b);
    double l = gl4(f, a, m), r = gl4(f, m, b);
    if (depth >= 14 || (depth >= 1 && std::fabs(l + r - whole) < tol)) return l + r;
    return adaptive_gl(f, a, m, l, 0.5 * tol, depth + 1) + adaptive_gl(f, m, b, r, 0.5 * tol, depth + 1);
}

template <typename F>
double integrate(const F& f, double a, double b, double tol) {
    return a < b ? adaptive_gl(f, a, b, gl4(f, a, b), tol) : 0.0;
}

using DirPdf = std::function<double(D3)>;

// Probability of every cell under `pdf`, a solid-angle density supported on the hemisphere
// {w : dot(w, up) > 0}.
std::vector<double> cell_probabilities(const Binning& b, const DirPdf& pdf, D3 up, double tol) {
    // dot(dir(theta, phi), up) = A cos(theta) + B sin(theta) cos(phi - phi0).
    D3 l = b.frame.to_local(up);
    double A = l.z, B = std::hypot(l.x, l.y), phi0 = std::atan2(l.y, l.x);
    std::vector<double> p(kRings * kSectors);
    for (int r = 0; r < kRings; ++r)
        for (int s = 0; s < kSectors; ++s) {
            double t0 = ring_edge(r), t1 = ring_edge(r + 1);
            double p0 = 2 * kPi * s / kSectors, p1 = 2 * kPi * (s + 1) / kSectors;
            auto ring = [&](double theta) {
                auto f = [&](double phi) { return pdf(b.dir(theta, phi)); };
                double bs = B * std::sin(theta), ac = A * std::cos(theta);
                double sum = 0;
                if (bs <= std::fabs(ac) * 1e-15) return ac > 0 ? integrate(f, p0, p1, tol) : 0.0;
                double x = -ac / bs;  // above the horizon where cos(phi - phi0) > x
                if (x <= -1) return integrate(f, p0, p1, tol);
                if (x >= 1) return 0.0;
                double half = std::acos(x);
                for (int k = -1; k <= 1; ++k) {
                    double lo = std::max(p0, phi0 + 2 * kPi * k - half), hi = std::min(p1, phi0 + 2 * kPi * k + half);
                    sum += integrate(f, lo, hi, tol);
                }
                return sum;
            };
            p[r * kSectors + s] = integrate([&](double t) { return ring(t) * std::sin(t); }, t0, t1, tol);
        }
    return p;
}

D3 reflect(D3 wo, D3 n) { return 2 * dot(wo, n) * n - wo; }

// ---- Tests -----------------------------------------------------------------------------------

// bsdf_sample stores bsdf_pdf's and bsdf_f's own values (bsdf.h), so they must agree to float
// rounding: 1e-4 relative. Against the double-precision reference, float GGX loses accuracy in
// 1 - cos^2(theta_h): a few ulps of 1 (~5e-7 absolute, through normalize(wo + wi)) divided by
// alpha^2 in D's denominator and doubled by its square, 1e-6/alpha^2 relative (4e-4 at alpha
// 0.05; measured 2.0e-4); 1e-4 on top for the other float operations.
double reference_tolerance(const Material& m) {
    return m.kind == MATERIAL_GLOSSY ? 1e-4 + 1e-6 / (double(m.alpha) * m.alpha) : 1e-4;
}
constexpr double kSelfTolerance = 1e-4;

TEST(Bsdf, SampleAgreesWithPdfAndF) {
    const size_t n = 1 << 14;
    uint32_t seed = 11;
    for (const Lobe& lobe : non_delta_lobes())
        for (double theta : kWoThetaDegrees)
            for (int mode : {kRadiance, kImportance}) {
                D3 wo = direction_at(kNormal, theta * kPi / 180, 0.7);
                D3 wo_f = as_float(wo);
                std::vector<Sample> s = sample_bsdf(lobe.material, kNormal, wo, mode, n, ++seed);
                double worst_self = 0, worst_ref = 0;
                size_t ok = 0;
                for (const Sample& x : s) {
                    if (!x.ok) continue;
                    ++ok;
                    ASSERT_FALSE(x.specular) << lobe.name;
                    worst_self = std::max(worst_self, rel_diff(x.pdf, x.pdf_eval));
                    worst_self = std::max({worst_self, rel_diff(x.f.x, x.f_eval.x), rel_diff(x.f.y, x.f_eval.y),
                                           rel_diff(x.f.z, x.f_eval.z)});
                    // Against the reference, on the float directions the device used.
                    worst_ref = std::max(worst_ref, rel_diff(x.pdf, lobe.ref.pdf(wo_f, x.wi)));
                    D3 fr = lobe.ref.f(wo_f, x.wi);
                    worst_ref = std::max({worst_ref, rel_diff(x.f.x, fr.x), rel_diff(x.f.y, fr.y),
                                          rel_diff(x.f.z, fr.z)});
                    // wi is a unit vector on wo's side of the surface.
                    ASSERT_NEAR(length(x.wi), 1.0, 1e-5);
                    ASSERT_GT(dot(x.wi, kNormal) * dot(wo, kNormal), 0) << lobe.name;
                }
                std::string what = std::string(lobe.name) + " theta_o " + std::to_string(theta) + " mode " +
                                   std::to_string(mode);
                EXPECT_GT(ok, n / 2) << what;
                EXPECT_LE(worst_self, kSelfTolerance) << what;
                EXPECT_LE(worst_ref, reference_tolerance(lobe.material)) << what;
            }
}

// With a shading normal (0.35 rad off the geometric one): the lobes live in the shading frame,
// while bsdf_f is 0 unless wo and wi are on the same side of the geometric surface (pbrt-v3
// BSDF::f); the sample still reports bsdf_pdf and bsdf_f of its own direction.
TEST(Bsdf, SampleAgreesWithPdfAndFWithShadingNormal) {
    const size_t n = 1 << 14;
    const D3 ng = normalize(kNormal + 0.35 * normalize(cross(kNormal, D3(1, 0, 0))));
    const D3 ng_f = as_float(ng);
    uint32_t seed = 500;
    size_t zero_f = 0;
    for (const Lobe& lobe : non_delta_lobes())
        for (double theta : {30.0, 75.0, 120.0}) {
            D3 wo_f = as_float(direction_at(kNormal, theta * kPi / 180, 4.0));
            std::vector<Sample> s = sample_bsdf(lobe.material, kNormal, wo_f, kRadiance, n, ++seed, &ng);
            double worst_self = 0, worst_ref = 0;
            for (const Sample& x : s) {
                if (!x.ok) continue;
                worst_self = std::max({worst_self, rel_diff(x.pdf, x.pdf_eval), rel_diff(x.f.x, x.f_eval.x),
                                       rel_diff(x.f.z, x.f_eval.z)});
                worst_ref = std::max(worst_ref, rel_diff(x.pdf, lobe.ref.pdf(wo_f, x.wi)));
                bool same_side = dot(wo_f, ng_f) * dot(x.wi, ng_f) > 0;
                // Skip directions within float rounding of the geometric plane.
                if (std::fabs(dot(x.wi, ng_f)) < 1e-5) continue;
                D3 fr = same_side ? lobe.ref.f(wo_f, x.wi) : D3();
                zero_f += !same_side;
                worst_ref = std::max({worst_ref, rel_diff(x.f.x, fr.x, 1e-6), rel_diff(x.f.z, fr.z, 1e-6)});
            }
            std::string what = std::string(lobe.name) + " theta_o " + std::to_string(theta);
            EXPECT_LE(worst_self, kSelfTolerance) << what;
            EXPECT_LE(worst_ref, reference_tolerance(lobe.material)) << what;
        }
    EXPECT_GT(zero_f, 0u) << "no sample crossed the geometric surface: the case is not exercised";
}

// bsdf_pdf / bsdf_f at arbitrary direction pairs (not only sampled ones), including pairs on
// opposite sides (0) and the delta materials (0 everywhere).
TEST(Bsdf, EvaluationMatchesReference) {
    std::mt19937_64 rng(5);
    std::uniform_real_distribution<double> uni(0, 1);
    const size_t n = 4096;
    std::vector<cl_float4> wo(n), wi(n);
    std::vector<D3> wo_d(n), wi_d(n);
    for (size_t i = 0; i < n; ++i) {
        wo_d[i] = as_float(normalize(spherical(2 * uni(rng) - 1, 2 * kPi * uni(rng))));
        wi_d[i] = as_float(normalize(spherical(2 * uni(rng) - 1, 2 * kPi * uni(rng))));
        // Keep |cos| away from 0, where the float and double horizon tests may disagree.
        if (std::fabs(dot(wo_d[i], kNormal)) < 1e-3 || std::fabs(dot(wi_d[i], kNormal)) < 1e-3) {
            wo_d[i] = as_float(kNormal);
        }
        wo[i] = f4(wo_d[i]);
        wi[i] = f4(wi_d[i]);
    }
    cl::Buffer wo_buf = upload(wo), wi_buf = upload(wi);
    std::vector<Lobe> lobes = non_delta_lobes();
    lobes.push_back(make_lobe("mirror", MATERIAL_MIRROR, {}, {0.9, 0.9, 0.9}, 0.1));
    lobes.push_back(make_lobe("glass", MATERIAL_GLASS, {}, {}, 0.1));
    for (const Lobe& lobe : lobes) {
        std::vector<cl_float4> r = eval_bsdf(lobe.material, kNormal, kNormal, wo_buf, wi_buf, n);
        bool delta = lobe.material.kind == MATERIAL_MIRROR || lobe.material.kind == MATERIAL_GLASS;
        for (size_t i = 0; i < n; ++i) {
            double pdf = delta ? 0 : lobe.ref.pdf(wo_d[i], wi_d[i]);
            D3 f = delta ? D3() : lobe.ref.f(wo_d[i], wi_d[i]);
            ASSERT_LE(rel_diff(r[i].s[0], pdf, 1e-6), reference_tolerance(lobe.material)) << lobe.name << " pair " << i;
            ASSERT_LE(rel_diff(r[i].s[1], f.x, 1e-6), reference_tolerance(lobe.material)) << lobe.name << " pair " << i;
            ASSERT_LE(rel_diff(r[i].s[3], f.z, 1e-6), reference_tolerance(lobe.material)) << lobe.name << " pair " << i;
        }
    }
}

// A scene without shading normals builds bsdf_f without the geometric side test: the shading
// normal is then the geometric one, and the test repeats the shading side's bit for bit. So both
// builds give the same pdf and f, to the bit, at every pair of directions with ns = ng (pairs
// across the plane included, where both are 0).
TEST(Bsdf, FlatShadingDropsOnlyARepeatedTest) {
    std::mt19937_64 rng(23);
    std::uniform_real_distribution<double> uni(0, 1);
    const size_t n = 4096;
    std::vector<cl_float4> wo(n), wi(n);
    for (size_t i = 0; i < n; ++i) {
        wo[i] = f4(as_float(normalize(spherical(2 * uni(rng) - 1, 2 * kPi * uni(rng)))));
        wi[i] = f4(as_float(normalize(spherical(2 * uni(rng) - 1, 2 * kPi * uni(rng)))));
    }
    cl::Buffer wo_buf = upload(wo), wi_buf = upload(wi);
    const std::vector<std::string> flat(kDefines.begin(), kDefines.end() - 1);
    ASSERT_EQ(kDefines.back(), "HAS_SHADING_NORMALS");
    for (const Lobe& lobe : non_delta_lobes()) {
        const std::vector<cl_float4> a = eval_bsdf(lobe.material, kNormal, kNormal, wo_buf, wi_buf, n);
        const std::vector<cl_float4> b = eval_bsdf(lobe.material, kNormal, kNormal, wo_buf, wi_buf, n, flat);
        size_t nonzero = 0;
        for (size_t i = 0; i < n; ++i) {
            ASSERT_EQ(std::memcmp(&a[i], &b[i], sizeof a[i]), 0) << lobe.name << " pair " << i;
            nonzero += a[i].s[1] != 0.0f;
        }
        EXPECT_GT(nonzero, n / 4) << lobe.name;
        EXPECT_LT(nonzero, n * 3 / 4) << lobe.name;
    }
}

// Where the shading normal differs from the geometric one (a smooth-shaded coarse mesh), bsdf_f
// must be 0 wherever bsdf_pdf is, for every pair of directions and both of their orders: an
// estimator that samples the BSDF can only find directions of non-zero density, one that joins
// a light or a light subpath finds every direction where f is non-zero, and they agree only
// if the two sets are the same (on a 12 x 6 sphere lit from the side, pt and lt differed by
// 1% before: directions across the terminator band, above one normal and below the other, had
// f > 0 and density 0). Directions within 1e-4 of either plane are left out (float and the
// horizon tests may disagree there).
TEST(Bsdf, FIsZeroWhereverThePdfIs) {
    std::mt19937_64 rng(17);
    std::uniform_real_distribution<double> uni(0, 1);
    const size_t n = 8192;
    const D3 ng = as_float(normalize(kNormal + 0.3 * normalize(cross(kNormal, D3(1, 0, 0)))));
    std::vector<cl_float4> wo(n), wi(n);
    std::vector<D3> wo_d(n), wi_d(n);
    size_t band = 0;
    for (size_t i = 0; i < n; ++i) {
        for (;;) {
            wo_d[i] = as_float(normalize(spherical(2 * uni(rng) - 1, 2 * kPi * uni(rng))));
            wi_d[i] = as_float(normalize(spherical(2 * uni(rng) - 1, 2 * kPi * uni(rng))));
            double c[4] = {dot(wo_d[i], kNormal), dot(wi_d[i], kNormal), dot(wo_d[i], ng), dot(wi_d[i], ng)};
            if (std::fabs(c[0]) > 1e-4 && std::fabs(c[1]) > 1e-4 && std::fabs(c[2]) > 1e-4 && std::fabs(c[3]) > 1e-4) {
                band += (c[0] * c[1] > 0) != (c[2] * c[3] > 0);
                break;
            }
        }
        wo[i] = f4(wo_d[i]);
        wi[i] = f4(wi_d[i]);
    }
    ASSERT_GT(band, n / 20) << "too few pairs across a terminator band";
    for (const Lobe& lobe : non_delta_lobes())
        for (int order = 0; order < 2; ++order) {
            cl::Buffer wo_buf = upload(order ? wi : wo), wi_buf = upload(order ? wo : wi);
            std::vector<cl_float4> r = eval_bsdf(lobe.material, kNormal, ng, wo_buf, wi_buf, n);
            size_t positive = 0;
            for (size_t i = 0; i < n; ++i) {
                const bool f_nonzero = r[i].s[1] != 0 || r[i].s[2] != 0 || r[i].s[3] != 0;
                positive += f_nonzero;
                ASSERT_FALSE(r[i].s[0] == 0 && f_nonzero)
                    << lobe.name << " pair " << i << " order " << order << ": f " << r[i].s[1] << " where the pdf is 0";
            }
            EXPECT_GT(positive, n / 8) << lobe.name << ": the case is not exercised";
        }
}

// Chi-square goodness of fit of the sampled directions against the reference pdf, which the
// test above ties to bsdf_pdf. 2^19 samples per case (the mode does not change non-delta
// sampling, so both modes are tested against one integration); significance
// kChiSquareSignificance.
TEST(Bsdf, SampledDirectionsFollowPdf) {
    const size_t n = 1 << 19;
    uint32_t seed = 1000;
    for (const Lobe& lobe : non_delta_lobes())
        for (double theta : kWoThetaDegrees) {
            D3 wo = direction_at(kNormal, theta * kPi / 180, 2.1);
            D3 wo_f = as_float(wo);
            D3 up = dot(wo_f, lobe.ref.n) > 0 ? lobe.ref.n : -lobe.ref.n;
            Binning bins(reflect(wo_f, lobe.ref.n));
            DirPdf pdf = [&](D3 w) { return lobe.ref.pdf(wo_f, w); };
            // Absolute tolerance 1e-9 of probability per integral: < 1e-3 expected samples.
            std::vector<double> p = cell_probabilities(bins, pdf, up, 1e-9);
            double total = 0;
            for (double x : p) total += x;
            for (int mode : {kRadiance, kImportance}) {
                std::vector<Sample> s = sample_bsdf(lobe.material, kNormal, wo, mode, n, ++seed);
                std::vector<double> observed(p.size() + 1, 0.0), expected(p.size() + 1, 0.0);
                for (size_t c = 0; c < p.size(); ++c) expected[c] = p[c] * double(n);
                // The last cell: samples that failed (a glossy half vector reflecting wi below
                // the horizon), expected (1 - integral of the pdf) of them.
                expected[p.size()] = std::max(0.0, 1 - total) * double(n);
                for (const Sample& x : s) observed[x.ok ? bins.cell(x.wi) : p.size()] += 1;
                ChiSquare chi = chi_square(observed, expected);
                std::string what = std::string(lobe.name) + " theta_o " + std::to_string(theta) + " mode " +
                                   std::to_string(mode);
                EXPECT_GT(chi.p_value, kChiSquareSignificance)
                    << what << ": chi2 " << chi.statistic << " dof " << chi.dof << ", worst " << chi.worst
                    << ", integral of pdf " << total << ", failed " << observed[p.size()];
            }
            EXPECT_LE(total, 1 + 1e-6) << lobe.name << ": the pdf integrates to more than 1";
        }
}

// A pure glossy lobe sampled from the visible normals weighs each sample f |cos theta_i| / pdf
// = Ks G2(wo, wi) / G1(wo) <= Ks (README "Materials"), at every wo, grazing ones included;
// sampling D(h) |cos theta_h| instead fails it already at 25 degrees (measured: a weight of 0.92
// for Ks 0.8 at alpha 0.2). 2^16 samples per case; the bound holds to float rounding (1e-4).
TEST(Bsdf, GlossySampleWeightsStayAtMostKs) {
    const size_t n = 1 << 16;
    uint32_t seed = 3000;
    for (const Lobe& lobe : non_delta_lobes()) {
        const Material& m = lobe.material;
        if (m.kind != MATERIAL_GLOSSY || m.kd.s[0] + m.kd.s[1] + m.kd.s[2] != 0.0f) continue;
        for (double theta : {25.0, 60.0, 84.0, 89.0, 130.0}) {
            const D3 wo = direction_at(kNormal, theta * kPi / 180, 0.7);
            size_t ok = 0;
            for (const Sample& x : sample_bsdf(m, kNormal, wo, kRadiance, n, ++seed)) {
                if (!x.ok) continue;
                ++ok;
                const double weight = x.f.y * std::fabs(dot(x.wi, kNormal)) / x.pdf;
                ASSERT_LE(weight, m.ks.s[1] * (1 + 1e-4)) << lobe.name << " theta_o " << theta << ": wi " << x.wi.x
                                                          << " " << x.wi.y << " " << x.wi.z;
            }
            EXPECT_GT(ok, n / 2) << lobe.name << " theta_o " << theta;
        }
    }
}

// Mirror: wi is wo reflected about the shading normal, pdf 1 (the lobe's discrete probability),
// f = ks / |cos theta_i|, flagged specular; the same in both modes.
TEST(Bsdf, MirrorFollowsReflectionLaw) {
    D3 ks(0.9, 0.8, 0.7);
    Material m = make_material(MATERIAL_MIRROR, {}, ks);
    const D3 n = as_float(kNormal);
    for (double theta : {5.0, 45.0, 80.0, 120.0, 175.0})
        for (int mode : {kRadiance, kImportance}) {
            D3 wo = as_float(direction_at(kNormal, theta * kPi / 180, 0.3));
            std::vector<Sample> s = sample_bsdf(m, kNormal, wo, mode, 64, 7);
            D3 expect = reflect(wo, n);
            for (const Sample& x : s) {
                ASSERT_TRUE(x.ok && x.specular);
                // Unit vectors through a float frame: a few ulps per component.
                EXPECT_LT(length(x.wi - expect), 1e-5) << "theta " << theta;
                EXPECT_NEAR(x.pdf, 1.0, 1e-6);
                double c = std::fabs(dot(x.wi, n));
                EXPECT_LE(rel_diff(x.f.x, ks.x / c), 1e-5);
                EXPECT_LE(rel_diff(x.f.z, ks.z / c), 1e-5);
                EXPECT_EQ(x.pdf_eval, 0.0) << "bsdf_pdf of a delta lobe";
                EXPECT_EQ(x.f_eval.x, 0.0) << "bsdf_f of a delta lobe";
            }
        }
}

// Glass: reflection is chosen with probability F (Fresnel, double-precision reference) and then
// wi is the mirror direction with pdf F and f = F/|cos|; otherwise wi obeys Snell's law
// (eta_i sin_i = eta_t sin_t, in the plane of wo and n, on the other side) with pdf 1 - F and
// f = (1 - F)/|cos| times (eta_i/eta_t)^2 in radiance mode only. Total internal reflection from
// inside beyond the critical angle: always reflected.
TEST(Bsdf, GlassFollowsFresnelAndSnell) {
    const size_t n = 1 << 16;
    for (double ior : {1.5, 1.33}) {
        Material m = make_material(MATERIAL_GLASS, {}, {}, {}, 0.1f, float(ior));
        const D3 nrm = as_float(kNormal);
        // 150 and 140 degrees: inside, beyond the critical angle (41.8 deg for 1.5, 48.8 for 1.33).
        for (double theta : {0.5, 30.0, 70.0, 88.0, 170.0, 150.0, 140.0, 135.0})
            for (int mode : {kRadiance, kImportance}) {
                D3 wo = as_float(direction_at(kNormal, theta * kPi / 180, 1.3));
                double cos_o = dot(wo, nrm);
                double F = fresnel(cos_o, double(float(ior)));
                bool entering = cos_o > 0;
                double eta_i = entering ? 1 : double(float(ior)), eta_t = entering ? double(float(ior)) : 1;
                std::vector<Sample> s = sample_bsdf(m, kNormal, wo, mode, n, 31 + uint32_t(theta));
                size_t reflected = 0;
                std::string what = "ior " + std::to_string(ior) + " theta " + std::to_string(theta) + " mode " +
                                   std::to_string(mode);
                for (const Sample& x : s) {
                    ASSERT_TRUE(x.ok && x.specular) << what;
                    double ci = dot(x.wi, nrm);
                    if (ci * cos_o > 0) {
                        ++reflected;
                        ASSERT_LT(length(x.wi - reflect(wo, nrm)), 1e-5) << what;
                        ASSERT_LE(rel_diff(x.pdf, F), 1e-4) << what;
                        ASSERT_LE(rel_diff(x.f.y, F / std::fabs(ci)), 1e-4) << what;
                    } else {
                        double sin_i = length(cross(wo, nrm)), sin_t = length(cross(x.wi, nrm));
                        ASSERT_NEAR(eta_i * sin_i, eta_t * sin_t, 1e-5) << what << ": Snell's law";
                        // Coplanar with wo and n, on the far side of the tangent plane.
                        ASSERT_NEAR(dot(x.wi, normalize(cross(wo, nrm))), 0.0, 1e-5) << what;
                        D3 wt = eta_i / eta_t * (-wo + cos_o * nrm);  // tangential part, refracted
                        ASSERT_LT(length((x.wi - dot(x.wi, nrm) * nrm) - wt), 1e-5) << what;
                        ASSERT_LE(rel_diff(x.pdf, 1 - F), 1e-4) << what;
                        double scale = mode == kRadiance ? (eta_i / eta_t) * (eta_i / eta_t) : 1.0;
                        ASSERT_LE(rel_diff(x.f.y, (1 - F) * scale / std::fabs(ci)), 1e-4) << what;
                    }
                    ASSERT_EQ(x.pdf_eval, 0.0) << what;
                }
                // The reflection count is Binomial(n, F): within kSigmas standard deviations.
                double sd = std::sqrt(double(n) * F * (1 - F));
                EXPECT_LE(std::fabs(double(reflected) - double(n) * F), kSigmas * sd + 1) << what << ", F " << F;
                if (F == 1.0) {
                    EXPECT_EQ(reflected, n) << what << ": total internal reflection";
                }
            }
    }
}

}  // namespace
}  // namespace clbdpt::test
