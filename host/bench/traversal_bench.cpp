// traversal_bench: BVH build time and ray-traversal throughput of cl/bvh.h on an OpenCL device,
// with Embree 3 (single-ray API, 2 threads) as the yardstick when it is available.
//
// Scenes (deterministic): the open Cornell box with its two blocks (32 triangles), and the open
// box with two tessellated spheres of about --triangles triangles in all (the scene of the
// project's Embree reference figures), or any scene file the renderer loads (--obj: a bare .obj
// or a .json scene). Ray kinds:
//   primary     closest hit, pinhole camera grid (coherent)
//   bounce      closest hit, cosine-distributed from the primary hits
//   random      closest hit, random origins in the scene bounds, random directions
//   light       any hit, shadow rays from primary hits to random points on the light
//   connection  any hit, between random surface points (area-weighted)
//   random-any  any hit, the random rays
// Each kind is traced once to warm up, then --repeats times by each tracer in turn; the table
// gives rays over the median wall time, and rays over the median CPU time of the process (the
// steadier figure when other processes share the cores), and the share of rays on which the
// two tracers agree (hit or miss, and t within 1e-3 relative).
//
// Usage: traversal_bench [--triangles N] [--rays N] [--repeats K] [--local L] [--device S]
//                        [--scene cornell|spheres|all] [--obj FILE] [--only KIND] [--huge-pages]
//                        [--no-embree] [--embree-quality high|medium] [--count-visits]
//                        [--spatial-splits BUDGET]
// --obj: instead of the built-in scenes, the triangles of FILE. Its primary rays look from the
// centre of its bounds along the longer horizontal axis (inside an interior such as Sponza's
// atrium), and its light rays aim at a patch spanning the middle half of the bounds' top, just
// below it (the sky over an atrium). --embree-quality: Embree's build, high (the default: with
// spatial splits) or medium (binned SAH alone). --spatial-splits: clbdpt's budget of extra
// references for spatial splits, as a fraction of the triangles (the renderer's default
// unless given; 0: object splits only).
// --count-visits: after each closest-hit kind, its mean numbers of nodes visited and triangles
// tested per ray (a second build of the kernel with counters, untimed).
// --local: work-group size (0 = the driver's choice). --huge-pages: BVH and triangles in host
// memory on transparent huge pages (CL_MEM_USE_HOST_PTR) instead of a driver copy.
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <random>
#include <string>
#include <thread>
#include <vector>
#include <sys/mman.h>

#include "bvh/bvh.h"
#include "device/opencl.h"
#include "render/device_scene.h"
#include "scene/scene.h"
#include "util/error.h"
#include "util/vec3.h"

#ifdef CLBDPT_HAVE_EMBREE
#include <embree3/rtcore.h>
#endif

