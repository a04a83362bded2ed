// MIS weights against brute force (cl/mis.h through cl/kernels/mis_brute_force_test.cl).
//
// The host builds random complete paths x_0 .. x_{n-1} (x_0 on the lens of a pinhole or a
// thin-lens camera, x_{n-1} on an area light, a point or spot light, a directional light or the
// environment map; 0 to 5 scattering vertices in between, diffuse, glossy (alpha 0.3 and 0.05),
// mirror and glass, some with shading normals). For every strategy (s, t), s + t = n, it
// computes the path's density p_s in double precision straight from its definition -- the
// product of the densities with which the strategy's camera subpath samples x_1 .. x_{t-1} and
// its light subpath samples x_{n-1} .. x_t -- and the balance-heuristic weight
//     w_s = p_s / sum of p_i over the strategies i that are enabled and can produce the path.
// The kernel gets the two subpaths of each strategy with pdf_fwd / pdf_rev filled as
// random_walk and generate_*_subpath fill them (the densities the connection changes hold junk,
// so using a stale one fails the test), and its mis_weight, computed by the ratio recursion,
// must match w_s. This checks the recursion, the four densities the connection replaces, the
// remap0 and delta rules, the strategy sets of bdpt / pt / lt, and the density conventions of
// every light and both cameras, independently of mis.h.
//
// In media (cl/medium.h), a second scene fills the space with a homogeneous chromatic medium and
// its paths have medium vertices too (phase-function densities, no cosines, always connectible):
// every density of a vertex reached along a segment of length d then carries the segment's
// distance density toward it, mean_c(T_c sigma_t,c) to a medium vertex and mean_c(T_c) to a
// surface, light or camera (T_c = exp(-sigma_t,c d)); the connection's segment carries none
// (its transmittance is evaluated, not sampled). Those paths have no specular vertices: next
// to a delta the distance densities are dropped with it (remap0), a convention the vacuum cases
// check.
//
// Density conventions (pbrt-v3, Veach 10.2-10.3; the definitions the weights are balanced for):
//  - area measure for every vertex on a surface or a point light; solid angle for a light at
//    infinity (environment, directional) and for an environment vertex reached by an escaped
//    camera ray; the first vertex a light at infinity emits toward gets the bounding-disk
//    density 1/(pi r^2) times its |cos|;
//  - the lens point's density is the same for every strategy (the camera samples it, by
//    generate_ray or Sample_Wi, uniformly on the lens; a pinhole's delta likewise), so it
//    cancels; so do a point/spot light's delta position and a directional light's delta
//    direction, shared by every strategy that can produce such a path (s >= 1);
//  - a chain of specular (delta) vertices between non-specular vertices u and v is sampled
//    from either end with the same generalised geometric term G(u, v) (Jakob & Marschner
//    2012), so the strategies' densities are compared up to that common factor: the chain's
//    entry vertex (its first from the side sampling it) has the projected solid-angle density
//    at the vertex it is entered from, pdf_w / |cos| there (no cosine off surfaces; the
//    bounding disk's density alone for a light at infinity), and every vertex sampled through a
//    specular vertex has density 1 (remap0: the delta dropped on both sides). pbrt-v3 converts
//    to area at the chain's first vertex instead, which the test fails. Strategies whose
//    connection touches a specular vertex cannot produce the path;
//  - light selection: the light's select_pdf, for Sample_Le and Sample_Li alike;
//  - a density 0 that is not a delta's (a vertex whose neighbours straddle its shading normal's
//    plane: the BSDF's density is 0 both ways through it) means the strategies sampling through
//    that vertex cannot produce the path; they get no weight and the others share all of it.
//    (clbdpt's BSDF is 0 there as well, so such paths carry no energy in a render; the rule is
//    checked here for itself: remapping that 0 to 1, as pbrt-v3 does, fails.) The environment
//    map's density toward a texel at or below its mean is such a 0 as well (bdpt and pt sample
//    it by its excess over the mean, render/device_scene.h): only s = 0 produces those paths.
#include <gtest/gtest.h>

#include "kernel_test_util.h"
#include "kernels/mis_brute_force_test.cl"  // as C++: TestVertex and MisCase only

namespace clbdpt::test {
namespace {

static_assert(sizeof(TestVertex) == 112, "TestVertex must match the device layout");
static_assert(sizeof(MisCase) == 32, "MisCase must match the device layout");

constexpr int kVertexCamera = 0, kVertexLight = 1, kVertexSurface = 2, kVertexMedium = 3;  // VERTEX_* (cl/vertex.h)

// ---- The scene ---------------------------------------------------------------------------------

enum MaterialIndex { kDiffuse = 0, kGlossyRough, kGlossySharp, kMirror, kGlass, kEmitBig, kEmitSmall, kMaterials };

const D3 kBig0(-0.8, 2.0, -0.6), kBig1(0.9, 2.0, -0.5), kBig2(0.1, 2.0, 0.9);  // faces down
const D3 kSmall0(1.6, 0.8, 0.3), kSmall1(1.7, 1.3, 0.1), kSmall2(1.5, 1.0, -0.3);
// An emitter that faces the camera, so that paths of the lens and an area light seen directly
// (strategies (0,2) and (1,1)) are among those tested; the other two face away or graze.
const D3 kFacing0(-0.9, 0.9, 2.5), kFacing1(-0.3, 0.9, 2.5), kFacing2(-0.6, 1.5, 2.5);
const D3 kPointPos(-0.9, 1.6, 0.4), kSpotPos(0.8, 2.2, -0.2), kSpotTarget(0.2, 0, 0.3);
const D3 kDirectionalDir = normalize(D3(0.3, -1, 0.25));

CameraDesc camera_desc(bool thin) {
    CameraDesc d;
    d.eye = {0, 0.6f, -4.5f};
    d.target = {0.1f, 0.8f, 0};
    d.up = {0, 1, 0};
    d.fov_degrees = 55;
    d.lens_radius = thin ? 0.15f : 0.0f;
    d.focus_distance = 4.5f;
    return d;
}
constexpr int kWidth = 64, kHeight = 48;

Scene mis_scene() {
    Scene s;
    s.path = "mis_brute_force_test";
    add_material(s, make_material(MATERIAL_DIFFUSE, {0.6, 0.5, 0.4}));
    add_material(s, make_material(MATERIAL_GLOSSY, {0.3, 0.3, 0.2}, {0.4, 0.5, 0.5}, {}, 0.3f));
    add_material(s, make_material(MATERIAL_GLOSSY, {0.1, 0.1, 0.1}, {0.8, 0.7, 0.8}, {}, 0.05f));
    add_material(s, make_material(MATERIAL_MIRROR, {}, {0.9, 0.9, 0.9}));
    add_material(s, make_material(MATERIAL_GLASS, {}, {}, {}, 0.1f, 1.5f));
    add_material(s, make_material(MATERIAL_DIFFUSE, {0, 0, 0}, {}, {3, 3, 3}));
    add_material(s, make_material(MATERIAL_DIFFUSE, {0, 0, 0}, {}, {20, 15, 10}));
    add_triangle(s, kBig0, kBig2, kBig1, kEmitBig);
    add_triangle(s, kSmall0, kSmall1, kSmall2, kEmitSmall);
    add_triangle(s, kFacing0, kFacing2, kFacing1, kEmitSmall);
    add_quad(s, {-2, -0.5, -2}, {-2, -0.5, 2}, {2, -0.5, 2}, {2, -0.5, -2}, kDiffuse);
    LightDesc point = point_light(v3(kPointPos), {2, 2, 2});
    LightDesc spot = spot_light(v3(kSpotPos), v3(kSpotTarget), {6, 6, 6}, 40, 10);
    LightDesc dir;
    dir.kind = LightDesc::Kind::Directional;
    dir.direction = v3(kDirectionalDir);
    dir.color = {0.5f, 0.5f, 0.5f};
    LightDesc env;
    env.kind = LightDesc::Kind::Environment;
    env.color = {0.7f, 0.7f, 0.7f};
    s.lights = {point, spot, dir, env};
    s.environment_map = synthetic_environment(16, 8);
    s.camera = camera_desc(true);
    return s;
}

const TestScene& scene() {
    static TestScene t(mis_scene(), kWidth, kHeight);
    return t;
}

// The same surfaces in a chromatic, forward-scattering medium filling space, lit by the area,
// point and spot lights only (light from infinitely far cannot cross infinite fog).
const D3 kSigmaA(0.05, 0.1, 0.2), kSigmaS(0.3, 0.25, 0.15);
constexpr double kPhaseG = 0.4;

const TestScene& media_scene() {
    static TestScene t = [] {
        Scene s = mis_scene();
        s.lights.resize(2);  // point, spot
        s.environment_map = EnvironmentMap();
        MediumDesc fog;
        fog.name = "fog";
        fog.sigma_a = v3(kSigmaA);
        fog.sigma_s = v3(kSigmaS);
        fog.g = float(kPhaseG);
        s.media.push_back(fog);
        s.scene_medium = 1;
        for (Material& m : s.materials) m.interior_medium = m.exterior_medium = 1;
        return TestScene(s, kWidth, kHeight);
    }();
    return t;
}

// ---- Reference densities in double -------------------------------------------------------------

struct Reference {
    const DeviceScene& ds;
    Camera cam;
    double radius;
    int env_light = -1;
    // The environment's per-texel sampling weights as tabulated by the host (lights_test.cpp
    // checks the table); the density derived from them is recomputed here.
    std::vector<double> env_func;
    double env_integral = 0;

