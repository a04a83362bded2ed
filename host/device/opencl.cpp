// The OpenCL layer: devices, contexts, kernel source expansion and program builds with an
// on-disk binary cache. Every cl::Error that escapes the OpenCL C++ bindings is turned into a
// clbdpt::Error at the public entry points, so callers deal with one exception type.
#include "device/opencl.h"

#include "device/embedded_kernels.h"
#include "util/error.h"

#include <algorithm>
#include <atomic>
#include <cctype>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <iterator>
#include <set>
#include <sstream>
#include <unordered_map>
#include <utility>

#include <unistd.h>

namespace clbdpt {

namespace fs = std::filesystem;

// Returned by the ICD loader when no platform is installed (cl_khr_icd). Not in every header.
constexpr cl_int kPlatformNotFoundKhr = -1001;

namespace {

// ---- Small helpers -----------------------------------------------------------------------------


std::string env_or_empty(const char* name) {
    const char* value = std::getenv(name);
    return value ? std::string(value) : std::string();
}

std::string to_lower(std::string s) {
    std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
    return s;
}

// OpenCL info strings often carry a trailing NUL or spaces.
std::string trimmed(std::string s) {
    while (!s.empty() && (s.back() == '\0' || std::isspace(static_cast<unsigned char>(s.back())))) s.pop_back();
    size_t first = 0;
    while (first < s.size() && std::isspace(static_cast<unsigned char>(s[first]))) ++first;
    return s.substr(first);
}

// A failed build as one line: the first diagnostic of the compiler's log that says "error"
// (else its first line), with the whole log saved to a file the line names.
Error build_failure(const std::string& entry_file, const std::string& device_name, const std::string& raw_log) {
    const std::string log = trimmed(raw_log);
    std::string first, line;
    std::istringstream lines(log);
    while (std::getline(lines, line)) {
        if (first.empty() && !line.empty()) first = line;
        if (line.find("error") != std::string::npos) {
            first = line;
            break;
        }
    }
    std::string saved;
    const std::string log_path =
        (fs::temp_directory_path() / ("clbdpt-build-" + std::to_string(static_cast<long>(::getpid())) + ".log")).string();
    if (std::ofstream(log_path) << log << "\n") saved = " (whole log: " + log_path + ")";
    return Error("kernel build failed for " + entry_file + " on " + device_name + ": " +
                 (first.empty() ? "no log from the compiler" : first) + saved);
}

// "OpenCL: clCreateContext: CL_OUT_OF_HOST_MEMORY"
Error cl_failure(const cl::Error& e) {
    return Error(std::string("OpenCL: ") + e.what() + ": " + cl_error_name(e.err()));
}

std::string device_type_name(cl_device_type type) {
    std::vector<std::string> names;
    if (type & CL_DEVICE_TYPE_GPU) names.push_back("GPU");
    if (type & CL_DEVICE_TYPE_CPU) names.push_back("CPU");
    if (type & CL_DEVICE_TYPE_ACCELERATOR) names.push_back("accelerator");
    if (type & CL_DEVICE_TYPE_CUSTOM) names.push_back("custom");
    if (names.empty()) return "unknown";
    std::string out = names[0];
    for (size_t i = 1; i < names.size(); ++i) out += "+" + names[i];
    return out;
}

// ---- Kernel sources ------------------------------------------------------------------------------

// Where the kernel files come from: the copy embedded at build time, or a directory on disk.
class KernelFiles {
public:
    KernelFiles() : dir_(env_or_empty("CLBDPT_KERNEL_DIR")) {}

    // The file's text, or false if there is no such file.
    bool read(const std::string& path, std::string* text) const {
        if (dir_.empty()) {
            const auto& table = embedded();
            auto it = table.find(path);
            if (it == table.end()) return false;
            *text = it->second;
            return true;
        }
        std::ifstream in(fs::path(dir_) / path, std::ios::binary);
        if (!in) return false;
        text->assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
        return !in.bad();
    }