namespace clbdpt {
namespace {

using Clock = std::chrono::steady_clock;
double seconds_since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

struct Options {
    long triangles = 1000000;
    long rays = 1 << 20;
    int repeats = 5;
    int local = 0;
    std::string device;
    std::string scene = "all";
    std::string obj;   // a scene file instead of the built-in scenes
    std::string only;  // one ray kind, for profiling
    bool huge_pages = false;
    bool embree = true;
    std::string embree_quality = "high";  // high: with spatial splits; medium: without
    bool count_visits = false;
    BvhOptions bvh;
};

// ---- Scenes ---------------------------------------------------------------------------------

Triangle tri(Vec3 a, Vec3 b, Vec3 c) {
    Triangle t;
    t.p0 = {{a.x, a.y, a.z, 0}};
    t.p1 = {{b.x, b.y, b.z, 0}};
    t.p2 = {{c.x, c.y, c.z, 0}};
    return t;
}
Vec3 corner(const Triangle& t, int i) {
    const cl_float4& p = i == 0 ? t.p0 : (i == 1 ? t.p1 : t.p2);
    return {p.s[0], p.s[1], p.s[2]};
}

void quad(std::vector<Triangle>& out, Vec3 a, Vec3 b, Vec3 c, Vec3 d) {
    out.push_back(tri(a, b, c));
    out.push_back(tri(a, c, d));
}

// A box's side faces and top (its bottom sits on the floor), from four floor corners and a height.
void block(std::vector<Triangle>& out, const Vec3 (&base)[4], float height) {
    Vec3 up{0, height, 0};
    for (int i = 0; i < 4; ++i) {
        Vec3 a = base[i], b = base[(i + 1) % 4];
        quad(out, a, b, b + up, a + up);
    }
    quad(out, base[0] + up, base[1] + up, base[2] + up, base[3] + up);
}

struct Scene {
    std::string name;
    std::vector<Triangle> triangles;
    Vec3 light_corner, light_u, light_v;  // the ceiling light, a parallelogram
    // The pinhole camera of the primary rays: vertical field of view in degrees.
    Vec3 eye{278, 273, -800}, forward{0, 0, 1}, right{-1, 0, 0}, up{0, 1, 0};
    float fov = 39.3f;
};

// The open Cornell box (classic 555-unit dimensions, no front wall) and its light.
void cornell_walls(Scene& s) {
    auto& t = s.triangles;
    quad(t, {0, 0, 0}, {556, 0, 0}, {556, 0, 559}, {0, 0, 559});            // floor
    quad(t, {0, 549, 0}, {0, 549, 559}, {556, 549, 559}, {556, 549, 0});    // ceiling
    quad(t, {0, 0, 559}, {556, 0, 559}, {556, 549, 559}, {0, 549, 559});    // back
    quad(t, {0, 0, 0}, {0, 0, 559}, {0, 549, 559}, {0, 549, 0});            // left
    quad(t, {556, 0, 0}, {556, 549, 0}, {556, 549, 559}, {556, 0, 559});    // right
    s.light_corner = {213, 548.8f, 227};
    s.light_u = {130, 0, 0};
    s.light_v = {0, 0, 105};
    quad(t, s.light_corner, s.light_corner + s.light_v, s.light_corner + s.light_u + s.light_v,
         s.light_corner + s.light_u);
}

Scene cornell_scene() {
    Scene s;
    s.name = "cornell";
    cornell_walls(s);
    block(s.triangles, {{130, 0, 65}, {82, 0, 225}, {240, 0, 272}, {290, 0, 114}}, 165);   // short
    block(s.triangles, {{423, 0, 247}, {265, 0, 296}, {314, 0, 456}, {472, 0, 406}}, 330);  // tall
    return s;
}

// A latitude-longitude sphere of `rings` x `segments` quads (triangles at the poles).
void sphere(std::vector<Triangle>& out, Vec3 c, float r, int rings, int segments) {
    auto p = [&](int i, int j) {
        float theta = float(M_PI) * float(i) / float(rings), phi = 2.0f * float(M_PI) * float(j % segments) / float(segments);
        return c + Vec3{std::sin(theta) * std::cos(phi), std::cos(theta), std::sin(theta) * std::sin(phi)} * r;
    };
    for (int i = 0; i < rings; ++i) {
        for (int j = 0; j < segments; ++j) {
            Vec3 a = p(i, j), b = p(i + 1, j), d = p(i + 1, j + 1), e = p(i, j + 1);
            if (i > 0) out.push_back(tri(a, b, e));
            if (i < rings - 1) out.push_back(tri(b, d, e));
        }
    }
}

Scene spheres_scene(long triangles) {
    Scene s;
    cornell_walls(s);
    // Two spheres of 2 * rings * (rings - 1) triangles each (segments = 2 rings).
    long per_sphere = std::max<long>(16, (triangles - long(s.triangles.size())) / 2);
    int rings = std::max(4, int(std::lround(std::sqrt(double(per_sphere) / 4.0))));
    sphere(s.triangles, {186, 120, 170}, 120, rings, 2 * rings);
    sphere(s.triangles, {370, 150, 370}, 150, rings, 2 * rings);
    s.name = "spheres";
    return s;
}

// Any scene the renderer loads, seen from the centre of its bounds (see --obj above).
Scene file_scene(const std::string& path) {
    clbdpt::Scene loaded = load_scene(path);
    Scene s;
    s.name = path;
    s.triangles = std::move(loaded.triangles);
    const Bounds3& b = loaded.bounds;
    Vec3 size = b.hi - b.lo;
    s.eye = b.center();
    s.forward = size.x >= size.z ? Vec3{1, 0, 0} : Vec3{0, 0, 1};
    s.up = {0, 1, 0};
    s.right = cross(s.forward, s.up);
    s.fov = 60.0f;
    s.light_corner = {b.lo.x + 0.25f * size.x, b.hi.y - 0.01f * size.y, b.lo.z + 0.25f * size.z};
    s.light_u = {0.5f * size.x, 0, 0};
    s.light_v = {0, 0, 0.5f * size.z};
    return s;
}

// ---- Rays -----------------------------------------------------------------------------------

struct RaySet {
    std::string kind;
    bool any_hit = false;
    std::vector<cl_float4> o, d;  // o.w = tmax
};

void push_ray(RaySet& set, Vec3 o, Vec3 d, float tmax) {
    set.o.push_back({{o.x, o.y, o.z, tmax}});
    set.d.push_back({{d.x, d.y, d.z, 0}});
}

Vec3 normal_of(const Triangle& t) {
    Vec3 a = corner(t, 0), b = corner(t, 1), c = corner(t, 2);
    Vec3 n = cross(b - a, c - a);
    float len = length(n);
    return len > 0 ? n * (1.0f / len) : Vec3{0, 1, 0};
}

Vec3 uniform_sphere(std::mt19937& rng) {
    std::uniform_real_distribution<float> u(0.0f, 1.0f);
    float z = 1.0f - 2.0f * u(rng), phi = 2.0f * float(M_PI) * u(rng), r = std::sqrt(std::max(0.0f, 1.0f - z * z));
    return {r * std::cos(phi), r * std::sin(phi), z};
}

Vec3 cosine_around(Vec3 n, std::mt19937& rng) {
    std::uniform_real_distribution<float> u(0.0f, 1.0f);
    float r = std::sqrt(u(rng)), phi = 2.0f * float(M_PI) * u(rng);
    Vec3 t = std::fabs(n.x) > 0.5f ? Vec3{0, 1, 0} : Vec3{1, 0, 0};
    Vec3 b1 = normalize(cross(n, t)), b2 = cross(n, b1);
    float z = std::sqrt(std::max(0.0f, 1.0f - r * r));
    return b1 * (r * std::cos(phi)) + b2 * (r * std::sin(phi)) + n * z;
}

// Host copy of cl/ray.h offset_ray_origin, for a point interpolated from a triangle's corners:
// its error off the plane is bounded by gamma(8) |p| along the normal here (generous; the
// kernels bound it from the corners, cl/lights.h triangle_point_error).
Vec3 offset_origin(Vec3 p, Vec3 ng, Vec3 w) {
    const float gamma8 = 8 * 0x1p-24f / (1 - 8 * 0x1p-24f);
    float error = gamma8 * (std::fabs(ng.x * p.x) + std::fabs(ng.y * p.y) + std::fabs(ng.z * p.z));
    Vec3 offset = ng * (dot(ng, w) < 0 ? -error : error);
    Vec3 out = p + offset;
    for (int k = 0; k < 3; ++k) {
        if (offset[k] > 0) out[k] = std::nextafter(out[k], INFINITY);
        if (offset[k] < 0) out[k] = std::nextafter(out[k], -INFINITY);
    }
    return out;
}

RaySet primary_rays(const Scene& scene, long count) {
    RaySet set{"primary", false, {}, {}};
    int w = int(std::sqrt(double(count))), h = int((count + w - 1) / w);
    const Vec3 &eye = scene.eye, &forward = scene.forward, &right = scene.right, &up = scene.up;
    float tan_half = std::tan(0.5f * scene.fov * float(M_PI) / 180.0f);
    for (long i = 0; i < count; ++i) {
        int x = int(i % w), y = int(i / w);
        float sx = (2.0f * (x + 0.5f) / float(w) - 1.0f) * tan_half;
        float sy = (1.0f - 2.0f * (y + 0.5f) / float(h)) * tan_half;
        push_ray(set, eye, normalize(forward + right * sx + up * sy), INFINITY);
    }
    return set;
}

struct SurfacePoint {
    Vec3 p, n;
};

// Area-weighted random points on the scene's triangles.
class SurfaceSampler {
public:
    explicit SurfaceSampler(const std::vector<Triangle>& tris) : tris_(tris) {
        cdf_.reserve(tris.size());
        double total = 0;
        for (const Triangle& t : tris) {
            total += 0.5 * length(cross(corner(t, 1) - corner(t, 0), corner(t, 2) - corner(t, 0)));
            cdf_.push_back(total);
        }
    }
    SurfacePoint sample(std::mt19937& rng) const {
        std::uniform_real_distribution<double> u(0.0, cdf_.back());
        std::uniform_real_distribution<float> v(0.0f, 1.0f);
        size_t i = std::min(cdf_.size() - 1, size_t(std::lower_bound(cdf_.begin(), cdf_.end(), u(rng)) - cdf_.begin()));
        const Triangle& t = tris_[i];
        float a = v(rng), b = v(rng);
        if (a + b > 1) a = 1 - a, b = 1 - b;
        return {corner(t, 0) * (1 - a - b) + corner(t, 1) * a + corner(t, 2) * b, normal_of(t)};
    }

private:
    const std::vector<Triangle>& tris_;
    std::vector<double> cdf_;
};

// ---- Tracers --------------------------------------------------------------------------------

struct TraceResult {
    std::vector<cl_float4> hits;  // closest: (t, b1, b2, triangle bits)
    std::vector<int> occluded;    // any hit
};

// Wall time and the CPU time of the whole process (PoCL's and Embree's threads included) of one
// run. Under load from other processes, rays per CPU-second times the core count is the steadier
// figure for comparing two tracers.
struct Timing {
    double wall = 0, cpu = 0;
};

double process_cpu_seconds() {
    timespec ts;
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
    return double(ts.tv_sec) + 1e-9 * double(ts.tv_nsec);
}

class Stopwatch {
public:
    Timing stop() const { return {seconds_since(wall_), process_cpu_seconds() - cpu_}; }

private:
    Clock::time_point wall_ = Clock::now();
    double cpu_ = process_cpu_seconds();
};

double median(std::vector<double> v) {
    if (v.empty()) return 0;
    std::sort(v.begin(), v.end());
    return v[v.size() / 2];
}

class ClTracer {
public:
    ClTracer(DeviceContext& ctx, const Bvh& bvh, const std::vector<Triangle>& tris, int local, bool huge_pages,
             bool count_visits)
        : ctx_(ctx), local_(local) {
        nodes_ = upload(bvh.nodes.data(), bvh.nodes.size() * sizeof(BvhNode), huge_pages, &nodes_memory_);
        const std::vector<TriangleRows> rows = triangle_rows(tris);
        tris_ = upload(rows.data(), rows.size() * sizeof(TriangleRows), huge_pages, &tris_memory_);
        const cl::Program& program = ctx.program("kernels/trace.cl", {}).program;
        closest_ = cl::Kernel(program, "trace_closest");
        any_ = cl::Kernel(program, "trace_any");
        if (count_visits)
            counted_ = cl::Kernel(ctx.program("kernels/trace.cl", {"BVH_COUNT_VISITS"}).program, "trace_closest");
    }