    Reference(const DeviceScene& scene, const Camera& camera) : ds(scene), cam(camera) {
        radius = ds.info.world_center.s[3];
        env_light = ds.info.environment_light;
        int w = ds.info.env_width, h = ds.info.env_height;
        for (int i = 0; i < w * h; ++i) {
            env_func.push_back(ds.env_distribution[size_t(i)]);
            env_integral += env_func.back();
        }
        env_integral /= double(w) * h;
        bool spot = false;
        for (const Light& l : ds.lights) spot |= l.kind == LIGHT_SPOT;
        int area_lights = 0;
        for (const Light& l : ds.lights) area_lights += l.kind == LIGHT_AREA;
        int groups = int(ds.lights.size()) - area_lights + (area_lights > 0 ? 1 : 0);
        every_light = ds.media.empty() && groups >= 2 && groups <= kEveryLightMaxGroups;
        cone_aware = !every_light && spot && ds.lights.size() <= kConeAwareMaxLights;
        for (float p : ds.light_power) total_power += p;
        for (const Light& l : ds.lights)
            if (l.kind == LIGHT_AREA) area_select_total += l.select_pdf;
    }

    // A light sample from x (s = 1) picks light l with probability w_l(x) / sum_k w_k(x) in a
    // scene with spot lights and few lights (cl/lights.h): w = select_pdf, but for a spot
    // 4 pi I / (the lights' total power) where its cone contains x and 0 elsewhere; light
    // subpaths pick by select_pdf. Returns the first probability over the second.
    bool cone_aware = false;
    double total_power = 0;
    double light_weight(int l, D3 x) const {
        const Light& L = ds.lights[size_t(l)];
        if (L.kind != LIGHT_SPOT) return L.select_pdf;
        bool inside = dot(normalize(x - d3(L.position)), d3(L.direction)) >= 1 - double(L.one_minus_cos_total);
        return inside ? 4 * kPi * luminance({L.emission.s[0], L.emission.s[1], L.emission.s[2]}) / total_power : 0.0;
    }
    // With a few light groups (NEE_EVERY_LIGHT) the light samples from x take every group: one
    // area light among them by select_pdf, and every other light with probability 1 (a spot
    // only inside its cone).
    bool every_light = false;
    double area_select_total = 0;
    double every_light_probability(int l, D3 x) const {
        const Light& L = ds.lights[size_t(l)];
        if (L.kind == LIGHT_AREA) return L.select_pdf / area_select_total;
        if (L.kind != LIGHT_SPOT) return 1;
        return dot(normalize(x - d3(L.position)), d3(L.direction)) >= 1 - double(L.one_minus_cos_total) ? 1 : 0;
    }
    double light_sample_ratio(int l, D3 x) const {
        if (every_light) return every_light_probability(l, x) / ds.lights[size_t(l)].select_pdf;
        if (!cone_aware) return 1;
        double total = 0;
        for (size_t k = 0; k < ds.lights.size(); ++k) total += light_weight(int(k), x);
        return light_weight(l, x) / (total * ds.lights[size_t(l)].select_pdf);
    }

    static void env_uv(D3 d, double* u, double* v) {
        double phi = std::atan2(d.z, d.x);
        if (phi < 0) phi += 2 * kPi;
        *u = phi / (2 * kPi);
        *v = std::acos(std::clamp(d.y, -1.0, 1.0)) / kPi;
    }
    // Solid-angle density of the environment sampling direction w (toward the light).
    double env_pdf(D3 w) const {
        double u, v;
        env_uv(w, &u, &v);
        int W = ds.info.env_width, H = ds.info.env_height;
        int x = std::min(int(u * W), W - 1), y = std::min(int(v * H), H - 1);
        return env_func[size_t(y) * W + x] / env_integral / (2 * kPi * kPi * std::sin(v * kPi));
    }
    // Whether w is safely inside a texel and away from the poles (float and double agree).
    bool env_safe(D3 w) const {
        double u, v;
        env_uv(w, &u, &v);
        auto inside = [](double t, int n) {
            double f = t * n - std::floor(t * n);
            return f > 0.01 && f < 0.99;
        };
        return inside(u, ds.info.env_width) && inside(v, ds.info.env_height) && v > 0.05 && v < 0.95;
    }

