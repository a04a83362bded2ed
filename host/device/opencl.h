// The OpenCL layer: device discovery and selection, one context + in-order queue per device,
// and program builds with per-scene -D options, cached on disk as device binaries.
#pragma once

#define CL_HPP_TARGET_OPENCL_VERSION 120
#define CL_HPP_MINIMUM_OPENCL_VERSION 120
#ifndef CL_HPP_ENABLE_EXCEPTIONS
#define CL_HPP_ENABLE_EXCEPTIONS
#endif
#include <CL/opencl.hpp>

#include <cstdint>
#include <map>
#include <memory>
#include <string>
#include <vector>

namespace clbdpt {

struct DeviceEntry {
    int index = 0;  // position in list_devices(), what `--device N` names
    cl::Platform platform;
    cl::Device device;
    std::string platform_name;
    std::string name;
    std::string type;  // "CPU", "GPU", "accelerator", ...
    std::string version;         // CL_DEVICE_VERSION
    std::string opencl_c_version;
    std::string driver_version;
    unsigned compute_units = 0;
    uint64_t global_memory = 0;  // bytes
    uint64_t max_alloc = 0;      // bytes
};

// Every device of every platform, numbered in order. Empty if there is no OpenCL platform.
std::vector<DeviceEntry> list_devices();

// spec: "" = the first GPU, else the first CPU, else the first device; a number = that index;
// anything else = the first device whose name contains it (case-insensitive).
// Throws Error("unknown device 'x' (see `clbdpt devices`)") or Error("no OpenCL device ...").
DeviceEntry select_device(const std::string& spec);

// Several devices: specs separated by commas, or "all" for every device. Each device at most
// once (a spec naming one already chosen is an error). Throws Error like select_device.
std::vector<DeviceEntry> select_devices(const std::string& specs);

struct ProgramBuild {
    cl::Program program;
    double seconds = 0;      // wall time to get a usable program (build or cache load)
    bool from_cache = false;
    std::string options;     // the full option string given to the compiler
    std::string build_log;   // the compiler's log (warnings), often empty
};

// One device's context, queue and program cache.
class DeviceContext {
public:
    explicit DeviceContext(const DeviceEntry& entry, bool profiling = false);

    const DeviceEntry& entry() const { return entry_; }
    cl::Context& context() { return context_; }
    cl::CommandQueue& queue() { return queue_; }
    bool profiling() const { return profiling_; }

    // Builds (or loads from the disk cache, or returns the one already built in this process)
    // the program whose entry file is `entry_file` (relative to cl/, e.g. "kernels/render.cl")
    // with the given -D definitions ("NAME" or "NAME=VALUE"). Throws Error with the full build
    // log on failure.
    const ProgramBuild& program(const std::string& entry_file, const std::vector<std::string>& defines);

private:
    DeviceEntry entry_;
    cl::Context context_;
    cl::CommandQueue queue_;
    std::map<std::string, ProgramBuild> programs_;
    bool profiling_ = false;
};

// The expanded source of a kernel entry file: every `#include "x"` replaced by the file's text
// (once per file), with #line directives so compiler messages name the real cl/ file and line.
// Reads the embedded copy, or cl/ on disk when CLBDPT_KERNEL_DIR is set (developer switch).
std::string kernel_source(const std::string& entry_file);

// Directory of the program binary cache: $CLBDPT_CACHE_DIR, else $XDG_CACHE_HOME/clbdpt,
// else ~/.cache/clbdpt.
std::string program_cache_dir();

// PoCL sizes its CPU device from hwloc's view of the machine, which hwloc reads from /sys.
// Where /sys is not mounted (a bare chroot, some containers) hwloc finds no memory at all and
// PoCL aborts the whole process ("Not enough memory to run on this device"). There this returns
// a synthetic hwloc topology (HWLOC_SYNTHETIC, with HWLOC_COMPONENTS=synthetic) of the cores and
// memory sysconf reports, which clbdpt sets for itself before its first OpenCL call; elsewhere
// (or if the memory is unknown) it is empty.
std::string hwloc_topology_without_sysfs();

// Helper for error messages: "CL_OUT_OF_RESOURCES" etc.
const char* cl_error_name(int code);

}  // namespace clbdpt