    // The loaded closest-hit rays' mean numbers of nodes visited and triangles tested, from the
    // diagnostic build (--count-visits).
    std::pair<double, double> visits() {
        size_t n = rays_->o.size();
        cl::Buffer counts(ctx_.context(), CL_MEM_WRITE_ONLY, n * sizeof(cl_float4));
        set_trace_args(counted_, counts);
        ctx_.queue().enqueueNDRangeKernel(counted_, cl::NullRange, cl::NDRange(n), cl::NullRange);
        std::vector<cl_float4> out(n);
        ctx_.queue().enqueueReadBuffer(counts, CL_TRUE, 0, n * sizeof(cl_float4), out.data());
        double nodes = 0, triangles = 0;
        for (const cl_float4& c : out) nodes += c.s[1], triangles += c.s[2];
        return {nodes / double(n), triangles / double(n)};
    }

    // Uploads a ray set; run() then traces it.
    void load(const RaySet& rays) {
        rays_ = &rays;
        size_t n = rays.o.size();
        cl::Context& c = ctx_.context();
        ob_ = cl::Buffer(c, CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR, n * sizeof(cl_float4), const_cast<cl_float4*>(rays.o.data()));
        db_ = cl::Buffer(c, CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR, n * sizeof(cl_float4), const_cast<cl_float4*>(rays.d.data()));
        out_ = cl::Buffer(c, CL_MEM_WRITE_ONLY, n * (rays.any_hit ? sizeof(int) : sizeof(cl_float4)));
        set_trace_args(rays.any_hit ? any_ : closest_, out_);
    }