    // Raster position of a ray leaving the lens at `lens` along `dir` (camera_raster_of).
    bool raster(D3 lens, D3 dir, double* rx, double* ry) const {
        D3 right = d3(cam.right), up = d3(cam.up), fwd = d3(cam.forward), eye = d3(cam.eye);
        D3 d(dot(dir, right), dot(dir, up), dot(dir, fwd));
        if (d.z <= 0) return false;
        D3 o(dot(lens - eye, right), dot(lens - eye, up), dot(lens - eye, fwd));
        double plane = cam.lens_radius > 0 ? cam.focus_distance : 1.0;
        D3 p = o + d * (plane / d.z);
        *rx = (p.x / plane / cam.tan_half_width + 1) * 0.5 * cam.width;
        *ry = (1 - p.y / plane / cam.tan_half_height) * 0.5 * cam.height;
        return *rx >= 0 && *rx < cam.width && *ry >= 0 && *ry < cam.height;
    }
    // With media: the scene-wide medium's extinction (float, as the device has it).
    bool media = false;
    D3 sigma_t;
    // Henyey-Greenstein density of scattering from wo into wi (both away from the vertex).
    double phase_pdf(D3 wo, D3 wi) const {
        double c = -dot(wo, wi), g = kPhaseG, denom = 1 + g * g - 2 * g * c;
        return (1 - g * g) / (4 * kPi * denom * std::sqrt(denom));
    }
    // pdf_dir = 1 / (A cos^3) inside the film (camera_pdf_we).
    double camera_pdf_dir(D3 lens, D3 dir) const {
        double rx, ry;
        double c = dot(dir, d3(cam.forward));
        if (c <= 0 || !raster(lens, dir, &rx, &ry)) return 0;
        return 1 / (double(cam.film_area) * c * c * c);
    }

