// The caustic photons that caustic merging (cl/caustic_merging.h) reads: for each pass, light
// subpaths traced on their own by the photon kernel, their caustic photons binned into a hashed
// grid of cells twice the pass's merge radius wide, all passes' grids in three device buffers.
//
// A pass's photons depend on the seed and the pass alone, so an image is the same however its
// passes are split between launches or devices (each device traces the passes it renders).
// The radius shrinks with the pass, r_q = r_0 (q + 1)^(-1/6) (progressive photon mapping's
// alpha = 2/3), so the blur's bias fades as passes accumulate; r_0 is a number of pixel
// footprints at the distance of the scene's centre from the camera. At most kMaxPasses passes
// have photons of their own, fewer where their photons would take more than 256 MiB (the first
// pass's count decides); the passes past them reuse theirs (pass i takes pass i % count's).
#pragma once

#include <cstdint>
#include <vector>

#include "device/opencl.h"
#include "render/device_scene.h"
#include "render/scene_buffers.h"

namespace clbdpt {

// Whether a scene has paths that caustic merging takes over: a triangle of mirror or glass and
// a light (of any kind). Media may fill the scene: a medium vertex counts as non-specular on both
// sides of the split.
bool scene_has_merged_caustics(const DeviceScene& scene);

// The sphere about the box of every mirror and glass triangle (xyz centre, w radius): a caustic
// photon's first hit lies in it, so its emitted ray is aimed at it (cl/lights.h,
// light_emission_aimed).
cl_float4 specular_bounding_sphere(const DeviceScene& scene);

class CausticPhotons {
public:
    // program: built with HAS_CAUSTIC_MERGING (its trace_caustic_photons kernel), whose work-group
    // function is compiled here (an empty launch) at local_size (0: the driver's). planned_passes:
    // the render's passes (0: not known ahead). The first min(planned_passes, kMaxPasses) passes
    // (kMaxPasses if not known) have photons of their own, fewer if the memory budget says so;
    // sample index i uses pass i % that many's (adaptive sampling's extra samples, past the
    // passes, reuse the passes' photons).
    CausticPhotons(DeviceContext& device, const cl::Program& program, const SceneBuffers& buffers,
                   const DeviceScene& scene, uint32_t seed, int planned_passes, double radius_pixels,
                   int local_size);
    static constexpr uint32_t kMaxPasses = 256;

    // Traces the photons of every pass that sample indices [first, last] use and has none yet.
    void ensure(uint32_t first_sample, uint32_t last_sample);
    // Sets the render kernel's photons, cells, slices and slice count, from argument `first` on.
    void set_args(cl::Kernel& kernel, cl_uint first) const;

    uint32_t paths_per_pass() const { return paths_per_slice_; }
    double radius(uint32_t pass) const;
    // The smallest radius of a render of `passes` passes: its last pass's with photons of its own.
    double smallest_radius(int passes) const;
    uint64_t photons() const { return photons_.size(); }
    uint32_t passes_traced() const { return traced_; }
    // Passes with photons of their own (sample index i uses pass i % this many's).
    uint32_t passes_with_photons() const { return slice_count_; }
    double seconds() const { return seconds_; }

private:
    void trace(uint32_t first_slice, uint32_t count);
    cl::NDRange launch_size(size_t items) const;
    cl::NDRange local_range() const;
    size_t max_trace_items() const;
    void set_trace_args(uint32_t first_slice, size_t first_item, size_t items);
    void upload();

    DeviceContext& device_;
    cl::Kernel kernel_;
    uint32_t seed_;
    uint32_t slice_count_;
    uint32_t paths_per_slice_;
    int local_size_;  // the render kernel's work-group size (0: the driver's choice)
    cl_float4 aim_;   // the photons' emitted rays are aimed at this sphere (specular_bounding_sphere)
    double radius0_;
    std::vector<CausticPhoton> photons_;
    std::vector<cl_uint> cells_;
    std::vector<MergeSlice> slices_;  // indexed by pass; radius 0: not traced yet
    uint32_t traced_ = 0;
    double seconds_ = 0;
    cl::Buffer photons_buffer_, cells_buffer_, slices_buffer_, trace_out_, trace_count_;
};

}  // namespace clbdpt