    // The arguments of trace_closest and trace_any (cl/kernels/trace.cl) for the loaded rays.
    void set_trace_args(cl::Kernel& k, const cl::Buffer& out) {
        k.setArg(0, nodes_);
        k.setArg(1, tris_);
        k.setArg(2, ob_);
        k.setArg(3, db_);
        k.setArg(4, out);
        k.setArg(5, cl_int(rays_->o.size()));
    }


    Timing run() {
        size_t n = rays_->o.size();
        size_t global = local_ > 0 ? (n + local_ - 1) / local_ * local_ : n;
        cl::NDRange local = local_ > 0 ? cl::NDRange(size_t(local_)) : cl::NullRange;
        Stopwatch watch;
        ctx_.queue().enqueueNDRangeKernel(rays_->any_hit ? any_ : closest_, cl::NullRange, cl::NDRange(global), local);
        ctx_.queue().finish();
        return watch.stop();
    }

    TraceResult read() {
        size_t n = rays_->o.size();
        TraceResult result;
        if (rays_->any_hit) {
            result.occluded.resize(n);
            ctx_.queue().enqueueReadBuffer(out_, CL_TRUE, 0, n * sizeof(int), result.occluded.data());
        } else {
            result.hits.resize(n);
            ctx_.queue().enqueueReadBuffer(out_, CL_TRUE, 0, n * sizeof(cl_float4), result.hits.data());
        }
        return result;
    }

private:
    struct Free {
        void operator()(void* p) const { std::free(p); }
    };
    using HostMemory = std::unique_ptr<void, Free>;