    double luminance(D3 c) const { return 0.2126 * c.x + 0.7152 * c.y + 0.0722 * c.z; }
    double ggx_d(double cos_h, double alpha) const {
        double c2 = cos_h * cos_h, a2 = alpha * alpha, e = 1 + (1 - c2) / c2 / a2;
        return 1 / (kPi * a2 * c2 * c2 * e * e);
    }
    double ggx_lambda(double cos_t, double alpha) const {
        double c2 = cos_t * cos_t;
        return 0.5 * (-1 + std::sqrt(1 + alpha * alpha * (1 - c2) / c2));
    }
    // bsdf_pdf in the shading frame (README "Materials"): diffuse cos/pi, glossy the mixture
    // of it and the visible normals' G1(wo) D(h) / (4 |cos o|) by the luminance of kd and ks.
    double bsdf_pdf(int material, D3 ns, D3 wo, D3 wi) const {
        const Material& m = ds.materials[material];
        double co = dot(wo, ns), ci = dot(wi, ns);
        if (co * ci <= 0) return 0;
        double diffuse = std::fabs(ci) / kPi;
        if (m.kind != MATERIAL_GLOSSY) return diffuse;
        double ld = luminance(d3(m.kd)), ls = luminance(d3(m.ks));
        double pd = ld + ls > 0 ? ld / (ld + ls) : 1;
        D3 h = normalize(wo + wi);
        double glossy = ggx_d(dot(h, ns), m.alpha) / ((1 + ggx_lambda(co, m.alpha)) * 4 * std::fabs(co));
        return pd * diffuse + (1 - pd) * glossy;
    }
};

// ---- Paths -------------------------------------------------------------------------------------

struct HostVertex {
    D3 p, ng, ns;      // ng = 0 off surfaces (camera, point and spot lights, lights at infinity, media)
    int material = -1; // surfaces
    bool specular = false;
    bool medium = false;  // a scattering in the medium
};

struct Path {
    std::vector<HostVertex> x;  // x[0] camera, x[n-1] light
    int light = -1;             // index into ds.lights
    bool thin = false;
    bool across_terminator = false;  // a vertex's neighbours straddle its shading normal's plane
};

int light_kind(const DeviceScene& ds, const Path& path) { return ds.lights[path.light].kind; }
bool light_at_infinity(int kind) { return kind == LIGHT_ENVIRONMENT || kind == LIGHT_DIRECTIONAL; }

// Area density at `to` of a solid-angle density at `from` (ConvertDensity): unchanged for a
// light at infinity, no cosine off surfaces.
double to_area(double pdf_w, const HostVertex& from, const HostVertex& to, bool to_at_infinity) {
    if (to_at_infinity) return pdf_w;
    D3 w = to.p - from.p;
    double d2 = dot(w, w);
    if (!is_zero(to.ng)) pdf_w *= std::fabs(dot(to.ng, w / std::sqrt(d2)));
    return pdf_w / d2;
}

D3 dir(const HostVertex& from, const HostVertex& to) { return normalize(to.p - from.p); }

// Density of a specular chain's entry vertex `to` (the file comment): the solid-angle density
// at `from` over |cos| there (no cosine off surfaces), and over glass_ior^2 where `to` is glass
// that the chain enters through its back face (`from` inside it); glass_ior 0: `to` is no glass.
double to_chain_entry(double pdf_w, const HostVertex& from, const HostVertex& to, double glass_ior) {
    if (glass_ior > 0 && dot(dir(from, to), to.ng) > 0) pdf_w /= glass_ior * glass_ior;
    if (is_zero(from.ng)) return pdf_w;
    double c = std::fabs(dot(from.ng, dir(from, to)));
    return c > 0 ? pdf_w / c : 0.0;
}

// Density at `to` of a solid-angle density at `from`: area measure, or a chain entry's.
double toward(const Reference& ref, double pdf_w, const HostVertex& from, const HostVertex& to, bool to_at_infinity) {
    if (!to.specular) return to_area(pdf_w, from, to, to_at_infinity);
    const Material& m = ref.ds.materials[size_t(to.material)];
    return to_chain_entry(pdf_w, from, to, m.kind == MATERIAL_GLASS ? double(m.ior) : 0.0);
}

struct Densities {
    // cam[i]: density of x_i sampled by the camera subpath (i >= 1); light[j]: by the light
    // subpath (j <= n-1; light[n-1] is the light vertex's own, light[n-2] the emission's).
    // A vertex sampled through a specular vertex gets 1 (see the file comment). With media,
    // toward[i] / away[i]: the distance densities of the segment x_{i-1} x_i toward x_i and
    // toward x_{i-1} (factors of cam[i] and light[i-1]); 1 in vacuum.
    std::vector<double> cam, light, toward, away;
};

// Distance density of a segment toward its end `to` (the file comment).
double distance_density(const Reference& ref, const HostVertex& from, const HostVertex& to) {
    if (!ref.media) return 1;
    double d = length(to.p - from.p), sum = 0;
    for (int c = 0; c < 3; ++c) {
        double sigma = c == 0 ? ref.sigma_t.x : c == 1 ? ref.sigma_t.y : ref.sigma_t.z;
        sum += std::exp(-sigma * d) * (to.medium ? sigma : 1.0);
    }
    return sum / 3;
}

// Density of scattering at v from direction toward `from` into direction toward `to`.
double scatter_pdf(const Reference& ref, const HostVertex& v, const HostVertex& from, const HostVertex& to) {
    if (v.medium) return ref.phase_pdf(dir(v, from), dir(v, to));
    return ref.bsdf_pdf(v.material, v.ns, dir(v, from), dir(v, to));
}

Densities densities(const Reference& ref, const Path& path) {
    const std::vector<HostVertex>& x = path.x;
    const int n = int(x.size());
    const Light& L = ref.ds.lights[path.light];
    const bool infinite = light_at_infinity(L.kind);
    Densities d;
    d.cam.assign(n, 0.0);
    d.light.assign(n, 0.0);
    for (int i = 1; i < n; ++i) {
        bool to_infinite = i == n - 1 && infinite;
        if (i == 1) {
            d.cam[i] = toward(ref, ref.camera_pdf_dir(x[0].p, dir(x[0], x[1])), x[0], x[1], to_infinite);
        } else if (x[i - 1].specular) {
            d.cam[i] = 1;
        } else {
            d.cam[i] = toward(ref, scatter_pdf(ref, x[i - 1], x[i - 2], x[i]), x[i - 1], x[i], to_infinite);
        }
    }
    d.toward.assign(n, 1.0);
    d.away.assign(n, 1.0);
    for (int i = 1; i < n; ++i) {
        d.toward[i] = distance_density(ref, x[i - 1], x[i]);
        d.away[i] = distance_density(ref, x[i], x[i - 1]);
        d.cam[i] *= d.toward[i];
    }
    const HostVertex& lv = x[n - 1];
    D3 w_light = dir(x[n - 2], lv);  // toward the light
    switch (L.kind) {
    case LIGHT_AREA: {
        const Triangle& t = ref.ds.triangles[L.triangle];
        double area = 0.5 * length(cross(d3(t.p1) - d3(t.p0), d3(t.p2) - d3(t.p0)));
        d.light[n - 1] = L.select_pdf / area;
        d.light[n - 2] = toward(ref, std::max(0.0, dot(lv.ng, -w_light)) / kPi, lv, x[n - 2], false);
        break;
    }
    case LIGHT_POINT:
        d.light[n - 1] = L.select_pdf;  // times the delta position, common to every strategy
        d.light[n - 2] = toward(ref, 1 / (4 * kPi), lv, x[n - 2], false);
        break;
    case LIGHT_SPOT:
        d.light[n - 1] = L.select_pdf;
        d.light[n - 2] = toward(ref,
                                dot(-w_light, d3(L.direction)) >= 1 - double(L.one_minus_cos_total)
                                    ? 1 / (2 * kPi * double(L.one_minus_cos_total))
                                    : 0.0,
                                lv, x[n - 2], false);
        break;
    case LIGHT_DIRECTIONAL:
    case LIGHT_ENVIRONMENT: {
        // Directional: times the delta direction, common to every strategy; environment: solid
        // angle.
        d.light[n - 1] = L.select_pdf * (L.kind == LIGHT_DIRECTIONAL ? 1.0 : ref.env_pdf(w_light));
        // The bounding disk's density is per projected area: a chain entry keeps it as it is.
        double cos_first = x[n - 2].specular ? 1.0 : std::fabs(dot(x[n - 2].ng, w_light));
        d.light[n - 2] = cos_first / (kPi * ref.radius * ref.radius);
        break;
    }
    }
    for (int j = n - 3; j >= 1; --j) {
        if (x[j + 1].specular) {
            d.light[j] = 1;
        } else {
            d.light[j] = toward(ref, scatter_pdf(ref, x[j + 1], x[j + 2], x[j]), x[j + 1], x[j], false);
        }
    }
    for (int j = 0; j + 1 < n; ++j) d.light[j] *= d.away[j + 1];
    return d;
}

// The strategy mix of efficiency-aware BDPT (cl/strategies.h), restated.
struct Mix {
    double light_subpaths = 1;  // light subpaths per pixel sample
    bool inner_connections = true;
    bool light_to_lens = true;  // bdpt's (1,1): with a thin lens or media (check_integrator sets it)
};

bool uses_light_subpath(int s, int t) { return s >= 2 || t == 1; }

// strategy_enabled's rules, restated: t >= 1, s + t >= 2; (1,1) only for area lights; pt uses
// s <= 1 < t, lt uses t = 1; bdpt what the mix allows, (1,1) with a thin lens or media only.
bool enabled(Integrator integrator, const Mix& mix, int s, int t, bool area) {
    if (t < 1 || s + t < 2) return false;
    if (s == 1 && t == 1 && !area) return false;
    switch (integrator) {
    case Integrator::Pt: return s <= 1 && t >= 2;
    case Integrator::Lt: return t == 1;
    default:
        if (s == 1 && t == 1 && !mix.light_to_lens) return false;
        if (s >= 2 && t >= 2 && !mix.inner_connections) return false;
        return !uses_light_subpath(s, t) || mix.light_subpaths > 0;
    }
}

// Samples of strategy (s, t) per pixel sample: the balance heuristic weighs n_s p_s.
double sample_count(Integrator integrator, const Mix& mix, int s, int t) {
    return integrator == Integrator::Bdpt && uses_light_subpath(s, t) ? mix.light_subpaths : 1.0;
}

// Whether strategy (s, t) can produce the path: s = 0 needs an emitter a camera ray can hit
// (area or environment); otherwise the connection x_{t-1} -- x_t joins non-specular vertices
// (x_t may be any light when s = 1: Sample_Li).
bool can_produce(const DeviceScene& ds, const Path& path, int s, int t) {
    const int n = int(path.x.size());
    int kind = light_kind(ds, path);
    if (s == 0) return kind == LIGHT_AREA || kind == LIGHT_ENVIRONMENT;
    if (path.x[t - 1].specular) return false;
    if (s == 1) return true;
    (void)n;
    return !path.x[t].specular;
}

// ---- Subpaths as the random walk stores them ---------------------------------------------------

// The value left in the densities mis_weight must replace (the walk would have stored whatever
// its own continuation gave): if the kernel used one, its weight would be off.
constexpr float kJunk = 777.0f;

TestVertex test_vertex(const HostVertex& v, int type, int light, D3 wo, bool delta) {
    TestVertex t{};
    if (v.medium && type == kVertexSurface) type = kVertexMedium;
    t.medium = v.medium ? 1 : 0;
    t.dist_fwd = t.dist_rev = 1.0f;
    t.p = f4(v.p);
    t.ng = f4(v.ng);
    t.ns = f4(v.ns);
    t.wo = f4(wo);
    t.type = type;
    t.delta = delta;
    t.material = v.material;
    t.light = light;
    return t;
}

// Camera subpath x_0 .. x_{t-1}.
std::vector<TestVertex> camera_subpath(const Reference& ref, const Path& path, const Densities& d, int t) {
    const std::vector<HostVertex>& x = path.x;
    const int n = int(x.size());
    std::vector<TestVertex> out;
    for (int i = 0; i < t; ++i) {
        TestVertex v;
        if (i == 0) {
            v = test_vertex(x[0], kVertexCamera, -1, {}, false);
            v.ng = v.ns = f4({});
            v.pdf_fwd = 0;
        } else if (i == n - 1) {  // the camera subpath ends on the emitter (s = 0)
            int kind = ref.ds.lights[path.light].kind;
            if (kind == LIGHT_ENVIRONMENT) {
                v = test_vertex(x[i], kVertexLight, path.light, dir(x[i], x[i - 1]), false);
                v.material = -1;
            } else {
                v = test_vertex(x[i], kVertexSurface, path.light, dir(x[i], x[i - 1]), false);
                v.material = kEmitBig;  // not read: mis_weight never scatters at the emitter
            }
            v.pdf_fwd = float(i >= 2 && x[i - 1].specular ? 0.0 : d.cam[i]);
        } else {
            v = test_vertex(x[i], kVertexSurface, -1, dir(x[i], x[i - 1]), x[i].specular);
            v.pdf_fwd = float(i >= 2 && x[i - 1].specular ? 0.0 : d.cam[i]);
        }
        // pdf_rev: the light-side density of x_i from x_{i+1}, which the walk knows when it
        // samples x_{i+2}; 0 if x_{i+1} is specular. The last two are the connection's.
        if (i <= t - 3 && i >= 1) v.pdf_rev = float(x[i + 1].specular ? 0.0 : d.light[i]);
        else v.pdf_rev = kJunk;
        if (i >= 1) {  // the segment from x_{i-1}, walked from the camera
            v.dist_fwd = float(d.toward[i]);
            v.dist_rev = float(d.away[i]);
        }
        out.push_back(v);
    }
    return out;
}

// Light subpath y_k = x_{n-1-k}, k = 0 .. s-1.
std::vector<TestVertex> light_subpath(const Reference& ref, const Path& path, const Densities& d, int s) {
    const std::vector<HostVertex>& x = path.x;
    const int n = int(x.size());
    const Light& L = ref.ds.lights[path.light];
    std::vector<TestVertex> out;
    for (int k = 0; k < s; ++k) {
        int i = n - 1 - k;
        TestVertex v;
        if (k == 0) {
            v = test_vertex(x[i], kVertexLight, path.light, x[i].ng, false);
            v.material = -1;
            if (light_at_infinity(L.kind)) {
                // InfiniteLightDensity: the environment's density of the direction, times its
                // selection probability (0 without an environment light).
                D3 w_light = dir(x[n - 2], x[n - 1]);
                v.pdf_fwd = float(ref.env_light >= 0 ? ref.ds.lights[ref.env_light].select_pdf * ref.env_pdf(w_light) : 0.0);
            } else {
                v.pdf_fwd = float(d.light[i]);
            }
        } else {
            v = test_vertex(x[i], kVertexSurface, -1, dir(x[i], x[i + 1]), x[i].specular);
            v.pdf_fwd = float(k >= 2 && x[i + 1].specular ? 0.0 : d.light[i]);
        }
        // pdf_rev: the camera-side density of x_i from x_{i-1}; 0 if x_{i-1} is specular.
        if (k <= s - 3) v.pdf_rev = float(x[i - 1].specular ? 0.0 : d.cam[i]);
        else v.pdf_rev = kJunk;
        if (k >= 1) {  // the segment from x_{i+1}, walked from the light
            v.dist_fwd = float(d.away[i + 1]);
            v.dist_rev = float(d.toward[i + 1]);
        }
        out.push_back(v);
    }
    return out;
}

// ---- Random paths ------------------------------------------------------------------------------

struct PathGenerator {
    const Reference& ref;
    std::mt19937_64 rng;
    std::uniform_real_distribution<double> uni{0, 1};
    std::vector<int> area_lights;
    int point = -1, spot = -1, directional = -1, environment = -1;

