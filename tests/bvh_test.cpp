// The BVH: host-side invariants of the build, and the device queries of cl/bvh.h (through the
// kernels of cl/kernels/trace.cl on the default OpenCL device) against a brute-force loop over all
// triangles with the same watertight test ported to C++ below.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <map>
#include <memory>
#include <random>
#include <tuple>
#include <vector>

#include "bvh/bvh.h"
#include "device/opencl.h"
#include "render/device_scene.h"

namespace clbdpt {
namespace {

// ---- Geometry helpers ---------------------------------------------------------------------------

struct V3 {
    float x, y, z;
};
V3 operator+(V3 a, V3 b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
V3 operator-(V3 a, V3 b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
V3 operator*(V3 a, float s) { return {a.x * s, a.y * s, a.z * s}; }
float dot(V3 a, V3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
V3 normalized(V3 a) { return a * (1.0f / std::sqrt(dot(a, a))); }
float get(V3 a, int k) { return k == 0 ? a.x : (k == 1 ? a.y : a.z); }

Triangle make_triangle(V3 a, V3 b, V3 c) {
    Triangle t;
    t.p0 = {{a.x, a.y, a.z, 0}};
    t.p1 = {{b.x, b.y, b.z, 0}};
    t.p2 = {{c.x, c.y, c.z, 0}};
    return t;
}
V3 vertex(const Triangle& t, int i) {
    const cl_float4& p = i == 0 ? t.p0 : (i == 1 ? t.p1 : t.p2);
    return {p.s[0], p.s[1], p.s[2]};
}

struct Ray {
    V3 o, d;
    float tmax;
};

// ---- Host port of the watertight test (cl/bvh.h bvh_hit_triangle), operation for operation. ----
// Compiled without FMA contraction (x86-64 without -mfma has no FMA instruction to contract to),
// so it gives the device's results bit for bit when the device does not contract either.

constexpr float gamma_f(int n) { return float(n) * 0x1p-24f / (1.0f - float(n) * 0x1p-24f); }

bool hit_triangle(const Triangle& tri, const Ray& ray, float tmax, float* t_out, float* b1_out, float* b2_out) {
    V3 d = ray.d, o = ray.o;
    float ax = std::fabs(d.x), ay = std::fabs(d.y), az = std::fabs(d.z);
    int kz = ax > ay ? (ax > az ? 0 : 2) : (ay > az ? 1 : 2);
    int kx = kz == 2 ? 0 : kz + 1;
    int ky = kx == 2 ? 0 : kx + 1;
    float sz = 1.0f / get(d, kz);
    float sx = -get(d, kx) * sz;
    float sy = -get(d, ky) * sz;
    V3 p[3] = {vertex(tri, 0), vertex(tri, 1), vertex(tri, 2)};
    float px[3], py[3], pz[3];
    for (int i = 0; i < 3; ++i) {
        pz[i] = get(p[i], kz) - get(o, kz);
        px[i] = get(p[i], kx) - get(o, kx) + sx * pz[i];
        py[i] = get(p[i], ky) - get(o, ky) + sy * pz[i];
    }
    float e0 = px[1] * py[2] - py[1] * px[2];
    float e1 = px[2] * py[0] - py[2] * px[0];
    float e2 = px[0] * py[1] - py[0] * px[1];
    if (e0 == 0.0f || e1 == 0.0f || e2 == 0.0f) {
        e0 = float(double(px[1]) * double(py[2]) - double(py[1]) * double(px[2]));
        e1 = float(double(px[2]) * double(py[0]) - double(py[2]) * double(px[0]));
        e2 = float(double(px[0]) * double(py[1]) - double(py[0]) * double(px[1]));
    }
    if ((e0 < 0 || e1 < 0 || e2 < 0) && (e0 > 0 || e1 > 0 || e2 > 0)) return false;
    float det = e0 + e1 + e2;
    if (det == 0) return false;
    for (float& z : pz) z *= sz;
    float t_scaled = e0 * pz[0] + e1 * pz[1] + e2 * pz[2];
    if (det < 0 ? (t_scaled >= 0 || t_scaled <= tmax * det) : (t_scaled <= 0 || t_scaled >= tmax * det)) return false;
    float inv_det = 1.0f / det;
    float t = t_scaled * inv_det;
    float max_zt = std::max({std::fabs(pz[0]), std::fabs(pz[1]), std::fabs(pz[2])});
    float delta_z = gamma_f(3) * max_zt;
    float max_xt = std::max({std::fabs(px[0]), std::fabs(px[1]), std::fabs(px[2])});
    float max_yt = std::max({std::fabs(py[0]), std::fabs(py[1]), std::fabs(py[2])});
    float delta_x = gamma_f(5) * (max_xt + max_zt);
    float delta_y = gamma_f(5) * (max_yt + max_zt);
    float delta_e = 2.0f * (gamma_f(2) * max_xt * max_yt + delta_y * max_xt + delta_x * max_yt);
    float max_e = std::max({std::fabs(e0), std::fabs(e1), std::fabs(e2)});
    float delta_t = 3.0f * (gamma_f(3) * max_e * max_zt + delta_e * max_zt + delta_z * max_e) * std::fabs(inv_det);
    if (t <= delta_t) return false;
    *t_out = t;
    *b1_out = e1 * inv_det;
    *b2_out = e2 * inv_det;
    return true;
}

struct HostHit {
    float t = INFINITY;
    int triangle = -1;
};

HostHit brute_closest(const std::vector<Triangle>& tris, const Ray& ray) {
    HostHit best;
    float tmax = ray.tmax;
    for (size_t i = 0; i < tris.size(); ++i) {
        float t, b1, b2;
        if (hit_triangle(tris[i], ray, tmax, &t, &b1, &b2)) {
            tmax = t;
            best.t = t;
            best.triangle = int(i);
        }
    }
    return best;
}

// ---- Device ------------------------------------------------------------------------------------

struct DeviceHit {
    float t, b1, b2;
    int triangle;
};

DeviceContext& device() {
    static std::unique_ptr<DeviceContext> ctx = std::make_unique<DeviceContext>(select_device(""));
    return *ctx;
}

// A BVH and its reordered triangles on the device.
class DeviceScene {
public:
    explicit DeviceScene(const std::vector<Triangle>& triangles, const BvhOptions& options = BvhOptions())
        : bvh_(build_bvh(triangles, options)), source_count_(triangles.size()) {
        tris_ = reorder(triangles, bvh_.order);
        DeviceContext& ctx = device();
        nodes_buf_ = cl::Buffer(ctx.context(), CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR,
                                bvh_.nodes.size() * sizeof(BvhNode), bvh_.nodes.data());
        // A zero-sized buffer is invalid in OpenCL: give an empty scene one unused triangle.
        std::vector<TriangleRows> upload = triangle_rows(tris_.empty() ? std::vector<Triangle>(1) : tris_);
        tris_buf_ = cl::Buffer(ctx.context(), CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR,
                               upload.size() * sizeof(TriangleRows), upload.data());
    }

    const Bvh& bvh() const { return bvh_; }
    const std::vector<Triangle>& triangles() const { return tris_; }  // BVH order
    size_t source_count() const { return source_count_; }

    std::vector<DeviceHit> closest(const std::vector<Ray>& rays) {
        std::vector<DeviceHit> hits(rays.size());
        run("trace_closest", rays, hits.data(), sizeof(DeviceHit));
        return hits;
    }
    std::vector<int> any(const std::vector<Ray>& rays) {
        std::vector<int> occluded(rays.size());
        run("trace_any", rays, occluded.data(), sizeof(int));
        return occluded;
    }

private:
    void run(const char* kernel_name, const std::vector<Ray>& rays, void* out, size_t out_size) {
        DeviceContext& ctx = device();
        std::vector<cl_float4> o(rays.size()), d(rays.size());
        for (size_t i = 0; i < rays.size(); ++i) {
            o[i] = {{rays[i].o.x, rays[i].o.y, rays[i].o.z, rays[i].tmax}};
            d[i] = {{rays[i].d.x, rays[i].d.y, rays[i].d.z, 0}};
        }
        cl::Buffer ob(ctx.context(), CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR, o.size() * sizeof(cl_float4), o.data());
        cl::Buffer db(ctx.context(), CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR, d.size() * sizeof(cl_float4), d.data());
        cl::Buffer outb(ctx.context(), CL_MEM_WRITE_ONLY, rays.size() * out_size);
        cl::Kernel kernel(ctx.program("kernels/trace.cl", {}).program, kernel_name);
        kernel.setArg(0, nodes_buf_);
        kernel.setArg(1, tris_buf_);
        kernel.setArg(2, ob);
        kernel.setArg(3, db);
        kernel.setArg(4, outb);
        kernel.setArg(5, cl_int(rays.size()));
        ctx.queue().enqueueNDRangeKernel(kernel, cl::NullRange, cl::NDRange(rays.size()), cl::NullRange);
        ctx.queue().enqueueReadBuffer(outb, CL_TRUE, 0, rays.size() * out_size, out);
    }

    Bvh bvh_;
    size_t source_count_;
    std::vector<Triangle> tris_;
    cl::Buffer nodes_buf_, tris_buf_;
};

// ---- Scenes and rays ----------------------------------------------------------------------------

std::vector<Triangle> random_soup(int count, uint32_t seed) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> pos(-1.0f, 1.0f), size(0.01f, 0.2f);
    std::vector<Triangle> tris;
    for (int i = 0; i < count; ++i) {
        V3 c{pos(rng), pos(rng), pos(rng)};
        float s = size(rng);
        V3 a = c + V3{pos(rng), pos(rng), pos(rng)} * s;
        V3 b = c + V3{pos(rng), pos(rng), pos(rng)} * s;
        V3 e = c + V3{pos(rng), pos(rng), pos(rng)} * s;
        tris.push_back(make_triangle(a, b, e));
    }
    return tris;
}

// A closed mesh: the surface of a cube of n x n quads per face, two triangles each, with every
// shared vertex computed once from its integer lattice point, so neighbouring triangles share
// corners bit for bit. With `sphere`, lattice points are projected onto the unit sphere.
std::vector<Triangle> closed_mesh(int n, bool sphere) {
    auto point = [&](int i, int j, int k) {
        V3 p{2.0f * float(i) / float(n) - 1.0f, 2.0f * float(j) / float(n) - 1.0f, 2.0f * float(k) / float(n) - 1.0f};
        return sphere ? normalized(p) : p;
    };
    std::vector<Triangle> tris;
    for (int axis = 0; axis < 3; ++axis) {
        for (int side = 0; side <= n; side += n) {
            for (int a = 0; a < n; ++a) {
                for (int b = 0; b < n; ++b) {
                    auto lattice = [&](int u, int v) {
                        int c[3];
                        c[axis] = side;
                        c[(axis + 1) % 3] = u;
                        c[(axis + 2) % 3] = v;
                        return point(c[0], c[1], c[2]);
                    };
                    V3 p00 = lattice(a, b), p10 = lattice(a + 1, b), p01 = lattice(a, b + 1), p11 = lattice(a + 1, b + 1);
                    // Alternate the diagonal so vertices have varying valence.
                    if ((a + b) % 2 == 0) {
                        tris.push_back(make_triangle(p00, p10, p11));
                        tris.push_back(make_triangle(p00, p11, p01));
                    } else {
                        tris.push_back(make_triangle(p00, p10, p01));
                        tris.push_back(make_triangle(p10, p11, p01));
                    }
                }
            }
        }
    }
    return tris;
}

// Long thin triangles slanted across the cube [-1, 1]^3 (beams, roof slopes, arches), among a
// soup of small ones: their boxes overlap everything, which is what spatial splits are for.
std::vector<Triangle> slanted_beams(int beams, int small, uint32_t seed) {
    std::vector<Triangle> tris = random_soup(small, seed);
    std::mt19937 rng(seed + 1);
    std::uniform_real_distribution<float> pos(-1.0f, 1.0f), width(0.01f, 0.05f);
    for (int i = 0; i < beams; ++i) {
        V3 a{pos(rng), pos(rng), pos(rng)}, b{pos(rng), pos(rng), pos(rng)};
        float w = width(rng);
        tris.push_back(make_triangle(a, b, b + V3{w, -w, w}));
    }
    return tris;
}

// A closed cube of 2 x 2 quads per face, turned about two axes so its faces are slanted.
std::vector<Triangle> slanted_cube() {
    std::vector<Triangle> tris = closed_mesh(2, false);
    const float a = 0.5f, b = 0.3f;
    auto turn = [&](V3 p) {
        V3 q{p.x * std::cos(a) - p.y * std::sin(a), p.x * std::sin(a) + p.y * std::cos(a), p.z};
        return V3{q.x, q.y * std::cos(b) - q.z * std::sin(b), q.y * std::sin(b) + q.z * std::cos(b)};
    };
    // Shared corners stay bit-identical: each is turned by the same arithmetic.
    for (Triangle& t : tris) t = make_triangle(turn(vertex(t, 0)), turn(vertex(t, 1)), turn(vertex(t, 2)));
    return tris;
}

V3 random_direction(std::mt19937& rng) {
    std::normal_distribution<float> g;
    for (;;) {
        V3 d{g(rng), g(rng), g(rng)};
        if (dot(d, d) > 1e-6f) return normalized(d);
    }
}

std::vector<Ray> random_rays(int count, uint32_t seed, float extent, float tmax) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> pos(-extent, extent);
    std::vector<Ray> rays;
    for (int i = 0; i < count; ++i) rays.push_back({{pos(rng), pos(rng), pos(rng)}, random_direction(rng), tmax});
    return rays;
}

// ---- Checks ------------------------------------------------------------------------------------

// Walks the flattened tree and checks its invariants. With spatial splits a triangle may be
// referenced by several leaves, each box holding only part of it; the parts' boxes together
// must then hold the whole triangle.
class InvariantChecker {
public:
    InvariantChecker(const Bvh& bvh, const std::vector<Triangle>& tris) : bvh_(bvh), tris_(tris) {}

    void run(size_t source_count) {
        const size_t n = tris_.size();
        ASSERT_EQ(bvh_.order.size(), n);
        std::vector<int> copies(source_count, 0);
        for (uint32_t i : bvh_.order) {
            ASSERT_LT(i, source_count) << "order names a triangle that does not exist";
            ++copies[i];
        }
        for (size_t i = 0; i < source_count; ++i) ASSERT_GE(copies[i], 1) << "triangle " << i << " is in no leaf";
        if (bvh_.spatial_splits == 0) {
            EXPECT_EQ(n, source_count) << "references added without a spatial split";
        }
        copies_ = copies;
        ASSERT_FALSE(bvh_.nodes.empty());
        int stack = visit(0, 0);
        EXPECT_EQ(size_t(next_first_), n) << "leaves do not cover every reference exactly once";
        EXPECT_EQ(size_t(next_node_), bvh_.nodes.size()) << "unreachable nodes";
        EXPECT_EQ(leaves_, bvh_.leaf_count);
        EXPECT_EQ(max_depth_, bvh_.max_depth);
        EXPECT_EQ(stack, bvh_.max_stack);
        EXPECT_LE(stack, BVH_STACK_SIZE);
        check_split_triangles();
    }

private:
    struct Box {
        float lo[3], hi[3];
        bool holds(V3 p) const {
            for (int a = 0; a < 3; ++a)
                if (!(get(p, a) >= lo[a] && get(p, a) <= hi[a])) return false;
            return true;
        }
    };

    float lo(const BvhNode& node, int slot, int axis) const { return node.bounds[2 * axis][slot]; }
    float hi(const BvhNode& node, int slot, int axis) const { return node.bounds[2 * axis + 1][slot]; }

    // Checks the subtree of node `index` (reached at `depth`); returns the most stack entries a
    // traversal starting there with an empty stack can hold (k pushed for k children, one of
    // them popped and its subtree traversed above the other k - 1).
    int visit(int index, int depth) {
        EXPECT_EQ(index, next_node_) << "nodes out of depth-first order";
        if (index != next_node_) return 0;
        ++next_node_;
        const BvhNode& node = bvh_.nodes[size_t(index)];
        int k = 0, deepest = 0;
        for (int slot = 0; slot < BVH_WIDTH; ++slot) {
            int c = node.child[slot];
            bool empty = lo(node, slot, 0) > hi(node, slot, 0);
            if (empty) {
                EXPECT_EQ(c, BVH_LEAF(0, 0)) << "empty slot with a child";
                for (int a = 0; a < 3; ++a) EXPECT_TRUE(lo(node, slot, a) == INFINITY && hi(node, slot, a) == -INFINITY);
                continue;
            }
            ++k;
            if (c < 0) {
                int first = BVH_LEAF_FIRST(c), count = BVH_LEAF_COUNT(c);
                EXPECT_GT(count, 0);
                EXPECT_EQ(first, next_first_) << "leaves out of depth-first order";
                next_first_ += count;
                ++leaves_;
                max_depth_ = std::max(max_depth_, depth + 1);
                Box box;
                for (int a = 0; a < 3; ++a) box.lo[a] = lo(node, slot, a), box.hi[a] = hi(node, slot, a);
                for (int i = first; i < first + count && size_t(i) < tris_.size(); ++i) {
                    uint32_t source = bvh_.order[size_t(i)];
                    for (int j = first; j < i; ++j)
                        EXPECT_NE(bvh_.order[size_t(j)], source) << "a triangle twice in one leaf";
                    if (copies_[source] > 1) {
                        // Part of a split triangle: checked with its other parts at the end.
                        EXPECT_GT(bvh_.spatial_splits, 0);
                        parts_[source].push_back(box);
                        continue;
                    }
                    for (int v = 0; v < 3; ++v) EXPECT_TRUE(box.holds(vertex(tris_[size_t(i)], v))) << "triangle outside its leaf";
                }
            } else {
                EXPECT_GT(c, index);
                if (c <= index || size_t(c) >= bvh_.nodes.size()) return 0;
                const BvhNode& child = bvh_.nodes[size_t(c)];
                for (int s = 0; s < BVH_WIDTH; ++s) {
                    if (lo(child, s, 0) > hi(child, s, 0)) continue;
                    for (int a = 0; a < 3; ++a) {
                        EXPECT_GE(lo(child, s, a), lo(node, slot, a)) << "child box outside its parent's";
                        EXPECT_LE(hi(child, s, a), hi(node, slot, a)) << "child box outside its parent's";
                    }
                }
                deepest = std::max(deepest, visit(c, depth + 1));
            }
        }
        return std::max(k, k - 1 + deepest);
    }

    // Every point of a split triangle (its corners, edge points and interior points on a
    // lattice of barycentrics) lies in the box of at least one of its parts' leaves.
    void check_split_triangles() {
        int failures = 0;
        for (const auto& entry : parts_) {
            const Triangle* tri = nullptr;
            for (size_t i = 0; i < tris_.size() && !tri; ++i)
                if (bvh_.order[i] == entry.first) tri = &tris_[i];
            ASSERT_NE(tri, nullptr);
            EXPECT_EQ(entry.second.size(), size_t(copies_[entry.first]));
            const int steps = 24;
            for (int i = 0; i <= steps; ++i) {
                for (int j = 0; i + j <= steps; ++j) {
                    float b1 = float(i) / steps, b2 = float(j) / steps;
                    V3 p = vertex(*tri, 0) * (1 - b1 - b2) + vertex(*tri, 1) * b1 + vertex(*tri, 2) * b2;
                    if (i == 0 && j == 0) p = vertex(*tri, 0);
                    if (i == steps) p = vertex(*tri, 1);
                    if (j == steps) p = vertex(*tri, 2);
                    bool held = false;
                    for (const Box& b : entry.second) held = held || b.holds(p);
                    if (!held && ++failures <= 5)
                        ADD_FAILURE() << "point (" << p.x << ", " << p.y << ", " << p.z << ") of split triangle "
                                      << entry.first << " lies in none of its " << entry.second.size() << " leaves";
                }
            }
        }
    }

    const Bvh& bvh_;
    const std::vector<Triangle>& tris_;
    std::vector<int> copies_;
    std::map<uint32_t, std::vector<Box>> parts_;
    int next_node_ = 0, next_first_ = 0, leaves_ = 0, max_depth_ = 0;
};

// tris_bvh_order: the triangles reordered by bvh.order; source_count: how many there were.
void check_invariants(const Bvh& bvh, const std::vector<Triangle>& tris_bvh_order, size_t source_count) {
    InvariantChecker(bvh, tris_bvh_order).run(source_count);
}

// The device's closest hits agree with the brute-force loop: same t (up to rounding), and the
// same triangle, or another one the brute force also hits at that t (ties at shared edges).
void expect_closest_matches(DeviceScene& scene, const std::vector<Ray>& rays, int* hits_out = nullptr) {
    std::vector<DeviceHit> hits = scene.closest(rays);
    std::vector<int> any = scene.any(rays);
    const std::vector<Triangle>& tris = scene.triangles();
    int hit_count = 0, mismatches = 0;
    for (size_t i = 0; i < rays.size() && mismatches < 10; ++i) {
        HostHit ref = brute_closest(tris, rays[i]);
        const DeviceHit& h = hits[i];
        bool ok = true;
        if (ref.triangle < 0) {
            ok = h.triangle == -1 && any[i] == 0;
        } else {
            ++hit_count;
            ok = h.triangle >= 0 && any[i] == 1 && std::fabs(h.t - ref.t) <= 1e-4f * ref.t;
            if (ok && h.triangle != ref.triangle) {
                float t, b1, b2;
                ok = hit_triangle(tris[h.triangle], rays[i], INFINITY, &t, &b1, &b2) &&
                     std::fabs(t - ref.t) <= 1e-4f * ref.t;
            }
            if (ok) {
                // The barycentrics give back the hit point.
                const Triangle& tri = tris[h.triangle];
                V3 p = vertex(tri, 0) * (1 - h.b1 - h.b2) + vertex(tri, 1) * h.b1 + vertex(tri, 2) * h.b2;
                V3 q = rays[i].o + rays[i].d * h.t;
                ok = std::sqrt(dot(p - q, p - q)) <= 1e-4f * (1 + std::sqrt(dot(q, q)));
            }
        }
        if (!ok) {
            ++mismatches;
            ADD_FAILURE() << "ray " << i << ": device t=" << h.t << " tri=" << h.triangle << " any=" << any[i]
                          << ", brute force t=" << ref.t << " tri=" << ref.triangle;
        }
    }
    if (hits_out) *hits_out = hit_count;
}

// ---- Tests ---------------------------------------------------------------------------------------

TEST(Bvh, InvariantsOnRandomSoup) {
    for (int count : {1, 2, 3, 5, 17, 1000, 20000}) {
        std::vector<Triangle> tris = random_soup(count, 7 + count);
        Bvh bvh = build_bvh(tris);
        check_invariants(bvh, reorder(tris, bvh.order), tris.size());
    }
}

// The collapse to wide nodes chooses by SAH cost (host/bvh/bvh.cpp, Collapser), which fills the
// nodes: the greedy collapse it replaced (open the child of largest area until there are
// BVH_WIDTH) left 4.0-4.3 children per wide node on Sponza and tessellated spheres, and 4.55 on
// this soup, where the SAH collapse leaves 7.45.
TEST(Bvh, WideNodesAreFilledBySahCost) {
    std::vector<Triangle> tris = random_soup(20000, 99);
    Bvh bvh = build_bvh(tris);
    size_t slots = 0;
    for (const BvhNode& node : bvh.nodes)
        for (int slot = 0; slot < BVH_WIDTH; ++slot)
            if (node.bounds[0][slot] <= node.bounds[1][slot]) ++slots;
    const double per_node = double(slots) / double(bvh.nodes.size());
    EXPECT_GE(per_node, 5.5) << bvh.nodes.size() << " nodes";
    check_invariants(bvh, reorder(tris, bvh.order), tris.size());
}

TEST(Bvh, InvariantsOnClosedMesh) {
    std::vector<Triangle> tris = closed_mesh(24, true);
    Bvh bvh = build_bvh(tris);
    check_invariants(bvh, reorder(tris, bvh.order), tris.size());
}

TEST(Bvh, DegenerateInputsStayShallow) {
    // All triangles identical: no split separates them; split by count.
    std::vector<Triangle> same(3000, make_triangle({0, 0, 0}, {1, 0, 0}, {0, 1, 0}));
    Bvh a = build_bvh(same);
    check_invariants(a, reorder(same, a.order), same.size());
    // Centroids spaced geometrically along x: SAH peels one triangle per level; the depth guard
    // must keep the traversal stack within BVH_STACK_SIZE.
    std::vector<Triangle> chain;
    for (int i = 0; i < 4000; ++i) {
        float x = std::ldexp(1.0f, -(i % 120));
        float s = x * 1e-3f;
        chain.push_back(make_triangle({x, 0, 0}, {x + s, 0, 0}, {x, s, 0}));
    }
    Bvh b = build_bvh(chain);
    check_invariants(b, reorder(chain, b.order), chain.size());
    // Zero-area triangles (points and segments).
    std::vector<Triangle> flat;
    for (int i = 0; i < 100; ++i) {
        float x = float(i);
        flat.push_back(make_triangle({x, 0, 0}, {x, 0, 0}, {x, 0, 0}));
        flat.push_back(make_triangle({x, 1, 0}, {x + 1, 1, 0}, {x + 2, 1, 0}));
    }
    Bvh c = build_bvh(flat);
    check_invariants(c, reorder(flat, c.order), flat.size());
}

TEST(Bvh, EmptySceneMissesEverything) {
    DeviceScene scene({});
    check_invariants(scene.bvh(), scene.triangles(), scene.source_count());
    std::vector<Ray> rays = random_rays(100, 1, 1.0f, INFINITY);
    for (const DeviceHit& h : scene.closest(rays)) EXPECT_EQ(h.triangle, -1);
    for (int o : scene.any(rays)) EXPECT_EQ(o, 0);
}

TEST(Bvh, ClosestAndAnyHitMatchBruteForceOnRandomSoup) {
    DeviceScene scene(random_soup(3000, 42));
    check_invariants(scene.bvh(), scene.triangles(), scene.source_count());
    std::vector<Ray> rays = random_rays(4000, 43, 1.2f, INFINITY);
    // Finite tmax too: any-hit and closest-hit must honour it.
    std::vector<Ray> short_rays = random_rays(4000, 44, 1.2f, 0.3f);
    int hits = 0, short_hits = 0;
    expect_closest_matches(scene, rays, &hits);
    expect_closest_matches(scene, short_rays, &short_hits);
    EXPECT_GT(hits, 1000);  // the rays do exercise hits
    EXPECT_GT(short_hits, 200);
    EXPECT_LT(short_hits, 4000);
}

TEST(Bvh, ClosestHitMatchesBruteForceOnClosedMesh) {
    DeviceScene scene(closed_mesh(16, true));
    std::vector<Ray> rays = random_rays(4000, 5, 0.5f, INFINITY);
    std::vector<Ray> outside = random_rays(2000, 6, 3.0f, INFINITY);
    rays.insert(rays.end(), outside.begin(), outside.end());
    expect_closest_matches(scene, rays);
}

// Rays from inside a closed mesh aimed exactly at its vertices and at points on its edges must
// all hit something: a leak would be a ray passing between the triangles that share the edge.
TEST(Bvh, NoLeaksThroughSharedEdgesAndVertices) {
    for (bool sphere : {false, true}) {
        std::vector<Triangle> mesh = closed_mesh(12, sphere);
        DeviceScene scene(mesh);
        std::mt19937 rng(sphere ? 11 : 12);
        std::uniform_real_distribution<float> inner(-0.5f, 0.5f), u01(0.0f, 1.0f);
        std::vector<Ray> rays;
        for (const Triangle& t : mesh) {
            for (int v = 0; v < 3; ++v) {
                V3 a = vertex(t, v), b = vertex(t, (v + 1) % 3);
                V3 o{inner(rng), inner(rng), inner(rng)};
                rays.push_back({o, a - o, INFINITY});  // through the vertex
                V3 on_edge = a + (b - a) * u01(rng);
                rays.push_back({o, on_edge - o, INFINITY});  // through (a float next to) the edge
                V3 mid = (a + b) * 0.5f;
                rays.push_back({{0, 0, 0}, mid, INFINITY});  // from the centre, axis-aligned cases too
            }
        }
        std::vector<DeviceHit> hits = scene.closest(rays);
        std::vector<int> any = scene.any(rays);
        int leaks = 0;
        for (size_t i = 0; i < rays.size(); ++i) {
            if (hits[i].triangle < 0 || !any[i]) {
                if (++leaks <= 5)
                    ADD_FAILURE() << (sphere ? "sphere" : "cube") << " ray " << i << " leaked: o=(" << rays[i].o.x
                                  << "," << rays[i].o.y << "," << rays[i].o.z << ") d=(" << rays[i].d.x << ","
                                  << rays[i].d.y << "," << rays[i].d.z << ")";
            }
        }
        EXPECT_EQ(leaks, 0) << "of " << rays.size() << " rays";
        // And the brute force agrees on a subset.
        std::vector<Ray> subset(rays.begin(), rays.begin() + std::min<size_t>(rays.size(), 3000));
        expect_closest_matches(scene, subset);
    }
}

// Spatial splits: long slanted triangles get references on both sides of planes (within the
// budget), every point of such a triangle stays inside some leaf, and both queries still give
// the brute force's answers; with a budget of 0 the build has none.
TEST(Bvh, SpatialSplitsCutLongSlantedTriangles) {
    std::vector<Triangle> tris = slanted_beams(60, 4000, 21);
    BvhOptions none;
    none.spatial_split_budget = 0;
    Bvh plain = build_bvh(tris, none);
    EXPECT_EQ(plain.spatial_splits, 0);
    check_invariants(plain, reorder(tris, plain.order), tris.size());

    DeviceScene scene(tris);
    const Bvh& bvh = scene.bvh();
    EXPECT_GT(bvh.spatial_splits, 0);
    EXPECT_GT(bvh.order.size(), tris.size());
    EXPECT_LE(double(bvh.order.size()), double(tris.size()) * (1.0 + BvhOptions().spatial_split_budget));
    check_invariants(bvh, scene.triangles(), scene.source_count());

    std::vector<Ray> rays = random_rays(4000, 22, 1.2f, INFINITY);
    std::vector<Ray> short_rays = random_rays(4000, 23, 1.2f, 0.3f);
    // Rays aimed at points on the beams, which lie in several leaves' boxes.
    std::mt19937 rng(24);
    std::uniform_real_distribution<float> u01(0.0f, 1.0f);
    for (size_t i = tris.size() - 60; i < tris.size(); ++i) {
        for (int k = 0; k < 50; ++k) {
            float b1 = u01(rng), b2 = u01(rng) * (1 - b1);
            V3 p = vertex(tris[i], 0) * (1 - b1 - b2) + vertex(tris[i], 1) * b1 + vertex(tris[i], 2) * b2;
            V3 o = p + random_direction(rng) * 0.5f;
            rays.push_back({o, p - o, INFINITY});
        }
    }
    int hits = 0, short_hits = 0;
    expect_closest_matches(scene, rays, &hits);
    expect_closest_matches(scene, short_rays, &short_hits);
    EXPECT_GT(hits, 3000);
    EXPECT_GT(short_hits, 200);
}

// A closed slanted cube whose faces spatial splits cut (the soup inside makes the build split
// them): rays through its shared edges and vertices, from inside, must not leak.
TEST(Bvh, NoLeaksThroughSplitTriangles) {
    std::vector<Triangle> cube = slanted_cube();
    std::vector<Triangle> tris = cube;
    for (const Triangle& t : random_soup(500, 31)) {
        V3 p[3];
        for (int v = 0; v < 3; ++v) p[v] = vertex(t, v) * 0.3f;  // well inside the cube
        tris.push_back(make_triangle(p[0], p[1], p[2]));
    }
    DeviceScene scene(tris);
    ASSERT_GT(scene.bvh().spatial_splits, 0);
    check_invariants(scene.bvh(), scene.triangles(), scene.source_count());
    std::mt19937 rng(32);
    std::uniform_real_distribution<float> inner(-0.45f, 0.45f), u01(0.0f, 1.0f);
    std::vector<Ray> rays;
    for (const Triangle& t : cube) {
        for (int v = 0; v < 3; ++v) {
            V3 a = vertex(t, v), b = vertex(t, (v + 1) % 3);
            for (int k = 0; k < 20; ++k) {
                V3 o{inner(rng) + 0.9f, inner(rng), inner(rng)};
                o = o * 0.5f;  // inside the cube, beside the soup
                rays.push_back({o, a - o, INFINITY});
                rays.push_back({o, a + (b - a) * u01(rng) - o, INFINITY});
            }
        }
    }
    std::vector<DeviceHit> hits = scene.closest(rays);
    std::vector<int> any = scene.any(rays);
    int leaks = 0;
    for (size_t i = 0; i < rays.size(); ++i)
        if ((hits[i].triangle < 0 || !any[i]) && ++leaks <= 5) ADD_FAILURE() << "ray " << i << " leaked";
    EXPECT_EQ(leaks, 0) << "of " << rays.size() << " rays";
    expect_closest_matches(scene, rays);
}

// Grazing rays over a tessellated plane: nearly parallel rays must find the same hits as the brute
// force, exactly parallel rays (in the plane) may hit nothing but must agree too, and rays running
// along the axis-aligned grid lines exercise zero direction components in the slab test.
TEST(Bvh, GrazingRays) {
    std::vector<Triangle> grid;
    const int n = 32;
    for (int i = 0; i < n; ++i) {
        for (int j = 0; j < n; ++j) {
            V3 p00{float(i), float(j), 0}, p10{float(i + 1), float(j), 0}, p01{float(i), float(j + 1), 0},
                p11{float(i + 1), float(j + 1), 0};
            grid.push_back(make_triangle(p00, p10, p11));
            grid.push_back(make_triangle(p00, p11, p01));
        }
    }
    DeviceScene scene(grid);
    std::mt19937 rng(3);
    std::uniform_real_distribution<float> u(0.0f, float(n)), angle(0.0f, 6.2831853f);
    std::vector<Ray> rays;
    for (int i = 0; i < 3000; ++i) {
        float a = angle(rng);
        V3 target{u(rng), u(rng), 0};
        float slope = std::ldexp(1.0f, -int(rng() % 20));  // 1 down to 2^-19
        V3 d = normalized({std::cos(a), std::sin(a), -slope});
        float back = 0.5f / slope;  // start above the plane, within reach of the grid mostly
        rays.push_back({target - d * std::min(back, 8.0f), d, INFINITY});
    }
    int hits = 0;
    expect_closest_matches(scene, rays, &hits);
    EXPECT_GT(hits, 2000);

    std::vector<Ray> in_plane, along_lines;
    for (int i = 0; i < 500; ++i) {
        float a = angle(rng);
        in_plane.push_back({{u(rng), u(rng), 0}, {std::cos(a), std::sin(a), 0}, INFINITY});
        // Interior grid lines only: boundary edges of the open grid have no neighbour.
        float c = float(1 + rng() % (n - 1)), c2 = float(1 + rng() % (n - 1));
        // Along a grid line, slightly above the plane, coming down onto it mid-grid: must hit.
        along_lines.push_back({{c, -1.0f, 1e-3f * (c2 + 1)}, {0, 1, -1e-3f}, INFINITY});
        along_lines.push_back({{-1.0f, c, 1e-3f * (c2 + 1)}, {1, 0, -1e-3f}, INFINITY});
        // Straight down onto a grid vertex (d has two zero components).
        along_lines.push_back({{c, c2, 1.0f}, {0, 0, -1}, INFINITY});
    }
    expect_closest_matches(scene, in_plane);
    int line_hits = 0;
    expect_closest_matches(scene, along_lines, &line_hits);
    EXPECT_EQ(line_hits, int(along_lines.size()));
}

}  // namespace
}  // namespace clbdpt