    // The name #line directives give the file: its path in the repository (embedded) or on disk.
    std::string display_name(const std::string& path) const {
        return dir_.empty() ? "cl/" + path : (fs::path(dir_) / path).string();
    }

private:
    static const std::unordered_map<std::string, std::string>& embedded() {
        static const std::unordered_map<std::string, std::string> table = [] {
            std::unordered_map<std::string, std::string> t;
            size_t count = 0;
            const EmbeddedFile* files = embedded_kernel_files(&count);
            for (size_t i = 0; i < count; ++i) t.emplace(files[i].path, files[i].text);
            return t;
        }();
        return table;
    }

    std::string dir_;
};

// A #line file name is a C string literal.
std::string quoted(const std::string& s) {
    std::string out = "\"";
    for (char c : s) {
        if (c == '"' || c == '\\') out += '\\';
        out += c;
    }
    return out + "\"";
}

// If `line` is `#include "name"` (spaces allowed around '#' and 'include'), sets name.
// `#include <...>` and anything else is left to the device compiler.
bool parse_quoted_include(const std::string& line, std::string* name) {
    size_t i = 0;
    auto skip_blanks = [&] {
        while (i < line.size() && (line[i] == ' ' || line[i] == '\t')) ++i;
    };
    skip_blanks();
    if (i >= line.size() || line[i] != '#') return false;
    ++i;
    skip_blanks();
    static const std::string kInclude = "include";
    if (line.compare(i, kInclude.size(), kInclude) != 0) return false;
    i += kInclude.size();
    skip_blanks();
    if (i >= line.size() || line[i] != '"') return false;
    size_t close = line.find('"', i + 1);
    if (close == std::string::npos) return false;
    *name = line.substr(i + 1, close - i - 1);
    return true;
}

void expand_file(const KernelFiles& files, const std::string& path, const std::string& text,
                 std::set<std::string>* included, std::string* out) {
    const std::string display = quoted(files.display_name(path));
    *out += "#line 1 " + display + "\n";
    std::istringstream lines(text);
    std::string line;
    int number = 0;
    while (std::getline(lines, line)) {
        ++number;
        if (!line.empty() && line.back() == '\r') line.pop_back();
        std::string name;
        if (!parse_quoted_include(line, &name)) {
            *out += line;
            *out += '\n';
            continue;
        }
        if (!included->insert(name).second) {
            *out += '\n';  // already expanded once: acts as #pragma once; keeps line numbers
            continue;
        }
        std::string child;
        if (!files.read(name, &child)) {
            throw Error(files.display_name(path) + ":" + std::to_string(number) + ": cannot include \"" + name +
                        "\": no such kernel file");
        }
        expand_file(files, name, child, included, out);
        *out += "#line " + std::to_string(number + 1) + " " + display + "\n";
    }
}

// ---- Program cache ---------------------------------------------------------------------------------

// FNV-1a, 64 bits, over length-prefixed fields so ("ab","c") and ("a","bc") differ.
class Fnv1a64 {
public:
    void add(const std::string& field) {
        uint64_t length = field.size();
        for (int i = 0; i < 8; ++i) byte(static_cast<unsigned char>(length >> (8 * i)));
        for (char c : field) byte(static_cast<unsigned char>(c));
    }
    std::string hex() const {
        char buf[17];
        std::snprintf(buf, sizeof buf, "%016llx", static_cast<unsigned long long>(hash_));
        return buf;
    }

private:
    void byte(unsigned char b) {
        hash_ ^= b;
        hash_ *= 0x100000001b3ull;
    }
    uint64_t hash_ = 0xcbf29ce484222325ull;
};

// Bumped whenever the cache file format or the key's ingredients change.
constexpr const char* kCacheFormat = "clbdpt-program-cache-1";

void warn_cache_once(const std::string& message) {
    static std::atomic<bool> warned{false};
    if (warned.exchange(true)) return;
    std::cerr << "clbdpt: warning: program cache disabled: " << message << "\n";
}

bool read_binary_file(const fs::path& path, std::vector<unsigned char>* data) {
    std::ifstream in(path, std::ios::binary);
    if (!in) return false;
    data->assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
    return !in.bad() && !data->empty();
}

// Writes to a temporary file in the same directory and renames it into place, so a concurrent
// reader sees either no file or the whole file.
void write_cache_file(const fs::path& path, const std::vector<unsigned char>& data) {
    fs::path tmp = path;
    tmp += ".tmp." + std::to_string(::getpid());
    {
        std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
        if (!out) {
            warn_cache_once("cannot write " + tmp.string());
            return;
        }
        out.write(reinterpret_cast<const char*>(data.data()), static_cast<std::streamsize>(data.size()));
        out.close();
        if (!out) {
            std::error_code ignored;
            fs::remove(tmp, ignored);
            warn_cache_once("cannot write " + tmp.string());
            return;
        }
    }
    std::error_code ec;
    fs::rename(tmp, path, ec);
    if (ec) {
        std::error_code ignored;
        fs::remove(tmp, ignored);
        warn_cache_once("cannot rename " + tmp.string() + ": " + ec.message());
    }
}

// The cache's size limit in bytes: CLBDPT_CACHE_MAX_MB, default 512 MiB (about 1400 render
// kernels of ~370 KB); 0 means no limit. Every scene, integrator and depth builds a kernel of
// its own, so without a limit the cache only grows (a developer's reached 744 MB).
uint64_t cache_max_bytes() {
    constexpr uint64_t kDefaultMiB = 512;
    const std::string text = env_or_empty("CLBDPT_CACHE_MAX_MB");
    char* end = nullptr;
    const unsigned long long mib = text.empty() ? kDefaultMiB : std::strtoull(text.c_str(), &end, 10);
    if (!text.empty() && (end == text.c_str() || *end)) return kDefaultMiB << 20;
    return uint64_t(mib) << 20;
}

// Keeps the cache within cache_max_bytes(): removes the least recently used binaries (a hit
// refreshes a file's time) until the rest fit, never `keep`, the one just written; and the
// temporary files of writers that died more than an hour ago. Files that another process
// removes first, or that cannot be removed, are passed over.
void trim_cache(const fs::path& dir, const fs::path& keep) {
    const uint64_t limit = cache_max_bytes();
    struct Entry {
        fs::path path;
        fs::file_time_type used;
        uint64_t bytes;
    };
    std::vector<Entry> binaries;
    uint64_t total = 0;
    std::error_code ec;
    const auto stale = fs::file_time_type::clock::now() - std::chrono::hours(1);
    for (fs::directory_iterator it(dir, ec), end; !ec && it != end; it.increment(ec)) {
        const fs::path& path = it->path();
        const auto used = fs::last_write_time(path, ec);
        const uintmax_t bytes = fs::file_size(path, ec);
        if (ec) {
            ec.clear();
            continue;
        }
        if (path.filename().string().find(".bin.tmp.") != std::string::npos) {
            if (used < stale) fs::remove(path, ec);
            ec.clear();
        } else if (path.extension() == ".bin") {
            binaries.push_back({path, used, uint64_t(bytes)});
            total += bytes;
        }
    }
    if (limit == 0 || total <= limit) return;
    std::sort(binaries.begin(), binaries.end(), [](const Entry& a, const Entry& b) { return a.used < b.used; });
    for (const Entry& e : binaries) {
        if (total <= limit) break;
        if (e.path == keep) continue;
        if (fs::remove(e.path, ec) && !ec) total -= e.bytes;
        ec.clear();
    }
}

// The cache directory, created if needed; empty if caching is not possible.
fs::path usable_cache_dir() {
    std::string dir = program_cache_dir();
    if (dir.empty()) {
        warn_cache_once("no cache directory (set CLBDPT_CACHE_DIR or HOME)");
        return {};
    }
    std::error_code ec;
    fs::create_directories(dir, ec);
    if (ec || !fs::is_directory(dir, ec)) {
        warn_cache_once("cannot create " + dir + (ec ? ": " + ec.message() : std::string()));
        return {};
    }
    return dir;
}

// Must run before the first OpenCL call; a user's own HWLOC_SYNTHETIC or HWLOC_COMPONENTS
// wins.
void describe_machine_to_hwloc_without_sysfs() {
    if (std::getenv("HWLOC_SYNTHETIC") || std::getenv("HWLOC_COMPONENTS")) return;
    const std::string topology = hwloc_topology_without_sysfs();
    if (topology.empty()) return;
    ::setenv("HWLOC_COMPONENTS", "synthetic", 0);
    ::setenv("HWLOC_SYNTHETIC", topology.c_str(), 0);
}

}  // namespace

std::string hwloc_topology_without_sysfs() {
    std::error_code ec;
    if (std::filesystem::is_directory("/sys/devices/system/cpu", ec)) return {};
    const long cores = std::max(1L, ::sysconf(_SC_NPROCESSORS_ONLN));
    const long long memory = static_cast<long long>(::sysconf(_SC_PHYS_PAGES)) * ::sysconf(_SC_PAGE_SIZE);
    if (memory <= 0) return {};
    return "numa:1(memory=" + std::to_string(memory) + ") core:" + std::to_string(cores) + " pu:1";
}

// ---- Devices ---------------------------------------------------------------------------------------

std::vector<DeviceEntry> list_devices() {
    std::vector<DeviceEntry> entries;
    describe_machine_to_hwloc_without_sysfs();
    try {
        // The raw calls, because the bindings treat "no platform" and "no device" as errors.
        cl_uint platform_count = 0;
        cl_int err = ::clGetPlatformIDs(0, nullptr, &platform_count);
        if (err == kPlatformNotFoundKhr || platform_count == 0) return entries;
        if (err != CL_SUCCESS) throw cl::Error(err, "clGetPlatformIDs");
        std::vector<cl_platform_id> platform_ids(platform_count);
        err = ::clGetPlatformIDs(platform_count, platform_ids.data(), nullptr);
        if (err != CL_SUCCESS) throw cl::Error(err, "clGetPlatformIDs");

        for (cl_platform_id platform_id : platform_ids) {
            cl::Platform platform(platform_id);
            cl_uint device_count = 0;
            err = ::clGetDeviceIDs(platform_id, CL_DEVICE_TYPE_ALL, 0, nullptr, &device_count);
            if (err == CL_DEVICE_NOT_FOUND || device_count == 0) continue;
            if (err != CL_SUCCESS) throw cl::Error(err, "clGetDeviceIDs");
            std::vector<cl_device_id> device_ids(device_count);
            err = ::clGetDeviceIDs(platform_id, CL_DEVICE_TYPE_ALL, device_count, device_ids.data(), nullptr);
            if (err != CL_SUCCESS) throw cl::Error(err, "clGetDeviceIDs");

            const std::string platform_name = trimmed(platform.getInfo<CL_PLATFORM_NAME>());
            for (cl_device_id device_id : device_ids) {
                DeviceEntry e;
                e.index = static_cast<int>(entries.size());
                e.platform = platform;
                e.device = cl::Device(device_id, /*retainObject=*/true);
                e.platform_name = platform_name;
                e.name = trimmed(e.device.getInfo<CL_DEVICE_NAME>());
                e.type = device_type_name(e.device.getInfo<CL_DEVICE_TYPE>());
                e.version = trimmed(e.device.getInfo<CL_DEVICE_VERSION>());
                e.opencl_c_version = trimmed(e.device.getInfo<CL_DEVICE_OPENCL_C_VERSION>());
                e.driver_version = trimmed(e.device.getInfo<CL_DRIVER_VERSION>());
                e.compute_units = e.device.getInfo<CL_DEVICE_MAX_COMPUTE_UNITS>();
                e.global_memory = e.device.getInfo<CL_DEVICE_GLOBAL_MEM_SIZE>();
                e.max_alloc = e.device.getInfo<CL_DEVICE_MAX_MEM_ALLOC_SIZE>();
                entries.push_back(std::move(e));
            }
        }
    } catch (const cl::Error& e) {
        throw cl_failure(e);
    }
    return entries;
}

DeviceEntry select_device(const std::string& spec) {
    std::vector<DeviceEntry> devices = list_devices();
    if (devices.empty()) throw Error("no OpenCL device found (is pocl-opencl-icd installed?)");

    if (spec.empty()) {
        for (const char* wanted : {"GPU", "CPU"}) {
            for (const DeviceEntry& d : devices) {
                if (d.type.find(wanted) != std::string::npos) return d;
            }
        }
        return devices.front();
    }

    if (std::all_of(spec.begin(), spec.end(), [](unsigned char c) { return std::isdigit(c); })) {
        // Compare as text lengths first so a huge number cannot overflow.
        size_t index = spec.size() <= 9 ? std::stoul(spec) : devices.size();
        if (index < devices.size()) return devices[index];
        throw Error("unknown device '" + spec + "' (" + std::to_string(devices.size()) +
                    (devices.size() == 1 ? " device" : " devices") + "; see `clbdpt devices`)");
    }

    const std::string needle = to_lower(spec);
    for (const DeviceEntry& d : devices) {
        if (to_lower(d.name).find(needle) != std::string::npos) return d;
    }
    throw Error("unknown device '" + spec + "' (see `clbdpt devices`)");
}

std::vector<DeviceEntry> select_devices(const std::string& specs) {
    if (specs == "all") {
        std::vector<DeviceEntry> devices = list_devices();
        if (devices.empty()) throw Error("no OpenCL device found (is pocl-opencl-icd installed?)");
        return devices;
    }
    std::vector<DeviceEntry> chosen;
    size_t start = 0;
    for (;;) {
        size_t comma = specs.find(',', start);
        std::string spec = specs.substr(start, comma == std::string::npos ? std::string::npos : comma - start);
        DeviceEntry entry = select_device(spec);
        for (const DeviceEntry& c : chosen)
            if (c.index == entry.index)
                throw Error("device " + std::to_string(entry.index) + " ('" + entry.name + "') named twice in '" +
                            specs + "'");
        chosen.push_back(entry);
        if (comma == std::string::npos) break;
        start = comma + 1;
    }
    return chosen;
}

DeviceContext::DeviceContext(const DeviceEntry& entry, bool profiling) : entry_(entry), profiling_(profiling) {
    try {
        context_ = cl::Context(entry_.device);
        cl::QueueProperties props = profiling ? cl::QueueProperties::Profiling : cl::QueueProperties::None;
        queue_ = cl::CommandQueue(context_, entry_.device, props);
    } catch (const cl::Error& e) {
        throw cl_failure(e);
    }
}

// ---- Kernel sources ----------------------------------------------------------------------------------

std::string kernel_source(const std::string& entry_file) {
    KernelFiles files;
    std::string text;
    if (!files.read(entry_file, &text)) {
        throw Error("unknown kernel file '" + entry_file + "' (looked for " + files.display_name(entry_file) + ")");
    }
    std::set<std::string> included{entry_file};
    std::string out;
    expand_file(files, entry_file, text, &included, &out);
    return out;
}

// ---- Programs ----------------------------------------------------------------------------------------

const ProgramBuild& DeviceContext::program(const std::string& entry_file, const std::vector<std::string>& defines) {
    using Clock = std::chrono::steady_clock;
    const auto start = Clock::now();

    // -cl-fast-relaxed-math is deliberately absent: it lets the compiler assume no NaN/Inf and
    // loosens precision, both of which the estimators and their tests rely on.
    std::string options = "-cl-std=CL1.2 -cl-mad-enable";
    for (const std::string& d : defines) options += " -D " + d;

    const std::string source = kernel_source(entry_file);

    std::string platform_version;
    try {
        if (entry_.platform()) platform_version = trimmed(entry_.platform.getInfo<CL_PLATFORM_VERSION>());
    } catch (const cl::Error& e) {
        throw cl_failure(e);
    }

    Fnv1a64 key;
    key.add(kCacheFormat);
    key.add(entry_.platform_name);
    key.add(platform_version);
    key.add(entry_.name);
    key.add(entry_.driver_version);
    key.add(entry_.version);
    key.add(source);
    key.add(options);
    const std::string hex = key.hex();

    // In-process memo: the same source and options on this device give the same program.
    auto memo = programs_.find(hex);
    if (memo != programs_.end()) return memo->second;

    ProgramBuild build;
    build.options = options;
    const std::vector<cl::Device> devices{entry_.device};

    try {
        const fs::path cache_dir = usable_cache_dir();
        const fs::path cache_file = cache_dir.empty() ? fs::path() : cache_dir / (hex + ".bin");

        // 1. The disk cache. Any failure (truncated file, driver update that the key missed,
        //    driver refusing binaries) falls through to a source build.
        std::vector<unsigned char> binary;
        if (!cache_file.empty() && read_binary_file(cache_file, &binary)) {
            try {
                cl::Program::Binaries binaries{binary};
                std::vector<cl_int> status;
                cl::Program program(context_, devices, binaries, &status);
                program.build(devices, options.c_str());
                build.program = program;
                build.from_cache = true;
                std::error_code ignored;  // most recently used: the last to be trimmed
                fs::last_write_time(cache_file, fs::file_time_type::clock::now(), ignored);
                build.build_log = trimmed(program.getBuildInfo<CL_PROGRAM_BUILD_LOG>(entry_.device));
            } catch (const cl::Error&) {
                std::error_code ignored;
                fs::remove(cache_file, ignored);
            }
        }

        // 2. The source.
        if (!build.from_cache) {
            cl::Program program(context_, source);
            try {
                program.build(devices, options.c_str());
            } catch (const cl::BuildError&) {
                throw build_failure(entry_file, entry_.name, program.getBuildInfo<CL_PROGRAM_BUILD_LOG>(entry_.device));
            }
            build.program = program;
            build.build_log = trimmed(program.getBuildInfo<CL_PROGRAM_BUILD_LOG>(entry_.device));

            if (!cache_file.empty()) {
                std::vector<std::vector<unsigned char>> binaries = program.getInfo<CL_PROGRAM_BINARIES>();
                if (binaries.size() == 1 && !binaries[0].empty()) {
                    write_cache_file(cache_file, binaries[0]);
                    trim_cache(cache_dir, cache_file);
                }
            }
        }
    } catch (const cl::Error& e) {
        throw cl_failure(e);
    }

    build.seconds = std::chrono::duration<double>(Clock::now() - start).count();
    return programs_.emplace(hex, std::move(build)).first->second;
}

std::string program_cache_dir() {
    std::string dir = env_or_empty("CLBDPT_CACHE_DIR");
    if (!dir.empty()) return dir;
    std::string xdg = env_or_empty("XDG_CACHE_HOME");
    if (!xdg.empty()) return (fs::path(xdg) / "clbdpt").string();
    std::string home = env_or_empty("HOME");
    if (!home.empty()) return (fs::path(home) / ".cache" / "clbdpt").string();
    return {};
}

const char* cl_error_name(int code) {
    switch (code) {
#define CLBDPT_CL_ERROR(name) \
    case name:                \
        return #name;
        CLBDPT_CL_ERROR(CL_SUCCESS)
        CLBDPT_CL_ERROR(CL_DEVICE_NOT_FOUND)
        CLBDPT_CL_ERROR(CL_DEVICE_NOT_AVAILABLE)
        CLBDPT_CL_ERROR(CL_COMPILER_NOT_AVAILABLE)
        CLBDPT_CL_ERROR(CL_MEM_OBJECT_ALLOCATION_FAILURE)
        CLBDPT_CL_ERROR(CL_OUT_OF_RESOURCES)
        CLBDPT_CL_ERROR(CL_OUT_OF_HOST_MEMORY)
        CLBDPT_CL_ERROR(CL_PROFILING_INFO_NOT_AVAILABLE)
        CLBDPT_CL_ERROR(CL_MEM_COPY_OVERLAP)
        CLBDPT_CL_ERROR(CL_IMAGE_FORMAT_MISMATCH)
        CLBDPT_CL_ERROR(CL_IMAGE_FORMAT_NOT_SUPPORTED)
        CLBDPT_CL_ERROR(CL_BUILD_PROGRAM_FAILURE)
        CLBDPT_CL_ERROR(CL_MAP_FAILURE)
        CLBDPT_CL_ERROR(CL_MISALIGNED_SUB_BUFFER_OFFSET)
        CLBDPT_CL_ERROR(CL_EXEC_STATUS_ERROR_FOR_EVENTS_IN_WAIT_LIST)
        CLBDPT_CL_ERROR(CL_COMPILE_PROGRAM_FAILURE)
        CLBDPT_CL_ERROR(CL_LINKER_NOT_AVAILABLE)
        CLBDPT_CL_ERROR(CL_LINK_PROGRAM_FAILURE)
        CLBDPT_CL_ERROR(CL_DEVICE_PARTITION_FAILED)
        CLBDPT_CL_ERROR(CL_KERNEL_ARG_INFO_NOT_AVAILABLE)
        CLBDPT_CL_ERROR(CL_INVALID_VALUE)
        CLBDPT_CL_ERROR(CL_INVALID_DEVICE_TYPE)
        CLBDPT_CL_ERROR(CL_INVALID_PLATFORM)
        CLBDPT_CL_ERROR(CL_INVALID_DEVICE)
        CLBDPT_CL_ERROR(CL_INVALID_CONTEXT)
        CLBDPT_CL_ERROR(CL_INVALID_QUEUE_PROPERTIES)
        CLBDPT_CL_ERROR(CL_INVALID_COMMAND_QUEUE)
        CLBDPT_CL_ERROR(CL_INVALID_HOST_PTR)
        CLBDPT_CL_ERROR(CL_INVALID_MEM_OBJECT)
        CLBDPT_CL_ERROR(CL_INVALID_IMAGE_FORMAT_DESCRIPTOR)
        CLBDPT_CL_ERROR(CL_INVALID_IMAGE_SIZE)
        CLBDPT_CL_ERROR(CL_INVALID_SAMPLER)
        CLBDPT_CL_ERROR(CL_INVALID_BINARY)
        CLBDPT_CL_ERROR(CL_INVALID_BUILD_OPTIONS)
        CLBDPT_CL_ERROR(CL_INVALID_PROGRAM)
        CLBDPT_CL_ERROR(CL_INVALID_PROGRAM_EXECUTABLE)
        CLBDPT_CL_ERROR(CL_INVALID_KERNEL_NAME)
        CLBDPT_CL_ERROR(CL_INVALID_KERNEL_DEFINITION)
        CLBDPT_CL_ERROR(CL_INVALID_KERNEL)
        CLBDPT_CL_ERROR(CL_INVALID_ARG_INDEX)
        CLBDPT_CL_ERROR(CL_INVALID_ARG_VALUE)
        CLBDPT_CL_ERROR(CL_INVALID_ARG_SIZE)
        CLBDPT_CL_ERROR(CL_INVALID_KERNEL_ARGS)
        CLBDPT_CL_ERROR(CL_INVALID_WORK_DIMENSION)
        CLBDPT_CL_ERROR(CL_INVALID_WORK_GROUP_SIZE)
        CLBDPT_CL_ERROR(CL_INVALID_WORK_ITEM_SIZE)
        CLBDPT_CL_ERROR(CL_INVALID_GLOBAL_OFFSET)
        CLBDPT_CL_ERROR(CL_INVALID_EVENT_WAIT_LIST)
        CLBDPT_CL_ERROR(CL_INVALID_EVENT)
        CLBDPT_CL_ERROR(CL_INVALID_OPERATION)
        CLBDPT_CL_ERROR(CL_INVALID_GL_OBJECT)
        CLBDPT_CL_ERROR(CL_INVALID_BUFFER_SIZE)
        CLBDPT_CL_ERROR(CL_INVALID_MIP_LEVEL)
        CLBDPT_CL_ERROR(CL_INVALID_GLOBAL_WORK_SIZE)
        CLBDPT_CL_ERROR(CL_INVALID_PROPERTY)
        CLBDPT_CL_ERROR(CL_INVALID_IMAGE_DESCRIPTOR)
        CLBDPT_CL_ERROR(CL_INVALID_COMPILER_OPTIONS)
        CLBDPT_CL_ERROR(CL_INVALID_LINKER_OPTIONS)
        CLBDPT_CL_ERROR(CL_INVALID_DEVICE_PARTITION_COUNT)
#undef CLBDPT_CL_ERROR
        case kPlatformNotFoundKhr:
            return "CL_PLATFORM_NOT_FOUND_KHR";
        default:
            break;
    }
    // Unknown codes: "CL error N", kept per code so the pointer stays valid.
    static thread_local std::map<int, std::string> unknown;
    auto it = unknown.find(code);
    if (it == unknown.end()) it = unknown.emplace(code, "CL error " + std::to_string(code)).first;
    return it->second.c_str();
}

}  // namespace clbdpt