    PathGenerator(const Reference& r, uint64_t seed) : ref(r), rng(seed) {
        for (size_t i = 0; i < r.ds.lights.size(); ++i) {
            switch (r.ds.lights[i].kind) {
            case LIGHT_AREA: area_lights.push_back(int(i)); break;
            case LIGHT_POINT: point = int(i); break;
            case LIGHT_SPOT: spot = int(i); break;
            case LIGHT_DIRECTIONAL: directional = int(i); break;
            case LIGHT_ENVIRONMENT: environment = int(i); break;
            }
        }
    }

    double u() { return uni(rng); }
    D3 unit() {
        double z = 2 * u() - 1, phi = 2 * kPi * u();
        return spherical(z, phi);
    }
    D3 round(D3 v) const { return as_float(v); }

    // A normal with both neighbours in front of it (cos > 0.15), near the half vector for the
    // sharp glossy lobe (so its density is not vanishingly small). Returns false if none.
    bool pick_normal(D3 a, D3 b, double spread, D3* n) {
        D3 h = a + b;
        if (length(h) < 1e-3) return false;
        h = normalize(h);
        for (int tries = 0; tries < 64; ++tries) {
            D3 c = round(normalize(h + spread * unit()));
            if (dot(c, a) > 0.15 && dot(c, b) > 0.15) {
                *n = c;
                return true;
            }
        }
        return false;
    }