    // A read-only device copy of the bytes. With huge_pages, the buffer uses host memory on 2 MiB
    // pages (CL_MEM_USE_HOST_PTR, which PoCL's CPU device uses in place): fewer TLB misses on
    // the random accesses of incoherent rays. Memory must outlive the buffer.
    cl::Buffer upload(const void* data, size_t bytes, bool huge_pages, HostMemory* memory) {
        if (!huge_pages)
            return cl::Buffer(ctx_.context(), CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR, bytes, const_cast<void*>(data));
        const size_t page = size_t(2) << 20;
        size_t size = (bytes + page - 1) / page * page;
        void* p = nullptr;
        if (posix_memalign(&p, page, size) != 0) throw Error("out of memory");
        memory->reset(p);
        madvise(p, size, MADV_HUGEPAGE);  // a hint: without transparent huge pages, normal pages
        std::memcpy(p, data, bytes);
        return cl::Buffer(ctx_.context(), CL_MEM_READ_ONLY | CL_MEM_USE_HOST_PTR, bytes, p);
    }

    DeviceContext& ctx_;
    int local_;
    HostMemory nodes_memory_, tris_memory_;
    const RaySet* rays_ = nullptr;
    cl::Buffer nodes_, tris_, ob_, db_, out_;
    cl::Kernel closest_, any_, counted_;
};

int hit_triangle(const cl_float4& h) {
    int i;
    std::memcpy(&i, &h.s[3], 4);
    return i;
}

#ifdef CLBDPT_HAVE_EMBREE
class EmbreeTracer {
public:
    EmbreeTracer(const std::vector<Triangle>& tris, int threads, bool spatial_splits) : threads_(threads) {
        device_ = rtcNewDevice(("threads=" + std::to_string(threads)).c_str());
        if (!device_) throw Error("rtcNewDevice failed");
        auto t0 = Clock::now();
        scene_ = rtcNewScene(device_);
        // Quality high builds with spatial splits; medium is binned SAH alone, like clbdpt's.
        rtcSetSceneBuildQuality(scene_, spatial_splits ? RTC_BUILD_QUALITY_HIGH : RTC_BUILD_QUALITY_MEDIUM);
        RTCGeometry geom = rtcNewGeometry(device_, RTC_GEOMETRY_TYPE_TRIANGLE);
        float* v = static_cast<float*>(rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                                                               3 * sizeof(float), 3 * tris.size()));
        unsigned* idx = static_cast<unsigned*>(rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                                                                       3 * sizeof(unsigned), tris.size()));
        for (size_t i = 0; i < tris.size(); ++i) {
            for (int c = 0; c < 3; ++c) {
                Vec3 p = corner(tris[i], c);
                v[9 * i + 3 * c + 0] = p.x;
                v[9 * i + 3 * c + 1] = p.y;
                v[9 * i + 3 * c + 2] = p.z;
                idx[3 * i + c] = unsigned(3 * i + c);
            }
        }
        rtcCommitGeometry(geom);
        rtcAttachGeometry(scene_, geom);
        rtcReleaseGeometry(geom);
        rtcCommitScene(scene_);
        build_seconds = seconds_since(t0);
    }
    ~EmbreeTracer() {
        rtcReleaseScene(scene_);
        rtcReleaseDevice(device_);
    }

    void load(const RaySet& rays) {
        rays_ = &rays;
        result_ = TraceResult();
        if (rays.any_hit) result_.occluded.resize(rays.o.size());
        else result_.hits.resize(rays.o.size());
    }

