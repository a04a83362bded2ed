// Geometric helpers through cl/kernels/geometry_test.cl:
//  - convert_density: solid angle at v -> area at next, pdf |cos(ng_next, w)| / d^2; no cosine
//    for a point not on a surface (camera, point light); unchanged when next is a light at
//    infinity (environment, directional), whose vertex density stays in solid angle;
//  - geometry_term: |ns_a . w| |ns_b . w| / d^2 against a hand computation, 0 when the segment
//    is blocked (decided on the host in double), visibility symmetric;
//  - offset_ray_origin: rays leaving a surface at grazing angles (down to 1e-5 rad, and exactly
//    tangent) on either side, from points computed as the renderer computes hit points, never
//    hit their own surface or its coplanar neighbour, at unit, large (~1e3), tiny (< 1/32) and
//    mixed coordinate scales; the origin moves to the side the ray leaves toward, by no more
//    than the hit point's own error bound (a few ULPs).
#include <gtest/gtest.h>

#include "kernel_test_util.h"

namespace clbdpt::test {
namespace {

constexpr int kVertexCamera = 0, kVertexLight = 1, kVertexSurface = 2;  // VERTEX_* (cl/vertex.h)

// Floor (y = 0, facing up), ceiling (y = 2, facing down), an occluder triangle at y = 1 between
// them; a point, a directional and a constant environment light (indices 0, 1, 2).
const D3 kOcc0(-0.5, 1, -0.5), kOcc1(0.5, 1, -0.5), kOcc2(0, 1, 0.6);

Scene box_scene() {
    Scene s;
    s.path = "geometry_test";
    int m = add_material(s, make_material(MATERIAL_DIFFUSE, {0.5, 0.5, 0.5}));
    add_quad(s, {-2, 0, -2}, {-2, 0, 2}, {2, 0, 2}, {2, 0, -2}, m);
    add_quad(s, {-2, 2, -2}, {2, 2, -2}, {2, 2, 2}, {-2, 2, 2}, m);
    add_triangle(s, kOcc0, kOcc1, kOcc2, m);
    LightDesc point = point_light({0.2f, 1.5f, 0.1f}, {1, 1, 1});
    LightDesc dir;
    dir.kind = LightDesc::Kind::Directional;
    dir.direction = {0, -1, 0};
    dir.color = {1, 1, 1};
    LightDesc env;
    env.kind = LightDesc::Kind::Environment;
    env.color = {1, 1, 1};
    s.lights = {point, dir, env};
    s.camera.eye = {0, 1, -5};
    s.camera.target = {0, 1, 0};
    return s;
}

const TestScene& box() {
    static TestScene scene(box_scene(), 16, 16);
    return scene;
}

// ---- triangle normals ----------------------------------------------------------------------------

// Every hit and area-light sample reads its triangle's normal from the corners' w lanes
// (cl/shared/types.h): the unit normal of the counter-clockwise winding, rounded once from
// double, on every triangle of the BVH (spatial-split copies included).
TEST(Geometry, TrianglesCarryTheirUnitNormal) {
    ASSERT_FALSE(box().ds.triangles.empty());
    for (const Triangle& t : box().ds.triangles) {
        const D3 expected = normalize(cross(d3(t.p1) - d3(t.p0), d3(t.p2) - d3(t.p0)));
        EXPECT_NEAR(t.p0.s[3], expected.x, 1e-7);
        EXPECT_NEAR(t.p1.s[3], expected.y, 1e-7);
        EXPECT_NEAR(t.p2.s[3], expected.z, 1e-7);
    }
    // A sliver far from the origin: its normal is still of unit length.
    Scene s = box_scene();
    add_triangle(s, {1000, 3, 7}, {1000.001, 3, 7}, {1000, 3.0000001, 7.5}, 0);
    TestScene sliver(s, 8, 8);
    for (const Triangle& t : sliver.ds.triangles) {
        const double len = std::sqrt(double(t.p0.s[3]) * t.p0.s[3] + double(t.p1.s[3]) * t.p1.s[3] +
                                     double(t.p2.s[3]) * t.p2.s[3]);
        EXPECT_NEAR(len, 1.0, 2e-7);
    }
}

// The device's copy (TriangleRows) is the transpose: row k holds the corners' coordinate k in
// lanes 0-2 and the normal's in lane 3, bit for bit what the corners held.
TEST(Geometry, DeviceTrianglesAreTheTransposedCorners) {
    const std::vector<Triangle>& corners = box().ds.triangles;
    const std::vector<TriangleRows> rows = triangle_rows(corners);
    ASSERT_EQ(rows.size(), corners.size());
    for (size_t i = 0; i < corners.size(); ++i) {
        const cl_float4* corner[3] = {&corners[i].p0, &corners[i].p1, &corners[i].p2};
        for (int k = 0; k < 3; ++k) {
            for (int c = 0; c < 3; ++c) EXPECT_EQ(rows[i].row[k].s[c], corner[c]->s[k]) << i << " " << k << " " << c;
            EXPECT_EQ(rows[i].row[k].s[3], corner[k]->s[3]) << i << " normal " << k;
        }
    }
}

// ---- convert_density ---------------------------------------------------------------------------

// ~6 float operations on values of order 1: 1e-5 of pdf / d^2 (the cosine is a float dot product
// with an absolute error of a few 1e-8, so near grazing the relative error grows as 1/cos).
constexpr double kConvertTolerance = 1e-5;

TEST(Geometry, ConvertDensity) {
    const TestScene& scene = box();
    ASSERT_EQ(scene.ds.lights[0].kind, LIGHT_POINT);
    ASSERT_EQ(scene.ds.lights[1].kind, LIGHT_DIRECTIONAL);
    ASSERT_EQ(scene.ds.lights[2].kind, LIGHT_ENVIRONMENT);
    std::mt19937_64 rng(3);
    std::uniform_real_distribution<double> uni(-1, 1);
    struct Case {
        D3 v, next, ng;
        int type, light;
        double pdf, expect;
    };
    std::vector<Case> cases;
    for (int i = 0; i < 1000; ++i) {
        Case c;
        c.v = as_float(D3(uni(rng), uni(rng), uni(rng)) * 3);
        c.next = as_float(c.v + D3(uni(rng), uni(rng), uni(rng)) * 2 + D3(0.1, 0, 0));
        c.pdf = 0.01 + 10 * (uni(rng) + 1);
        D3 w = normalize(c.next - c.v);
        double d2 = dot(c.next - c.v, c.next - c.v);
        switch (i % 6) {
        case 0:  // a surface vertex
        case 1:  // an area light vertex (a light vertex on a surface)
            c.ng = as_float(normalize(D3(uni(rng), uni(rng), uni(rng))));
            c.type = i % 6 == 0 ? kVertexSurface : kVertexLight;
            c.light = i % 6 == 0 ? -1 : 0;  // the point light's index, but ng != 0 decides
            c.expect = c.pdf * std::fabs(dot(c.ng, w)) / d2;
            break;
        case 2:  // the camera: not on a surface
            c.type = kVertexCamera;
            c.light = -1;
            c.expect = c.pdf / d2;
            break;
        case 3:  // a point light
            c.type = kVertexLight;
            c.light = 0;
            c.expect = c.pdf / d2;
            break;
        default:  // lights at infinity: solid angle stays
            c.type = kVertexLight;
            c.light = i % 6 == 4 ? 1 : 2;
            c.expect = c.pdf;
            break;
        }
        cases.push_back(c);
    }
    // Coincident points give 0 (no division by zero).
    cases.push_back({D3(1, 1, 1), D3(1, 1, 1), D3(0, 1, 0), kVertexSurface, -1, 1.0, 0.0});
    std::vector<cl_float4> in;
    std::vector<cl_int2> kind;
    std::vector<float> pdf;
    for (const Case& c : cases) {
        in.push_back(f4(c.v));
        in.push_back(f4(c.next));
        in.push_back(f4(c.ng));
        kind.push_back({{c.type, c.light}});
        pdf.push_back(float(c.pdf));
    }
    cl::Kernel k = scene.kernel("kernels/geometry_test.cl", "convert_density_test");
    cl::Buffer a = upload(in), b = upload(kind), p = upload(pdf), out = output_buffer<float>(cases.size());
    cl_uint n = SceneBuffers::kSceneArgCount;
    k.setArg(n, a);
    k.setArg(n + 1, b);
    k.setArg(n + 2, p);
    k.setArg(n + 3, out);
    launch(k, cases.size());
    std::vector<float> r = download<float>(out, cases.size());
    for (size_t i = 0; i < cases.size(); ++i) {
        double expect = cases[i].expect * double(float(cases[i].pdf)) / cases[i].pdf;
        const Case& c = cases[i];
        double scale = c.pdf / std::max(1e-30, dot(c.next - c.v, c.next - c.v));
        EXPECT_LE(std::fabs(r[i] - expect), kConvertTolerance * scale)
            << "case " << i << " (type " << cases[i].type << ", light " << cases[i].light << "): " << r[i]
            << " vs " << expect;
    }
}

// ---- geometry_term -----------------------------------------------------------------------------

// Whether segment a-b crosses the occluder (y = 1), and how far the crossing is from the
// occluder's edges (negative outside), in the plane.
double occluder_margin(D3 a, D3 b, bool* crosses) {
    *crosses = false;
    if ((a.y - 1) * (b.y - 1) >= 0) return 1e9;
    double t = (a.y - 1) / (a.y - b.y);
    D3 q = a + (b - a) * t;
    auto edge = [&](D3 p0, D3 p1, D3 inside) {
        // Signed distance of q to the line p0-p1 in the xz plane, positive toward `inside`.
        double ex = p1.x - p0.x, ez = p1.z - p0.z, len = std::hypot(ex, ez);
        auto side = [&](D3 x) { return (ex * (x.z - p0.z) - ez * (x.x - p0.x)) / len; };
        return side(q) * (side(inside) > 0 ? 1 : -1);
    };
    double m = std::min({edge(kOcc0, kOcc1, kOcc2), edge(kOcc1, kOcc2, kOcc0), edge(kOcc2, kOcc0, kOcc1)});
    *crosses = m > 0;
    return m;
}

TEST(Geometry, GeometryTermAndVisibility) {
    const TestScene& scene = box();
    std::mt19937_64 rng(4);
    std::uniform_real_distribution<double> uni(-1, 1);
    struct Pair {
        D3 a, na, sa, b, nb, sb;
        double expect;
        bool visible;
    };
    std::vector<Pair> pairs;
    while (pairs.size() < 4000) {
        Pair p;
        int kind = int(pairs.size() % 4);
        p.a = as_float(D3(1.5 * uni(rng), 0, 1.5 * uni(rng)));  // on the floor
        p.na = D3(0, 1, 0);
        p.sa = kind == 1 ? as_float(normalize(D3(0.2 * uni(rng), 1, 0.2 * uni(rng)))) : p.na;
        if (kind < 2) {  // to the ceiling
            p.b = as_float(D3(1.5 * uni(rng), 2, 1.5 * uni(rng)));
            p.nb = D3(0, -1, 0);
            p.sb = kind == 1 ? as_float(normalize(D3(0.2 * uni(rng), -1, 0.2 * uni(rng)))) : p.nb;
        } else if (kind == 2) {  // to a point in mid-air (a point light or the camera: ng = 0)
            p.b = as_float(D3(0.8 * uni(rng), 1.2 + 0.7 * (uni(rng) + 1) / 2, 0.8 * uni(rng)));
            p.nb = p.sb = D3();
        } else {  // to a point in mid-air below the occluder, at a grazing angle to the floor
            p.b = as_float(p.a + D3(uni(rng), 0.02 + 0.1 * (uni(rng) + 1), uni(rng)));
            p.nb = p.sb = D3();
        }
        bool crosses;
        double margin = occluder_margin(p.a, p.b, &crosses);
        if (std::fabs(margin) < 1e-3) continue;  // too close to an occluder edge to call
        D3 d = p.b - p.a;
        double d2 = dot(d, d);
        D3 w = d / std::sqrt(d2);
        double g = 1 / d2;
        if (!is_zero(p.na)) g *= std::fabs(dot(p.sa, w));
        if (!is_zero(p.nb)) g *= std::fabs(dot(p.sb, w));
        p.visible = !crosses;
        p.expect = p.visible ? g : 0.0;
        pairs.push_back(p);
    }
    std::vector<cl_float4> in;
    for (const Pair& p : pairs)
        for (D3 v : {p.a, p.na, p.sa, p.b, p.nb, p.sb}) in.push_back(f4(v));
    cl::Kernel k = scene.kernel("kernels/geometry_test.cl", "geometry_term_test");
    cl::Buffer a = upload(in), out = output_buffer<cl_float4>(pairs.size());
    k.setArg(SceneBuffers::kSceneArgCount, a);
    k.setArg(SceneBuffers::kSceneArgCount + 1, out);
    launch(k, pairs.size());
    std::vector<cl_float4> r = download<cl_float4>(out, pairs.size());
    size_t blocked = 0;
    for (size_t i = 0; i < pairs.size(); ++i) {
        const Pair& p = pairs[i];
        blocked += !p.visible;
        std::string what = "pair " + std::to_string(i) + " kind " + std::to_string(i % 4);
        EXPECT_EQ(r[i].s[1] != 0, p.visible) << what << ": vertices_visible(a, b)";
        EXPECT_EQ(r[i].s[2] != 0, p.visible) << what << ": vertices_visible(b, a)";
        // Float geometry of order 1: 1e-5 relative.
        EXPECT_LE(rel_diff(r[i].s[0], p.expect, 1e-30), 1e-5) << what << ": G " << r[i].s[0] << " vs " << p.expect;
        EXPECT_GE(r[i].s[3], 1) << what << ": the shadow ray was not counted";
    }
    EXPECT_GT(blocked, pairs.size() / 20) << "the occluder should block some pairs";
}

// Two points on the same plane see each other (each shadow-ray end is offset to the same side).
TEST(Geometry, CoplanarPointsAreMutuallyVisible) {
    const TestScene& scene = box();
    std::vector<cl_float4> in;
    std::mt19937_64 rng(6);
    std::uniform_real_distribution<double> uni(-1.8, 1.8);
    const size_t n = 512;
    for (size_t i = 0; i < n; ++i) {
        D3 a(uni(rng), 0, uni(rng)), b(uni(rng), 0, uni(rng));
        for (D3 v : {a, D3(0, 1, 0), D3(0, 1, 0), b, D3(0, 1, 0), D3(0, 1, 0)}) in.push_back(f4(v));
    }
    cl::Kernel k = scene.kernel("kernels/geometry_test.cl", "geometry_term_test");
    cl::Buffer a = upload(in), out = output_buffer<cl_float4>(n);
    k.setArg(SceneBuffers::kSceneArgCount, a);
    k.setArg(SceneBuffers::kSceneArgCount + 1, out);
    launch(k, n);
    std::vector<cl_float4> r = download<cl_float4>(out, n);
    for (size_t i = 0; i < n; ++i) {
        EXPECT_NE(r[i].s[1], 0) << "pair " << i;
        EXPECT_NE(r[i].s[2], 0) << "pair " << i;
        EXPECT_EQ(r[i].s[0], 0) << "cosines are 0 in the plane";
    }
}

// ---- offset_ray_origin -------------------------------------------------------------------------

struct Plane {
    const char* name;
    D3 centre, normal;
    double half;
};

Scene plane_scene(const Plane& pl) {
    Scene s;
    s.path = pl.name;
    int m = add_material(s, make_material(MATERIAL_DIFFUSE, {0.5, 0.5, 0.5}));
    DFrame f(pl.normal);
    D3 c = pl.centre, u = f.s * pl.half, v = f.t * pl.half;
    add_quad(s, c - u - v, c + u - v, c + u + v, c - u + v, m);
    return s;
}

TEST(Geometry, OffsetRayOriginAvoidsSelfIntersection) {
    const std::vector<Plane> planes = {
        {"unit, tilted", {0.3, -0.2, 0.5}, normalize(D3(0.3, 0.9, 0.2)), 1.0},
        {"large coordinates", {800, 1200, -500}, normalize(D3(-0.5, 0.2, 0.84)), 300.0},
        {"tiny, near the origin", {0.004, -0.003, 0.002}, normalize(D3(0.1, 0.2, 0.97)), 0.02},
        {"axis-aligned", {1, 5, -2}, D3(0, 1, 0), 2.0},
        {"mixed magnitudes", {1000, 0.01, 3}, normalize(D3(0, 0.6, 0.8)), 5.0},
    };
    // Elevation of the ray above (+) or below (-) the tangent plane, in radians.
    const std::vector<double> elevations = {1e-1, 1e-2, 1e-3, 1e-4, 1e-5, 0, -1e-5, -1e-4, -1e-3, -1e-2, -1e-1};
    std::mt19937_64 rng(8);
    std::uniform_real_distribution<double> uni(0, 1);
    for (const Plane& pl : planes) {
        TestScene scene(plane_scene(pl), 8, 8);
        ASSERT_EQ(scene.ds.triangles.size(), 2u);
        std::vector<cl_float4> in;
        std::vector<D3> dirs, normals;
        const size_t per = 256;
        for (double e : elevations)
            for (size_t i = 0; i < per; ++i) {
                int tri = int(i % 2);
                const Triangle& t = scene.ds.triangles[tri];
                D3 ng = normalize(cross(d3(t.p1) - d3(t.p0), d3(t.p2) - d3(t.p0)));
                double b1 = uni(rng), b2 = uni(rng);
                if (b1 + b2 > 1) {
                    b1 = 1 - b1;
                    b2 = 1 - b2;
                }
                DFrame f(ng);
                double phi = 2 * kPi * uni(rng);
                D3 w = normalize(f.from_local(D3(std::cos(e) * std::cos(phi), std::cos(e) * std::sin(phi), std::sin(e))));
                in.push_back({{float(b1), float(b2), float(tri), 0}});
                in.push_back(f4(w));
                dirs.push_back(as_float(w));
                normals.push_back(ng);
            }
        cl::Kernel k = scene.kernel("kernels/geometry_test.cl", "offset_ray_test");
        cl::Buffer a = upload(in), out = output_buffer<cl_float4>(in.size());
        k.setArg(SceneBuffers::kSceneArgCount, a);
        k.setArg(SceneBuffers::kSceneArgCount + 1, out);
        launch(k, dirs.size());
        std::vector<cl_float4> r = download<cl_float4>(out, in.size());
        size_t hits = 0;
        for (size_t i = 0; i < dirs.size(); ++i) {
            double e = elevations[i / per];
            D3 o = d3(r[2 * i]), p = d3(r[2 * i + 1]);
            std::string what = std::string(pl.name) + " elevation " + std::to_string(e) + " ray " + std::to_string(i);
            bool hit = r[2 * i].s[3] >= 0 || r[2 * i + 1].s[3] != 0;
            hits += hit;
            EXPECT_FALSE(hit) << what << ": the ray hit its own surface (triangle " << r[2 * i].s[3] << ")";
            // The origin moved to the side the ray leaves toward (a tangent ray, whose float
            // direction leans a rounding error to either side, may go either way).
            double side = dot(o - p, normals[i]);
            if (e != 0) {
                EXPECT_GT(e > 0 ? side : -side, 0) << what;
            }
            // ... by the point's own error bound, a few ULPs: gamma(4) times the magnitudes of
            // the terms (at most |p| + 2 plane widths per coordinate), plus one ULP of rounding
            // away. (A fixed 256 ULPs of |p| before: 3e-5 relative.)
            double scale = std::max({std::fabs(p.x), std::fabs(p.y), std::fabs(p.z)}) + 4 * pl.half;
            EXPECT_LT(length(o - p), 1e-6 * scale) << what;
        }
        EXPECT_EQ(hits, 0u) << pl.name;
    }
}

}  // namespace
}  // namespace clbdpt::test