    // A random path with `scatter` scattering vertices to light `light` (or nothing).
    bool make(Path* path, int scatter, int light, bool thin) {
        const Camera& cam = ref.cam;
        const int n = scatter + 2;
        const Light& L = ref.ds.lights[light];
        path->x.assign(n, HostVertex());
        path->light = light;
        path->thin = thin;
        std::vector<HostVertex>& x = path->x;
        D3 eye = d3(cam.eye), right = d3(cam.right), up = d3(cam.up), fwd = d3(cam.forward);
        // x_0 on the lens.
        D3 lens = eye;
        if (thin) {
            double r = std::sqrt(u()) * cam.lens_radius, phi = 2 * kPi * u();
            lens = eye + right * (r * std::cos(phi)) + up * (r * std::sin(phi));
        }
        x[0].p = round(lens);
        // x_1 through a random raster position (not on the film's edge).
        double rx = 2 + u() * (cam.width - 4), ry = 2 + u() * (cam.height - 4);
        D3 film = right * ((2 * rx / cam.width - 1) * cam.tan_half_width) +
                  up * ((1 - 2 * ry / cam.height) * cam.tan_half_height) + fwd;
        D3 d1 = thin ? normalize(eye + film * double(cam.focus_distance) - x[0].p) : normalize(film);
        double r = ref.radius;
        // The light vertex and the last scattering vertex.
        if (n == 2) {
            if (L.kind == LIGHT_AREA) {
                // A point on the light the camera sees.
                const Triangle& t = ref.ds.triangles[L.triangle];
                double b1 = u(), b2 = u();
                if (b1 + b2 > 1) b1 = 1 - b1, b2 = 1 - b2;
                x[1].p = round(d3(t.p0) * (1 - b1 - b2) + d3(t.p1) * b1 + d3(t.p2) * b2);
                x[1].ng = x[1].ns = round(normalize(cross(d3(t.p1) - d3(t.p0), d3(t.p2) - d3(t.p0))));
                double qx, qy;
                if (!ref.raster(x[0].p, dir(x[0], x[1]), &qx, &qy) || qx < 1 || qy < 1 || qx > cam.width - 1 ||
                    qy > cam.height - 1)
                    return false;
                if (dot(x[1].ng, dir(x[1], x[0])) < 0.15) return false;
                return true;
            }
            if (L.kind != LIGHT_ENVIRONMENT) return false;  // no strategy sees a delta light directly
            if (!ref.env_safe(d1)) return false;
            x[1].p = round(x[0].p + d1 * (2 * r));
            return true;
        }
        x[1].p = round(x[0].p + d1 * (1.5 + 3 * u()));
        for (int i = 2; i < n - 1; ++i) {
            x[i].p = round(D3(-1.5 + 3 * u(), -0.3 + 2.1 * u(), -1.2 + 2.7 * u()));
            if (length(x[i].p - x[i - 1].p) < 0.3) return false;
        }
        HostVertex& lv = x[n - 1];
        const HostVertex& last = x[n - 2];
        switch (L.kind) {
        case LIGHT_AREA: {
            const Triangle& t = ref.ds.triangles[L.triangle];
            double b1 = u(), b2 = u();
            if (b1 + b2 > 1) b1 = 1 - b1, b2 = 1 - b2;
            lv.p = round(d3(t.p0) * (1 - b1 - b2) + d3(t.p1) * b1 + d3(t.p2) * b2);
            lv.ng = lv.ns = round(normalize(cross(d3(t.p1) - d3(t.p0), d3(t.p2) - d3(t.p0))));
            if (dot(lv.ng, dir(lv, last)) < 0.15) return false;  // one-sided emitter
            break;
        }
        case LIGHT_POINT: lv.p = d3(L.position); break;
        case LIGHT_SPOT:
            lv.p = d3(L.position);
            if (dot(dir(lv, last), d3(L.direction)) < 1 - double(L.one_minus_cos_total) + 0.01) return false;
            break;
        case LIGHT_DIRECTIONAL: lv.p = round(last.p - d3(L.direction) * (2 * r)); break;
        case LIGHT_ENVIRONMENT: {
            D3 w = unit();
            if (!ref.env_safe(w)) return false;
            lv.p = round(last.p + w * (2 * r));
            break;
        }
        }
        if (length(lv.p - last.p) < 0.3) return false;
        // Materials and normals of the scattering vertices; in media, a third of them scatter in
        // the medium instead.
        for (int i = 1; i < n - 1; ++i) {
            if (ref.media && u() < 0.35) {
                x[i].medium = true;
                continue;
            }
            double m = u();
            int material = m < 0.3 ? kDiffuse : m < 0.5 ? kGlossyRough : m < 0.7 ? kGlossySharp : m < 0.85 ? kMirror : kGlass;
            if (ref.media && (material == kMirror || material == kGlass)) material = kDiffuse;  // see the file comment
            x[i].material = material;
            x[i].specular = material == kMirror || material == kGlass;
            D3 a = dir(x[i], x[i - 1]), b = dir(x[i], x[i + 1]);
            if (x[i].specular) {
                D3 h = a + b;
                if (length(h) < 1e-3) return false;
                x[i].ng = x[i].ns = round(normalize(h));  // a mirror reflects a into b
                // Half the glass reflects from inside: its neighbours behind its front face, so
                // that chains enter it through the back (entry densities over ior^2).
                if (material == kGlass && u() < 0.5) x[i].ng = x[i].ns = -x[i].ng;
                continue;
            }
            double spread = material == kGlossySharp ? 0.03 : 0.6;
            if (!pick_normal(a, b, spread, &x[i].ns)) return false;
            x[i].ng = x[i].ns;
            if (u() < 0.3) {  // a shading normal differing from the geometric one
                D3 g = round(normalize(x[i].ns + 0.15 * unit()));
                if (dot(g, a) > 0.15 && dot(g, b) > 0.15) x[i].ng = g;
            } else if (!path->across_terminator && u() < 0.2) {
                // Across a terminator band (a coarse smooth-shaded mesh): both neighbours in
                // front of the geometric normal, on opposite sides of the shading normal (up to
                // 45 degrees off it). No BSDF sampling passes through this vertex: only the two
                // strategies that connect at it can produce the path.
                for (int tries = 0; tries < 64; ++tries) {
                    D3 ns = round(normalize(x[i].ng + 0.6 * unit()));
                    double ca = dot(ns, a), cb = dot(ns, b);
                    if (ca * cb < 0 && std::fabs(ca) > 0.05 && std::fabs(cb) > 0.05 && dot(ns, x[i].ng) > 0.7) {
                        x[i].ns = ns;
                        path->across_terminator = true;
                        break;
                    }
                }
            }
        }
        return true;
    }
};

// ---- The test ----------------------------------------------------------------------------------

struct CaseRef {
    size_t path;
    int s, t;
    double weight;  // brute force
};

// Weights agree to 1e-3 relative: the kernel's ratios are float products of at most 6 ratios
// of float densities (each good to ~1e-6), and 1e-3 leaves room for the GGX alpha 0.05 lobes'
// ~1e-4 float error (bsdf_test.cpp) at the connection vertices. Any convention mismatch (a
// missing cosine, a density in the wrong measure, a wrong delta rule) moves weights by O(1).
constexpr double kWeightTolerance = 1e-3;
// The weights of every strategy that can produce a path sum to 1 (float rounding).
constexpr double kSumTolerance = 1e-4;

void check_integrator(Integrator integrator, bool thin, uint64_t seed, Mix mix = Mix(), bool media = false) {
    const TestScene& ts = media ? media_scene() : scene();
    Camera cam = make_camera(camera_desc(thin), kWidth, kHeight);
    mix.light_to_lens = thin || media;
    Reference ref(ts.ds, cam);
    // Light samples take a light of each of the vacuum scene's 5 light groups (NEE_EVERY_LIGHT);
    // in media, one light, skipping the spot where its cone does not reach (NEE_CONE_AWARE).
    EXPECT_EQ(ref.every_light, !media);
    EXPECT_EQ(ref.cone_aware, media);
    if (media) {
        ref.media = true;
        ref.sigma_t = d3(ts.ds.media[0].sigma_t);
    }
    PathGenerator gen(ref, seed);

    std::vector<Path> paths;
    std::vector<TestVertex> vertices;
    std::vector<MisCase> cases;
    std::vector<CaseRef> refs;
    std::vector<int> lights = gen.area_lights;
    for (int l : {gen.point, gen.spot, gen.directional, gen.environment})
        if (l >= 0) lights.push_back(l);
    const size_t target = 1200;
    size_t attempts = 0;
    std::vector<size_t> per_kind(5, 0);
    size_t across_terminator = 0;  // paths across a terminator band with two or more producers
    size_t env_left_to_bsdf_sampling = 0;  // environment paths that only s = 0 can produce
    size_t medium_vertices = 0;
    size_t area_light_seen = 0;  // paths x_0 x_1 of the lens and an area light: (0,2) and maybe (1,1)
    while (paths.size() < target && attempts < 200 * target) {
        ++attempts;
        int scatter = int(gen.u() * 6);  // depth 0 .. 5
        int light = lights[size_t(gen.u() * lights.size())];
        Path path;
        if (!gen.make(&path, scatter, light, thin)) continue;
        const int n = int(path.x.size());
        Densities d = densities(ref, path);
        bool area = light_kind(ts.ds, path) == LIGHT_AREA;
        // An environment map sampled by its excess over its mean (render/device_scene.h) never
        // picks a direction at or below the mean: no strategy with a light vertex can produce
        // such a path.
        const bool env_unsampled = light_kind(ts.ds, path) == LIGHT_ENVIRONMENT &&
                                   ref.env_pdf(dir(path.x[size_t(n - 2)], path.x[size_t(n - 1)])) == 0;
        std::vector<int> producers;
        double sum = 0;
        std::vector<double> p(n + 1, 0.0);
        for (int s = 0; s <= n; ++s) {
            int t = n - s;
            if (!enabled(integrator, mix, s, t, area) || !can_produce(ts.ds, path, s, t)) continue;
            double ps = 1;
            for (int i = 1; i < t; ++i) ps *= d.cam[i];
            for (int j = t; j < n; ++j) ps *= d.light[j];
            // A light sample's own choice of light, from the path's second vertex.
            if (s == 1 && t >= 2) ps *= ref.light_sample_ratio(path.light, path.x[size_t(n - 2)].p);
            // Only a vertex across a terminator band and an environment direction left to BSDF
            // sampling have a density 0 that is not a delta's: strategies that would sample
            // through them cannot produce the path.
            if (ps == 0 && (path.across_terminator || env_unsampled)) continue;
            ASSERT_TRUE(ps > 0 && std::isfinite(ps)) << "degenerate density for s " << s;
            ps *= sample_count(integrator, mix, s, t);
            p[s] = ps;
            sum += ps;
            producers.push_back(s);
        }
        if (producers.empty()) continue;
        if (path.across_terminator && producers.size() >= 2) ++across_terminator;
        env_left_to_bsdf_sampling += env_unsampled;
        if (n == 2 && area) ++area_light_seen;
        for (const HostVertex& v : path.x) medium_vertices += v.medium;
        size_t index = paths.size();
        paths.push_back(path);
        ++per_kind[size_t(light_kind(ts.ds, path))];
        for (int s : producers) {
            int t = n - s;
            MisCase c{};
            c.s = s;
            c.t = t;
            c.light_offset = int(vertices.size());
            for (const TestVertex& v : light_subpath(ref, path, d, s)) vertices.push_back(v);
            c.camera_offset = int(vertices.size());
            for (const TestVertex& v : camera_subpath(ref, path, d, t)) vertices.push_back(v);
            // The connection x_{t-1} -- x_t: its distance densities toward either end.
            c.to_qs = float(s > 0 ? d.toward[t] : 1.0);
            c.to_pt = float(s > 0 ? d.away[t] : 1.0);
            cases.push_back(c);
            refs.push_back({index, s, t, p[s] / sum});
        }
    }
    ASSERT_EQ(paths.size(), target) << "could not generate enough paths";
    for (int light : lights) {
        const int kind = ts.ds.lights[size_t(light)].kind;
        EXPECT_GT(per_kind[size_t(kind)], target / 20) << "light kind " << kind;
    }
    if (media) {
        EXPECT_GT(medium_vertices, target / 2) << "medium vertices";  // about 1.2 per path
    }
    // Whether bdpt joins a light point to the lens ((1,1), with a thin lens or media) shows in them.
    EXPECT_GT(area_light_seen, target / 100) << "paths of an area light seen directly";
    if (integrator != Integrator::Lt && ts.ds.info.env_width > 0) {  // the media scene's is constant
        EXPECT_GT(env_left_to_bsdf_sampling, target / 100) << "environment paths below the map's mean";
    }
    // Full bdpt has the most strategies that can connect at such a vertex.
    if (integrator == Integrator::Bdpt && mix.light_subpaths == 1 && mix.inner_connections) {
        EXPECT_GT(across_terminator, target / 50) << "terminator paths";
    }

    std::vector<std::string> defines;
    for (const std::string& d : ts.defines)
        defines.push_back(d.rfind("INTEGRATOR=", 0) == 0 ? "INTEGRATOR=" + std::to_string(int(integrator)) : d);
    cl::Kernel k = test_kernel("kernels/mis_brute_force_test.cl", defines, "mis_weight_test");
    ts.buffers->set_args(k);
    k.setArg(SceneBuffers::kCameraArg, cam);
    cl::Buffer vb = upload(vertices), cb = upload(cases), out = output_buffer<float>(cases.size());
    k.setArg(SceneBuffers::kSceneArgCount, vb);
    k.setArg(SceneBuffers::kSceneArgCount + 1, cb);
    k.setArg(SceneBuffers::kSceneArgCount + 2, out);
    k.setArg(SceneBuffers::kSceneArgCount + 3, float(mix.light_subpaths));
    k.setArg(SceneBuffers::kSceneArgCount + 4, cl_int(mix.inner_connections ? 1 : 0));
    k.setArg(SceneBuffers::kSceneArgCount + 5, cl_int(mix.light_to_lens ? 1 : 0));
    launch(k, cases.size());
    std::vector<float> w = download<float>(out, cases.size());

    std::vector<double> sums(paths.size(), 0.0);
    size_t failures = 0;
    double worst = 0;
    for (size_t i = 0; i < cases.size(); ++i) {
        const CaseRef& r = refs[i];
        sums[r.path] += w[i];
        double e = rel_diff(w[i], r.weight, 1e-7);
        worst = std::max(worst, e);
        if (e > kWeightTolerance && ++failures <= 10) {
            const Path& path = paths[r.path];
            std::string desc;
            for (size_t j = 1; j + 1 < path.x.size(); ++j) desc += std::to_string(path.x[j].material) + " ";
            ADD_FAILURE() << integrator_name(integrator) << (thin ? " thin lens" : " pinhole") << ": path " << r.path
                          << " (n " << path.x.size() << ", light kind " << light_kind(ts.ds, path)
                          << ", materials " << desc << ") s " << r.s << " t " << r.t << ": kernel weight " << w[i]
                          << ", brute force " << r.weight;
        }
    }
    EXPECT_EQ(failures, 0u) << "worst relative error " << worst << " over " << cases.size() << " weights";
    for (size_t j = 0; j < paths.size(); ++j)
        EXPECT_NEAR(sums[j], 1.0, kSumTolerance) << integrator_name(integrator) << " path " << j;
}

// ---- The chain convention against the densities it stands for ----------------------------------

// A glass sphere (index 1.5, in air) and rays through it onto a plane dot(p, plane_n) = plane_d.
struct GlassSphere {
    D3 center{0, 0.3, 0};
    double radius = 0.3, eta = 1.5;