    Timing run() {
        const RaySet& rays = *rays_;
        TraceResult& result = result_;
        size_t n = rays.o.size();
        std::atomic<size_t> next{0};
        auto worker = [&] {
            RTCIntersectContext context;
            rtcInitIntersectContext(&context);
            const size_t chunk = 1024;
            for (;;) {
                size_t begin = next.fetch_add(chunk);
                if (begin >= n) break;
                size_t end = std::min(n, begin + chunk);
                for (size_t i = begin; i < end; ++i) {
                    RTCRayHit rh;
                    rh.ray.org_x = rays.o[i].s[0];
                    rh.ray.org_y = rays.o[i].s[1];
                    rh.ray.org_z = rays.o[i].s[2];
                    rh.ray.tnear = 0.0f;
                    rh.ray.dir_x = rays.d[i].s[0];
                    rh.ray.dir_y = rays.d[i].s[1];
                    rh.ray.dir_z = rays.d[i].s[2];
                    rh.ray.time = 0.0f;
                    rh.ray.tfar = rays.o[i].s[3];
                    rh.ray.mask = ~0u;
                    rh.ray.id = 0;
                    rh.ray.flags = 0;
                    if (rays.any_hit) {
                        rtcOccluded1(scene_, &context, &rh.ray);
                        result.occluded[i] = rh.ray.tfar < 0 ? 1 : 0;
                    } else {
                        rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
                        rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
                        rtcIntersect1(scene_, &context, &rh);
                        bool hit = rh.hit.geomID != RTC_INVALID_GEOMETRY_ID;
                        int prim = hit ? int(rh.hit.primID) : -1;
                        float bits;
                        std::memcpy(&bits, &prim, 4);
                        result.hits[i] = {{hit ? rh.ray.tfar : rays.o[i].s[3], rh.hit.u, rh.hit.v, bits}};
                    }
                }
            }
        };
        Stopwatch watch;
        std::vector<std::thread> pool;
        for (int t = 0; t < threads_; ++t) pool.emplace_back(worker);
        for (auto& th : pool) th.join();
        return watch.stop();
    }

    TraceResult read() { return result_; }

    double build_seconds = 0;

private:
    int threads_;
    const RaySet* rays_ = nullptr;
    TraceResult result_;
    RTCDevice device_ = nullptr;
    RTCScene scene_ = nullptr;
};
#endif

#ifdef CLBDPT_HAVE_EMBREE
// Fraction of rays on which two tracers agree: hit/miss, and for closest hits t within 1e-3
// relative (the triangle may differ at shared edges or exactly overlapping walls and lights).
double agreement(const RaySet& rays, const TraceResult& a, const TraceResult& b) {
    size_t n = rays.o.size(), same = 0;
    for (size_t i = 0; i < n; ++i) {
        if (rays.any_hit) {
            same += a.occluded[i] == b.occluded[i];
        } else {
            bool ha = hit_triangle(a.hits[i]) >= 0, hb = hit_triangle(b.hits[i]) >= 0;
            float ta = a.hits[i].s[0], tb = b.hits[i].s[0];
            same += ha == hb && (!ha || std::fabs(ta - tb) <= 1e-3f * std::max(ta, tb));
        }
    }
    return double(same) / double(n);
}
#endif

