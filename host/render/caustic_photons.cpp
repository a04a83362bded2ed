#include "render/caustic_photons.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>

#include "util/error.h"

namespace clbdpt {

namespace {

// Light subpaths per pass and pixel. Their emitted rays are aimed at the mirrors and glass
// (specular_bounding_sphere), and they end at their first non-specular hit. Before the aiming,
// on cornell-specular (64 spp, 256 x 256, 3 seeds) 0.25, 0.5 and 1 gave MSE 4.54e-5, 4.32e-5 and
// 4.26e-5 for 0.2, 0.3 and 0.6 s of photons in a 7 s render, about even, and 0.5 was kept. Aimed,
// 0.25 finds 1.27x the photons that 0.5 found unaimed there, in 0.92x the time (163 027 against
// 128 682 in 64 passes, 0.33 s against 0.36 s).
constexpr double kPathsPerPixel = 0.25;
// Passes traced at once where a render needs one it has not traced; at the first, up to
// kSlicesAtFirst (a trace waits for the render launches in flight).
constexpr uint32_t kSlicesPerTrace = 8;
constexpr uint32_t kSlicesAtFirst = 64;
// Items per launch of the photon kernel: its output buffer holds a photon for each (64 MiB).
constexpr size_t kMaxTraceItems = size_t(1) << 20;
// The photons of all passes together, host and device each: past this, later passes reuse the
// photons of earlier ones (a lamp inside a glass shade makes every light subpath a photon).
constexpr double kPhotonBytesBudget = 256.0 * (1 << 20);

// trace_caustic_photons(SCENE_KERNEL_ARGS, paths_per_slice, first_slice, first_item, item_count,
//                       seed, out, count, aim)
constexpr cl_uint kTraceArg = SceneBuffers::kSceneArgCount;

}  // namespace

// The sphere about the box of every mirror and glass triangle (xyz centre, w radius), which the
// photons' emitted rays are aimed at: a caustic photon's first hit is on one of them. Widened by
// a thousandth of the scene's radius, so that rounding cannot take a grazing ray out of it.
// Only for scenes with such a triangle (scene_has_merged_caustics).
cl_float4 specular_bounding_sphere(const DeviceScene& scene) {
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (size_t i = 0; i < scene.triangles.size(); ++i) {
        if (!material_is_specular(scene.materials[size_t(scene.infos[i].material)])) continue;
        for (const cl_float4* p : {&scene.triangles[i].p0, &scene.triangles[i].p1, &scene.triangles[i].p2})
            for (int a = 0; a < 3; ++a) {
                lo[a] = std::min(lo[a], double(p->s[a]));
                hi[a] = std::max(hi[a], double(p->s[a]));
            }
    }
    cl_float4 sphere{};
    double r2 = 0;
    for (int a = 0; a < 3; ++a) {
        sphere.s[a] = float(0.5 * (lo[a] + hi[a]));
        r2 += 0.25 * (hi[a] - lo[a]) * (hi[a] - lo[a]);
    }
    sphere.s[3] = float(std::sqrt(r2) + 1e-3 * scene.info.world_center.s[3]);
    return sphere;
}

bool scene_has_merged_caustics(const DeviceScene& scene) {
    // Used materials only: an MTL file often defines materials that no face uses.
    return has_specular_surfaces(scene) && !scene.lights.empty();
}

CausticPhotons::CausticPhotons(DeviceContext& device, const cl::Program& program, const SceneBuffers& buffers,
                               const DeviceScene& scene, uint32_t seed, int planned_passes, double radius_pixels,
                               int local_size)
    : device_(device),
      seed_(seed),
      slice_count_(planned_passes > 0 ? std::min(uint32_t(planned_passes), kMaxPasses) : kMaxPasses),
      local_size_(local_size),
      aim_(specular_bounding_sphere(scene)) {
    const Camera& camera = scene.camera;
    paths_per_slice_ = uint32_t(std::max(1.0, std::ceil(kPathsPerPixel * camera.width * camera.height)));
    // One pixel's footprint at the scene centre's distance from the camera.
    const double dx = scene.info.world_center.s[0] - camera.eye.s[0];
    const double dy = scene.info.world_center.s[1] - camera.eye.s[1];
    const double dz = scene.info.world_center.s[2] - camera.eye.s[2];
    const double distance = std::max(std::sqrt(dx * dx + dy * dy + dz * dz), 1e-3 * scene.info.world_center.s[3]);
    radius0_ = radius_pixels * 2.0 * distance * camera.tan_half_height / camera.height;
    try {
        kernel_ = cl::Kernel(program, "trace_caustic_photons");
        buffers.set_args(kernel_);
        // PoCL compiles a kernel's work-group function at its first launch: that is done here,
        // with an empty launch as wide as the widest trace, so that it counts as build time.
        trace_out_ = cl::Buffer(device.context(), CL_MEM_WRITE_ONLY, sizeof(CausticPhoton) * max_trace_items());
        trace_count_ = cl::Buffer(device.context(), CL_MEM_READ_WRITE, sizeof(cl_uint));
        set_trace_args(0, 0, 0);
        device.queue().enqueueNDRangeKernel(kernel_, cl::NullRange, launch_size(max_trace_items()), local_range());
        device.queue().finish();
    } catch (const cl::Error& e) {
        throw Error(std::string("OpenCL: ") + e.what() + ": " + cl_error_name(e.err()) +
                    " while setting up caustic photons on " + device.entry().name);
    }
    upload();
}

cl::NDRange CausticPhotons::launch_size(size_t items) const {
    return local_size_ > 0 ? cl::NDRange((items + size_t(local_size_) - 1) / size_t(local_size_) * size_t(local_size_))
                           : cl::NDRange(items);
}

cl::NDRange CausticPhotons::local_range() const {
    return local_size_ > 0 ? cl::NDRange(size_t(local_size_)) : cl::NullRange;
}

size_t CausticPhotons::max_trace_items() const {
    return std::min(size_t(paths_per_slice_) * kSlicesPerTrace, kMaxTraceItems);
}

void CausticPhotons::set_trace_args(uint32_t first_slice, size_t first_item, size_t items) {
    kernel_.setArg(kTraceArg, cl_uint(paths_per_slice_));
    kernel_.setArg(kTraceArg + 1, cl_uint(first_slice));
    kernel_.setArg(kTraceArg + 2, cl_uint(first_item));
    kernel_.setArg(kTraceArg + 3, cl_uint(items));
    kernel_.setArg(kTraceArg + 4, cl_uint(seed_));
    kernel_.setArg(kTraceArg + 5, trace_out_);
    kernel_.setArg(kTraceArg + 6, trace_count_);
    kernel_.setArg(kTraceArg + 7, aim_);
}

double CausticPhotons::radius(uint32_t pass) const {
    return radius0_ * std::pow(double(pass % slice_count_) + 1.0, -1.0 / 6.0);
}

double CausticPhotons::smallest_radius(int passes) const {
    return radius(std::min(uint32_t(std::max(passes, 1)), slice_count_) - 1);
}

void CausticPhotons::ensure(uint32_t first_sample, uint32_t last_sample) {
    bool changed = false;
    if (traced_ == 0) {
        // The first pass's photons say what a pass's cost in memory: as many passes get photons
        // of their own as fit in the budget, at least one.
        trace(0, 1);
        changed = true;
        const double bytes = double(photons_.size()) * sizeof(CausticPhoton) + double(cells_.size()) * sizeof(cl_uint);
        if (bytes > 0) slice_count_ = uint32_t(std::clamp(kPhotonBytesBudget / bytes, 1.0, double(slice_count_)));
    }
    std::vector<uint32_t> wanted;
    if (uint64_t(last_sample) - first_sample + 1 >= slice_count_) {
        for (uint32_t q = 0; q < slice_count_; ++q) wanted.push_back(q);
    } else {
        for (uint64_t i = first_sample; i <= last_sample; ++i) wanted.push_back(uint32_t(i % slice_count_));
    }
    for (uint32_t q : wanted) {
        if (q < slices_.size() && slices_[q].radius > 0) continue;
        // This pass and the next few untraced ones, in one launch; at the first, many more:
        // a trace waits for the launches in flight.
        const uint32_t most = traced_ == 1 ? kSlicesAtFirst : kSlicesPerTrace;
        uint32_t count = 1;
        while (count < most && q + count < slice_count_ &&
               !(q + count < slices_.size() && slices_[q + count].radius > 0))
            ++count;
        for (uint32_t k = 0; k < count; k += kSlicesPerTrace) trace(q + k, std::min(kSlicesPerTrace, count - k));
        changed = true;
    }
    if (changed) upload();
}

void CausticPhotons::trace(uint32_t first_slice, uint32_t count) {
    const auto start = std::chrono::steady_clock::now();
    const size_t items = size_t(paths_per_slice_) * count;
    std::vector<CausticPhoton> found;
    try {
        cl::CommandQueue& queue = device_.queue();
        for (size_t first = 0; first < items; first += max_trace_items()) {
            const size_t n = std::min(max_trace_items(), items - first);
            const cl_uint zero = 0;
            queue.enqueueWriteBuffer(trace_count_, CL_TRUE, 0, sizeof zero, &zero);
            set_trace_args(first_slice, first, n);
            queue.enqueueNDRangeKernel(kernel_, cl::NullRange, launch_size(n), local_range());
            cl_uint appended = 0;
            queue.enqueueReadBuffer(trace_count_, CL_TRUE, 0, sizeof appended, &appended);
            found.resize(found.size() + appended);
            if (appended > 0)
                queue.enqueueReadBuffer(trace_out_, CL_TRUE, 0, sizeof(CausticPhoton) * appended,
                                        &found[found.size() - appended]);
        }
    } catch (const cl::Error& e) {
        throw Error(std::string("OpenCL: ") + e.what() + ": " + cl_error_name(e.err()) +
                    " while tracing caustic photons on " + device_.entry().name);
    }
    // In the order of the light subpaths that found them (beta.w holds the subpath's item).
    const auto item = [](const CausticPhoton& ph) {
        cl_uint i;
        std::memcpy(&i, &ph.beta.s[3], sizeof i);
        return i;
    };
    std::sort(found.begin(), found.end(), [&](const CausticPhoton& a, const CausticPhoton& b) { return item(a) < item(b); });
    if (slices_.size() < first_slice + count) slices_.resize(first_slice + count, MergeSlice{});
    size_t next = 0;
    for (uint32_t k = 0; k < count; ++k) {
        const uint32_t q = first_slice + k;
        MergeSlice& slice = slices_[q];
        const double r = radius(q);
        slice.radius = float(r);
        slice.inv_cell = float(1.0 / (2.0 * r));
        slice.estimate_scale = float(1.0 / (double(paths_per_slice_) * M_PI * r * r));
        // The pass's photons, binned by cell with a counting sort (within a cell they stay in
        // subpath order, so the sums are reproducible).
        const size_t begin = next;
        while (next < found.size() && item(found[next]) / paths_per_slice_ == k) ++next;
        const size_t n = next - begin;
        uint32_t cells = 1;
        while (cells < 2 * n) cells <<= 1;
        slice.cell_mask = cells - 1;
        slice.photon_begin = cl_uint(photons_.size());
        slice.cell_begin = cl_uint(cells_.size());
        std::vector<cl_uint> slot(n);
        std::vector<cl_uint> start_of(size_t(cells) + 1, 0);
        for (size_t i = 0; i < n; ++i) {
            const cl_float4& p = found[begin + i].p;
            const auto cell = [&](int axis) { return cl_int(std::floor(p.s[axis] * slice.inv_cell)); };
            slot[i] = merge_cell_hash(cell(0), cell(1), cell(2)) & slice.cell_mask;
            ++start_of[slot[i] + 1];
        }
        for (uint32_t c = 0; c < cells; ++c) start_of[c + 1] += start_of[c];
        cells_.insert(cells_.end(), start_of.begin(), start_of.end());
        photons_.resize(photons_.size() + n);
        CausticPhoton* binned = &photons_[slice.photon_begin];
        for (size_t i = 0; i < n; ++i) binned[start_of[slot[i]]++] = found[begin + i];
        ++traced_;
    }
    seconds_ += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

void CausticPhotons::upload() {
    cl::Context& ctx = device_.context();
    // Never empty: an OpenCL buffer has at least one byte.
    const auto buffer = [&ctx](const auto& v) {
        using T = typename std::decay_t<decltype(v)>::value_type;
        const size_t n = std::max<size_t>(1, v.size());
        cl::Buffer b(ctx, CL_MEM_READ_ONLY, sizeof(T) * n);
        return b;
    };
    try {
        photons_buffer_ = buffer(photons_);
        cells_buffer_ = buffer(cells_);
        slices_buffer_ = buffer(slices_);
        cl::CommandQueue& queue = device_.queue();
        if (!photons_.empty())
            queue.enqueueWriteBuffer(photons_buffer_, CL_TRUE, 0, sizeof(CausticPhoton) * photons_.size(), photons_.data());
        if (!cells_.empty())
            queue.enqueueWriteBuffer(cells_buffer_, CL_TRUE, 0, sizeof(cl_uint) * cells_.size(), cells_.data());
        if (!slices_.empty())
            queue.enqueueWriteBuffer(slices_buffer_, CL_TRUE, 0, sizeof(MergeSlice) * slices_.size(), slices_.data());
    } catch (const cl::Error& e) {
        throw Error(std::string("OpenCL: ") + e.what() + ": " + cl_error_name(e.err()) +
                    " while uploading caustic photons to " + device_.entry().name);
    }
}

void CausticPhotons::set_args(cl::Kernel& kernel, cl_uint first) const {
    kernel.setArg(first, photons_buffer_);
    kernel.setArg(first + 1, cells_buffer_);
    kernel.setArg(first + 2, slices_buffer_);
    kernel.setArg(first + 3, cl_uint(slice_count_));
}

}  // namespace clbdpt