    // The far (inside = true) or near intersection of o + t d with the sphere.
    double hit(D3 o, D3 d, bool inside) const {
        D3 oc = o - center;
        double b = dot(oc, d), c = dot(oc, oc) - radius * radius, disc = b * b - c;
        EXPECT_GE(disc, 0) << "the test's ray misses the sphere";
        return inside ? -b + std::sqrt(std::max(disc, 0.0)) : -b - std::sqrt(std::max(disc, 0.0));
    }
    static D3 refract(D3 d, D3 n, double eta_ratio) {  // n against d; eta_ratio = eta_i / eta_t
        double cos_i = -dot(n, d), k = 1 - eta_ratio * eta_ratio * (1 - cos_i * cos_i);
        EXPECT_GT(k, 0) << "total internal reflection in the test's chain";
        return normalize(d * eta_ratio + n * (eta_ratio * cos_i - std::sqrt(std::max(k, 0.0))));
    }
    static D3 onto_plane(D3 o, D3 d, D3 plane_n, double plane_d) {
        return o + d * ((plane_d - dot(o, plane_n)) / dot(d, plane_n));
    }
    // From o outside: in and out of the sphere, onto the plane; the sphere points in *in, *out.
    D3 through(D3 o, D3 d, D3 plane_n, double plane_d, D3* in = nullptr, D3* out = nullptr) const {
        D3 a = o + d * hit(o, d, false);
        d = refract(d, normalize(a - center), 1 / eta);
        if (in) *in = a;
        return out_of(a, d, plane_n, plane_d, out);
    }
    // From o inside: out of the sphere, onto the plane.
    D3 out_of(D3 o, D3 d, D3 plane_n, double plane_d, D3* out = nullptr) const {
        D3 b = o + d * hit(o, d, true);
        if (out) *out = b;
        return onto_plane(b, refract(d, -normalize(b - center), eta), plane_n, plane_d);
    }
    // From o outside: into the sphere, onto a plane inside it.
    D3 into(D3 o, D3 d, D3 plane_n, double plane_d) const {
        D3 a = o + d * hit(o, d, false);
        return onto_plane(a, refract(d, normalize(a - center), 1 / eta), plane_n, plane_d);
    }
};

// |dA/dw|: the area where a chain lands per solid angle around direction d (finite differences).
template <class Chain> double area_per_solid_angle(D3 d, Chain chain) {
    const double eps = 1e-6;
    D3 t1 = normalize(cross(d, std::fabs(d.x) < 0.9 ? D3(1, 0, 0) : D3(0, 1, 0))), t2 = cross(d, t1);
    D3 p0 = chain(d), p1 = chain(normalize(d + t1 * eps)), p2 = chain(normalize(d + t2 * eps));
    return length(cross(p1 - p0, p2 - p0)) / (eps * eps);
}

HostVertex host_vertex(D3 p, D3 ng, bool specular = false) {
    HostVertex v;
    v.p = p;
    v.ng = v.ns = ng;
    v.specular = specular;
    return v;
}

// The chain between D and y: each side's density of the other end is its solid-angle density
// times the chain's Jacobian (by finite differences). The entry densities' ratio must be that
// ratio (so the MIS weights are the balance heuristic's); pbrt-v3's must not (so the check can
// fail). dA_y_dw_D: |dA_y / dw_D|, and so on; entry_D, entry_y: the chain's first vertex from
// either end; eta_D: 1 or the glass's index where D lies inside it.
void check_chain_densities(const HostVertex& D, D3 w_D, const HostVertex& y, D3 w_y, double dA_y_dw_D,
                           double dA_D_dw_y, const HostVertex& entry_D, const HostVertex& entry_y, double glass_ior,
                           double eta_D) {
    // The generalised geometric term from either end (etendue eta^2 cos dA dw is conserved).
    double cos_D = std::fabs(dot(D.ng, w_D)), cos_y = std::fabs(dot(y.ng, w_y));
    EXPECT_LT(rel_diff(eta_D * eta_D * cos_D / dA_y_dw_D, cos_y / dA_D_dw_y), 1e-3);
    const double pdf_w_D = 0.7, pdf_w_y = 0.3;
    double true_ratio = (pdf_w_y / dA_D_dw_y) / (pdf_w_D / dA_y_dw_D);  // p(D | y) / p(y | D)
    double entry_ratio =
        to_chain_entry(pdf_w_y, y, entry_y, glass_ior) / to_chain_entry(pdf_w_D, D, entry_D, glass_ior);
    EXPECT_LT(rel_diff(entry_ratio, true_ratio), 1e-3);
    double pbrt_ratio = to_area(pdf_w_y, y, entry_y, false) / to_area(pdf_w_D, D, entry_D, false);
    EXPECT_GT(std::fabs(std::log(pbrt_ratio / true_ratio)), std::log(2.0)) << "pbrt's ratio " << pbrt_ratio;
}

// cornell-specular's caustic: a floor point D, a glass sphere resting on the floor, a light
// point y above; the chain enters and leaves the glass.
TEST(MisBruteForce, ChainEntryDensitiesAreExactThroughGlass) {
    const GlassSphere glass;
    const D3 up(0, 1, 0);
    const double light_height = 1.5;
    HostVertex D = host_vertex(D3(0.25, 0, 0.05), up);
    D3 w_D = normalize(D3(0.05, 0.32, -0.02) - D.p), s1, s2;
    HostVertex y = host_vertex(glass.through(D.p, w_D, up, light_height, &s1, &s2), -up);
    D3 w_y = normalize(s2 - y.p);
    ASSERT_LT(length(glass.through(y.p, w_y, up, 0.0) - D.p), 1e-9) << "the reversed chain must return to D";
    double dA_y_dw_D = area_per_solid_angle(w_D, [&](D3 d) { return glass.through(D.p, d, up, light_height); });
    double dA_D_dw_y = area_per_solid_angle(w_y, [&](D3 d) { return glass.through(y.p, d, up, 0.0); });
    check_chain_densities(D, w_D, y, w_y, dA_y_dw_D, dA_D_dw_y, host_vertex(s1, normalize(s1 - glass.center), true),
                          host_vertex(s2, normalize(s2 - glass.center), true), glass.eta, 1.0);
}

// A diffuse point D inside the glass (a body embedded in it) and a light point y outside: one
// refraction, whose ends lie in indices 1.5 and 1.
TEST(MisBruteForce, ChainEntryDensitiesAreExactOutOfGlass) {
    const GlassSphere glass;
    const D3 up(0, 1, 0), n_D = normalize(D3(0.2, 1, 0.1));
    const double light_height = 1.5;
    HostVertex D = host_vertex(glass.center + D3(0.05, -0.1, 0.03), n_D);
    const double plane_D = dot(D.p, n_D);
    D3 w_D = normalize(D3(0.3, 1, -0.2)), s;
    HostVertex y = host_vertex(glass.out_of(D.p, w_D, up, light_height, &s), -up);
    D3 w_y = normalize(s - y.p);
    ASSERT_LT(length(glass.into(y.p, w_y, n_D, plane_D) - D.p), 1e-9) << "the reversed chain must return to D";
    double dA_y_dw_D = area_per_solid_angle(w_D, [&](D3 d) { return glass.out_of(D.p, d, up, light_height); });
    double dA_D_dw_y = area_per_solid_angle(w_y, [&](D3 d) { return glass.into(y.p, d, n_D, plane_D); });
    HostVertex entry = host_vertex(s, normalize(s - glass.center), true);
    check_chain_densities(D, w_D, y, w_y, dA_y_dw_D, dA_D_dw_y, entry, entry, glass.eta, glass.eta);
}

TEST(MisBruteForce, BdptPinhole) { check_integrator(Integrator::Bdpt, false, 101); }
TEST(MisBruteForce, BdptThinLens) { check_integrator(Integrator::Bdpt, true, 102); }
TEST(MisBruteForce, PtPinhole) { check_integrator(Integrator::Pt, false, 103); }
TEST(MisBruteForce, PtThinLens) { check_integrator(Integrator::Pt, true, 104); }
TEST(MisBruteForce, LtPinhole) { check_integrator(Integrator::Lt, false, 105); }
TEST(MisBruteForce, LtThinLens) { check_integrator(Integrator::Lt, true, 106); }
// Efficiency-aware mixes: a quarter of a light subpath per pixel sample; half, without the
// s >= 2, t >= 2 connections; none (path tracing inside the bdpt kernel).
TEST(MisBruteForce, BdptQuarterLightSubpaths) { check_integrator(Integrator::Bdpt, false, 107, Mix{0.25, true}); }
TEST(MisBruteForce, BdptNoInnerConnections) { check_integrator(Integrator::Bdpt, true, 108, Mix{0.5, false}); }
TEST(MisBruteForce, BdptNoLightSubpaths) { check_integrator(Integrator::Bdpt, false, 109, Mix{0.0, true}); }

// Paths with medium vertices, in a chromatic medium filling space.
TEST(MisBruteForce, BdptInMedia) { check_integrator(Integrator::Bdpt, false, 111, Mix(), /*media=*/true); }
TEST(MisBruteForce, BdptThinLensInMedia) { check_integrator(Integrator::Bdpt, true, 112, Mix{0.25, true}, true); }
TEST(MisBruteForce, PtInMedia) { check_integrator(Integrator::Pt, false, 113, Mix(), true); }
TEST(MisBruteForce, LtInMedia) { check_integrator(Integrator::Lt, true, 114, Mix(), true); }

}  // namespace
}  // namespace clbdpt::test