void run_scene(const Scene& scene, const Options& opt, DeviceContext& ctx) {
    const std::vector<Triangle>& input = scene.triangles;
    Bvh bvh = build_bvh(input, opt.bvh);
    std::vector<Triangle> tris = reorder(input, bvh.order);
    size_t n = input.size();
    double bytes = double(bvh.nodes.size() * sizeof(BvhNode) + tris.size() * sizeof(Triangle));
    std::printf("\nscene %s: %zu triangles\n", scene.name.c_str(), n);
    std::printf("  clbdpt BVH: build %.3f s, %zu nodes, %d leaves, depth %d, stack <= %d, %.1f bytes/triangle, "
                "%d spatial splits (%zu references, budget %.2f)\n",
                bvh.build_seconds, bvh.nodes.size(), bvh.leaf_count, bvh.max_depth, bvh.max_stack, bytes / double(n),
                bvh.spatial_splits, tris.size(), double(opt.bvh.spatial_split_budget));

    ClTracer cl_tracer(ctx, bvh, tris, opt.local, opt.huge_pages, opt.count_visits);
#ifdef CLBDPT_HAVE_EMBREE
    std::unique_ptr<EmbreeTracer> embree;
    if (opt.embree) {
        embree = std::make_unique<EmbreeTracer>(input, 2, opt.embree_quality == "high");
        std::printf("  Embree BVH: build %.3f s (quality %s, 2 threads)\n", embree->build_seconds,
                    opt.embree_quality.c_str());
    }
#endif

    // Ray sets. Primary first: bounce and light rays start at its hits.
    std::mt19937 rng(1234);
    std::vector<RaySet> sets;
    sets.push_back(primary_rays(scene, opt.rays));
    cl_tracer.load(sets[0]);
    cl_tracer.run();
    TraceResult primary = cl_tracer.read();
    std::vector<SurfacePoint> hits;
    for (size_t i = 0; i < primary.hits.size(); ++i) {
        int t = hit_triangle(primary.hits[i]);
        if (t < 0) continue;
        Vec3 d{sets[0].d[i].s[0], sets[0].d[i].s[1], sets[0].d[i].s[2]};
        const Triangle& tri = tris[size_t(t)];
        Vec3 ng = normal_of(tri);
        if (dot(ng, d) > 0) ng = ng * -1.0f;  // the side the camera sees
        // The hit point from the barycentrics, not o + t d: its error then scales with the
        // point's own magnitude, which is what offset_origin assumes.
        float b1 = primary.hits[i].s[1], b2 = primary.hits[i].s[2];
        hits.push_back({corner(tri, 0) * (1 - b1 - b2) + corner(tri, 1) * b1 + corner(tri, 2) * b2, ng});
    }
    if (hits.empty()) throw Error("no primary ray hit the scene");

    RaySet bounce{"bounce", false, {}, {}}, light{"light", true, {}, {}};
    for (long i = 0; i < opt.rays; ++i) {
        const SurfacePoint& h = hits[size_t(i) % hits.size()];
        Vec3 w = cosine_around(h.n, rng);
        push_ray(bounce, offset_origin(h.p, h.n, w), w, INFINITY);
        std::uniform_real_distribution<float> u(0.0f, 1.0f);
        Vec3 q = scene.light_corner + scene.light_u * u(rng) + scene.light_v * u(rng);
        Vec3 o = offset_origin(h.p, h.n, q - h.p);
        // Stop short of the light itself (its own triangle would occlude).
        push_ray(light, o, q - o, 1.0f - 1e-4f);
    }
    sets.push_back(std::move(bounce));

    Bounds3 bounds;
    for (const Triangle& t : tris)
        for (int c = 0; c < 3; ++c) bounds.extend(corner(t, c));
    RaySet random{"random", false, {}, {}};
    for (long i = 0; i < opt.rays; ++i) {
        std::uniform_real_distribution<float> ux(bounds.lo.x, bounds.hi.x), uy(bounds.lo.y, bounds.hi.y),
            uz(bounds.lo.z, bounds.hi.z);
        push_ray(random, {ux(rng), uy(rng), uz(rng)}, uniform_sphere(rng), INFINITY);
    }
    sets.push_back(random);
    sets.push_back(std::move(light));

    SurfaceSampler sampler(input);  // each triangle once, however many references it has
    RaySet connection{"connection", true, {}, {}};
    for (long i = 0; i < opt.rays; ++i) {
        SurfacePoint a = sampler.sample(rng), b = sampler.sample(rng);
        Vec3 o = offset_origin(a.p, a.n, b.p - a.p);
        Vec3 e = offset_origin(b.p, b.n, o - b.p);
        push_ray(connection, o, e - o, 1.0f - 1e-4f);  // pbrt's ShadowEpsilon: not the far surface itself
    }
    sets.push_back(std::move(connection));
    random.kind = "random-any";
    random.any_hit = true;
    sets.push_back(std::move(random));

    // Mray/s: rays over the median wall time. Per CPU-second: rays over the median CPU time of
    // the process, the steadier figure when other processes share the cores.
    std::printf("  %-11s %-7s %8s %8s %8s", "rays", "query", "count", "clbdpt", "per-cpu");
#ifdef CLBDPT_HAVE_EMBREE
    if (embree) std::printf(" %8s %8s %7s %7s %8s", "embree", "per-cpu", "ratio", "cpu", "agree");
#endif
    std::printf("\n");
    for (const RaySet& set : sets) {
        if (!opt.only.empty() && set.kind != opt.only) continue;
        const double n = double(set.o.size());
        std::vector<double> ours_wall, ours_cpu, theirs_wall, theirs_cpu;
        cl_tracer.load(set);
        cl_tracer.run();  // warm-up, not counted
#ifdef CLBDPT_HAVE_EMBREE
        if (embree) {
            embree->load(set);
            embree->run();
        }
#endif
        // Alternate the two tracers so load from elsewhere hits both alike.
        for (int r = 0; r < opt.repeats; ++r) {
            Timing t = cl_tracer.run();
            ours_wall.push_back(t.wall);
            ours_cpu.push_back(t.cpu);
#ifdef CLBDPT_HAVE_EMBREE
            if (embree) {
                t = embree->run();
                theirs_wall.push_back(t.wall);
                theirs_cpu.push_back(t.cpu);
            }
#endif
        }
        double ours_mrays = n / median(ours_wall) * 1e-6, ours_cpu_mrays = n / median(ours_cpu) * 1e-6;
        std::printf("  %-11s %-7s %8zu %8.2f %8.2f", set.kind.c_str(), set.any_hit ? "any" : "closest", set.o.size(),
                    ours_mrays, ours_cpu_mrays);
#ifdef CLBDPT_HAVE_EMBREE
        if (embree) {
            double theirs_mrays = n / median(theirs_wall) * 1e-6, theirs_cpu_mrays = n / median(theirs_cpu) * 1e-6;
            std::printf(" %8.2f %8.2f %7.2f %7.2f %7.2f%%", theirs_mrays, theirs_cpu_mrays, ours_mrays / theirs_mrays,
                        ours_cpu_mrays / theirs_cpu_mrays, 100.0 * agreement(set, cl_tracer.read(), embree->read()));
        }
#endif
        std::printf("\n");
        if (opt.count_visits && !set.any_hit) {
            std::pair<double, double> v = cl_tracer.visits();
            std::printf("  %-11s per ray: %.2f nodes visited, %.2f triangles tested\n", "", v.first, v.second);
        }
        std::fflush(stdout);
    }
}

double parse_number(const char* flag, const char* value) {
    if (!value) throw Error(std::string(flag) + " needs a value");
    char* end = nullptr;
    double v = std::strtod(value, &end);
    if (end == value || *end || !std::isfinite(v)) throw Error(std::string("bad value for ") + flag + ": " + value);
    return v;
}

long parse_long(const char* flag, const char* value) { return long(parse_number(flag, value)); }

int run(int argc, char** argv) {
    Options opt;
    for (int i = 1; i < argc; ++i) {
        std::string a = argv[i];
        const char* next = i + 1 < argc ? argv[i + 1] : nullptr;
        if (a == "--triangles") opt.triangles = parse_long("--triangles", next), ++i;
        else if (a == "--rays") opt.rays = parse_long("--rays", next), ++i;
        else if (a == "--repeats") opt.repeats = int(parse_long("--repeats", next)), ++i;
        else if (a == "--local") opt.local = int(parse_long("--local", next)), ++i;
        else if (a == "--device" && next) opt.device = next, ++i;
        else if (a == "--scene" && next) opt.scene = next, ++i;
        else if (a == "--obj" && next) opt.obj = next, ++i;
        else if (a == "--only" && next) opt.only = next, ++i;
        else if (a == "--huge-pages") opt.huge_pages = true;
        else if (a == "--no-embree") opt.embree = false;
        else if (a == "--count-visits") opt.count_visits = true;
        else if (a == "--spatial-splits")
            opt.bvh.spatial_split_budget = float(parse_number("--spatial-splits", next)), ++i;
        else if (a == "--embree-quality" && next && (std::string(next) == "high" || std::string(next) == "medium"))
            opt.embree_quality = next, ++i;
        else {
            std::fprintf(stderr,
                         "usage: traversal_bench [--triangles N] [--rays N] [--repeats K] [--local L] "
                         "[--device S] [--scene cornell|spheres|all] [--obj FILE] [--only KIND] [--huge-pages] "
                         "[--no-embree] [--embree-quality high|medium] [--count-visits] "
                         "[--spatial-splits BUDGET]\n");
            return a == "--help" || a == "-h" ? 0 : 2;
        }
    }
    if (opt.rays < 1 || opt.repeats < 1 || opt.triangles < 1) throw Error("--rays, --repeats, --triangles must be positive");

    DeviceEntry entry = select_device(opt.device);
    DeviceContext ctx(entry);
    auto t0 = Clock::now();
    const ProgramBuild& build = ctx.program("kernels/trace.cl", {});
    std::printf("device: %s (%s), kernel build %.2f s%s, work-group size %s\n", entry.name.c_str(),
                entry.platform_name.c_str(), seconds_since(t0), build.from_cache ? " (cache)" : "",
                opt.local > 0 ? std::to_string(opt.local).c_str() : "driver's choice");
    std::printf("rays per kind: %ld, repeats: %d (median reported), BVH width %d%s\n", opt.rays, opt.repeats, BVH_WIDTH,
                opt.huge_pages ? ", huge pages" : "");

    if (!opt.obj.empty()) {
        run_scene(file_scene(opt.obj), opt, ctx);
        return 0;
    }
    if (opt.scene == "cornell" || opt.scene == "all") run_scene(cornell_scene(), opt, ctx);
    if (opt.scene == "spheres" || opt.scene == "all") run_scene(spheres_scene(opt.triangles), opt, ctx);
    return 0;
}

}  // namespace
}  // namespace clbdpt

int main(int argc, char** argv) {
    try {
        return clbdpt::run(argc, argv);
    } catch (const std::exception& e) {
        std::fprintf(stderr, "traversal_bench: error: %s\n", e.what());
        return 1;
    }
}
