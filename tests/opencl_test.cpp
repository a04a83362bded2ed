// The OpenCL layer on whatever device is present (PoCL in CI): device listing and selection,
// kernel source expansion, build errors, and the on-disk program cache.
#include "device/opencl.h"

#include "device/embedded_kernels.h"
#include "device/pinned_host_array.h"
#include "util/error.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cctype>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include <unistd.h>

namespace clbdpt {
namespace {

namespace fs = std::filesystem;

// Sets an environment variable for one scope and restores the previous value after, so the
// tests can run in one process in any order.
class ScopedEnv {
public:
    ScopedEnv(const char* name, const std::string& value) : name_(name) {
        if (const char* old = std::getenv(name)) old_ = old;
        ::setenv(name, value.c_str(), 1);
    }
    ~ScopedEnv() {
        if (old_) {
            ::setenv(name_, old_->c_str(), 1);
        } else {
            ::unsetenv(name_);
        }
    }
    ScopedEnv(const ScopedEnv&) = delete;
    ScopedEnv& operator=(const ScopedEnv&) = delete;

private:
    const char* name_;
    std::optional<std::string> old_;
};

// A fresh directory under the system temp dir, removed with everything in it at scope exit.
class TempDir {
public:
    TempDir() {
        std::string pattern = (fs::temp_directory_path() / "clbdpt-test-XXXXXX").string();
        if (!::mkdtemp(pattern.data())) throw std::runtime_error("mkdtemp failed");
        path_ = pattern;
    }
    ~TempDir() {
        std::error_code ignored;
        fs::remove_all(path_, ignored);
    }
    TempDir(const TempDir&) = delete;
    TempDir& operator=(const TempDir&) = delete;

    const fs::path& path() const { return path_; }

    void write(const std::string& relative, const std::string& text) const {
        fs::path file = path_ / relative;
        fs::create_directories(file.parent_path());
        std::ofstream(file) << text;
    }

private:
    fs::path path_;
};

int count_occurrences(const std::string& haystack, const std::string& needle) {
    int count = 0;
    for (size_t at = haystack.find(needle); at != std::string::npos; at = haystack.find(needle, at + 1)) ++count;
    return count;
}

std::string embedded_text(const std::string& path) {
    size_t count = 0;
    const EmbeddedFile* files = embedded_kernel_files(&count);
    for (size_t i = 0; i < count; ++i) {
        if (path == files[i].path) return files[i].text;
    }
    return {};
}

std::string error_message(const std::function<void()>& f) {
    try {
        f();
    } catch (const Error& e) {
        return e.what();
    }
    ADD_FAILURE() << "expected clbdpt::Error";
    return {};
}

const char* kTinyKernel =
    "__kernel void add_one(__global int* data) {\n"
    "    size_t i = get_global_id(0);\n"
    "    data[i] += VALUE;\n"
    "}\n";

// ---- Devices -------------------------------------------------------------------------------------

TEST(Opencl, ListDevicesFindsAtLeastOne) {
    std::vector<DeviceEntry> devices = list_devices();
    ASSERT_FALSE(devices.empty());
    for (size_t i = 0; i < devices.size(); ++i) {
        const DeviceEntry& d = devices[i];
        EXPECT_EQ(d.index, static_cast<int>(i));
        EXPECT_FALSE(d.name.empty());
        EXPECT_FALSE(d.platform_name.empty());
        EXPECT_FALSE(d.type.empty());
        EXPECT_NE(d.version.find("OpenCL"), std::string::npos) << d.version;
        EXPECT_NE(d.opencl_c_version.find("OpenCL C"), std::string::npos) << d.opencl_c_version;
        EXPECT_GT(d.compute_units, 0u);
        EXPECT_GT(d.global_memory, 0u);
        EXPECT_GT(d.max_alloc, 0u);
    }
}

TEST(Opencl, SelectDefaultDevice) {
    DeviceEntry d = select_device("");
    EXPECT_FALSE(d.name.empty());
    EXPECT_TRUE(d.device() != nullptr);
}

TEST(Opencl, SelectByIndexAndName) {
    std::vector<DeviceEntry> devices = list_devices();
    ASSERT_FALSE(devices.empty());
    EXPECT_EQ(select_device("0").name, devices[0].name);
    // A case-changed substring of the name selects the same device.
    std::string part = devices[0].name.substr(0, std::min<size_t>(6, devices[0].name.size()));
    for (char& c : part) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
    EXPECT_EQ(select_device(part).index, 0);
}

TEST(Opencl, UnknownDeviceNameThrows) {
    std::string message = error_message([] { select_device("no-such-device-xyz"); });
    EXPECT_NE(message.find("no-such-device-xyz"), std::string::npos) << message;
    EXPECT_NE(message.find("clbdpt devices"), std::string::npos) << message;
}

TEST(Opencl, OutOfRangeIndexThrows) {
    std::string message = error_message([] { select_device("999"); });
    EXPECT_NE(message.find("'999'"), std::string::npos) << message;
    std::string huge = error_message([] { select_device("99999999999999999999999"); });
    EXPECT_NE(huge.find("unknown device"), std::string::npos) << huge;
}

// ---- Kernel sources --------------------------------------------------------------------------------

TEST(Opencl, KernelSourceExpandsIncludesOnce) {
    std::string source = kernel_source("kernels/layout_test.cl");
    EXPECT_NE(source.find("#line"), std::string::npos);
    EXPECT_EQ(count_occurrences(source, "#line 1 \"cl/shared/types.h\""), 1);
    EXPECT_EQ(count_occurrences(source, "#line 1 \"cl/shared/compat.h\""), 1);
    EXPECT_EQ(source.find("#include \"shared/"), std::string::npos) << "include left unexpanded";

    // types.h's text (after its own includes, which are replaced by their files) appears once.
    std::string types = embedded_text("shared/types.h");
    ASSERT_FALSE(types.empty());
    std::string tail = types.substr(types.find("#include \"shared/compat.h\"") + 26);
    EXPECT_EQ(count_occurrences(source, tail), 1);
}

TEST(Opencl, KernelSourceFromDiskWithLineDirectives) {
    TempDir dir;
    dir.write("a.h", "#ifndef A_H\n#define A_H\nint a_value;\n#endif\n");
    dir.write("b.h", "#include \"a.h\"\nint b_value;\n");
    dir.write("kernels/k.cl",
              "#include \"a.h\"\n#include <ignored_system.h>\n#include \"b.h\"\n#include \"a.h\"\nint k_value;\n");
    ScopedEnv env("CLBDPT_KERNEL_DIR", dir.path().string());

    std::string source = kernel_source("kernels/k.cl");
    const std::string k = "\"" + (dir.path() / "kernels/k.cl").string() + "\"";
    const std::string a = "\"" + (dir.path() / "a.h").string() + "\"";
    const std::string b = "\"" + (dir.path() / "b.h").string() + "\"";
    const std::string expected = "#line 1 " + k + "\n" +              //
                                 "#line 1 " + a + "\n" +              //
                                 "#ifndef A_H\n#define A_H\nint a_value;\n#endif\n" +
                                 "#line 2 " + k + "\n" +              //
                                 "#include <ignored_system.h>\n" +    // left to the compiler
                                 "#line 1 " + b + "\n" +              //
                                 "\n" +                               // a.h: already included
                                 "int b_value;\n" +                   //
                                 "#line 4 " + k + "\n" +              //
                                 "\n" +                               // a.h again
                                 "int k_value;\n";
    EXPECT_EQ(source, expected);
}

TEST(Opencl, MissingIncludeNamesFileAndLine) {
    TempDir dir;
    dir.write("kernels/k.cl", "int x;\n#include \"nope.h\"\n");
    ScopedEnv env("CLBDPT_KERNEL_DIR", dir.path().string());
    std::string message = error_message([] { kernel_source("kernels/k.cl"); });
    EXPECT_NE(message.find("nope.h"), std::string::npos) << message;
    EXPECT_NE(message.find("kernels/k.cl:2"), std::string::npos) << message;
}

TEST(Opencl, MissingEntryFileThrows) {
    std::string message = error_message([] { kernel_source("kernels/does_not_exist.cl"); });
    EXPECT_NE(message.find("kernels/does_not_exist.cl"), std::string::npos) << message;
}

TEST(Opencl, ErrorNames) {
    EXPECT_STREQ(cl_error_name(CL_OUT_OF_RESOURCES), "CL_OUT_OF_RESOURCES");
    EXPECT_STREQ(cl_error_name(CL_BUILD_PROGRAM_FAILURE), "CL_BUILD_PROGRAM_FAILURE");
    EXPECT_STREQ(cl_error_name(-1001), "CL_PLATFORM_NOT_FOUND_KHR");
    EXPECT_STREQ(cl_error_name(-12345), "CL error -12345");
}

// ---- Programs ----------------------------------------------------------------------------------------

TEST(Opencl, BuildFailureCarriesLog) {
    TempDir kernels;
    TempDir cache;
    kernels.write("kernels/bad.cl", "__kernel void broken(__global int* p) {\n    p[0] = undeclared_thing_xyz;\n}\n");
    ScopedEnv kernel_dir("CLBDPT_KERNEL_DIR", kernels.path().string());
    ScopedEnv cache_dir("CLBDPT_CACHE_DIR", cache.path().string());

    DeviceContext device(select_device(""));
    std::string message = error_message([&] { device.program("kernels/bad.cl", {}); });
    EXPECT_EQ(message.rfind("kernel build failed for kernels/bad.cl on " + device.entry().name + ": ", 0), 0u)
        << message;
    // One line: the compiler's first error, and where the whole log went.
    EXPECT_EQ(message.find('\n'), std::string::npos) << message;
    EXPECT_NE(message.find("undeclared_thing_xyz"), std::string::npos) << message;
    // The #line directives make the log name the real file.
    EXPECT_NE(message.find("bad.cl:2"), std::string::npos) << message;
    const size_t log_at = message.find("(whole log: ");
    ASSERT_NE(log_at, std::string::npos) << message;
    const std::string log_path = message.substr(log_at + 12, message.size() - log_at - 13);
    std::ifstream log(log_path);
    std::string log_text((std::istreambuf_iterator<char>(log)), std::istreambuf_iterator<char>());
    EXPECT_NE(log_text.find("undeclared_thing_xyz"), std::string::npos) << log_path;
    std::remove(log_path.c_str());
}

TEST(Opencl, ProgramIsCachedOnDiskAndInProcess) {
    TempDir kernels;
    TempDir cache;
    kernels.write("kernels/tiny.cl", kTinyKernel);
    ScopedEnv kernel_dir("CLBDPT_KERNEL_DIR", kernels.path().string());
    ScopedEnv cache_dir("CLBDPT_CACHE_DIR", (cache.path() / "nested" / "dir").string());
    const DeviceEntry entry = select_device("");

    DeviceContext first(entry);
    const ProgramBuild& built = first.program("kernels/tiny.cl", {"VALUE=3"});
    EXPECT_FALSE(built.from_cache);
    EXPECT_GT(built.seconds, 0.0);
    EXPECT_NE(built.options.find("-D VALUE=3"), std::string::npos) << built.options;
    EXPECT_NE(built.options.find("-cl-std=CL1.2"), std::string::npos) << built.options;
    EXPECT_EQ(built.options.find("fast-relaxed-math"), std::string::npos) << built.options;
    EXPECT_EQ(&first.program("kernels/tiny.cl", {"VALUE=3"}), &built) << "in-process memo";

    int cache_files = 0;
    for (const auto& f : fs::directory_iterator(cache.path() / "nested" / "dir")) {
        EXPECT_EQ(f.path().extension(), ".bin") << f.path();
        ++cache_files;
    }
    EXPECT_EQ(cache_files, 1);

    DeviceContext second(entry);
    const ProgramBuild& loaded = second.program("kernels/tiny.cl", {"VALUE=3"});
    EXPECT_TRUE(loaded.from_cache);

    // Different defines are a different program.
    EXPECT_FALSE(second.program("kernels/tiny.cl", {"VALUE=4"}).from_cache);

    // The program loaded from the binary runs and sees its -D value.
    cl::Kernel kernel(loaded.program, "add_one");
    std::vector<cl_int> data{1, 2, 3, 4};
    cl::Buffer buffer(second.context(), CL_MEM_READ_WRITE | CL_MEM_COPY_HOST_PTR, data.size() * sizeof(cl_int),
                      data.data());
    kernel.setArg(0, buffer);
    second.queue().enqueueNDRangeKernel(kernel, cl::NullRange, cl::NDRange(data.size()));
    second.queue().enqueueReadBuffer(buffer, CL_TRUE, 0, data.size() * sizeof(cl_int), data.data());
    EXPECT_EQ(data, (std::vector<cl_int>{4, 5, 6, 7}));
}

// The cache stays within CLBDPT_CACHE_MAX_MB: writing a kernel removes the least recently used
// binaries until the rest fit (never the new one), and a cache hit counts as a use.
TEST(Opencl, CacheKeepsItsSizeLimitDroppingTheLeastRecentlyUsed) {
    TempDir kernels;
    TempDir cache;
    kernels.write("kernels/tiny.cl", kTinyKernel);
    ScopedEnv kernel_dir("CLBDPT_KERNEL_DIR", kernels.path().string());
    ScopedEnv cache_dir("CLBDPT_CACHE_DIR", cache.path().string());
    ScopedEnv cache_max("CLBDPT_CACHE_MAX_MB", "1");
    const DeviceEntry entry = select_device("");

    DeviceContext first(entry);
    ASSERT_FALSE(first.program("kernels/tiny.cl", {"VALUE=1"}).from_cache);
    fs::path tiny;
    for (const auto& f : fs::directory_iterator(cache.path())) tiny = f.path();
    ASSERT_FALSE(tiny.empty());
    // Three older binaries of 400 KB: the oldest first; the tiny kernel's older still.
    const auto now = fs::file_time_type::clock::now();
    const char* names[] = {"oldest.bin", "older.bin", "old.bin"};
    for (int k = 0; k < 3; ++k) {
        cache.write(names[k], std::string(400 << 10, 'x'));
        fs::last_write_time(cache.path() / names[k], now - std::chrono::hours(3 - k));
    }
    fs::last_write_time(tiny, now - std::chrono::hours(10));
    // A hit makes the tiny kernel the most recently used.
    DeviceContext second(entry);
    ASSERT_TRUE(second.program("kernels/tiny.cl", {"VALUE=1"}).from_cache);
    EXPECT_GT(fs::last_write_time(tiny), now - std::chrono::minutes(1));

    // Writing another kernel brings the cache over 1 MiB: the oldest file goes, nothing else.
    ASSERT_FALSE(second.program("kernels/tiny.cl", {"VALUE=2"}).from_cache);
    EXPECT_FALSE(fs::exists(cache.path() / "oldest.bin"));
    EXPECT_TRUE(fs::exists(cache.path() / "older.bin"));
    EXPECT_TRUE(fs::exists(cache.path() / "old.bin"));
    EXPECT_TRUE(fs::exists(tiny));
    uint64_t total = 0;
    int binaries = 0;
    for (const auto& f : fs::directory_iterator(cache.path())) {
        total += fs::file_size(f.path());
        ++binaries;
    }
    EXPECT_EQ(binaries, 4);  // older, old, and the two tiny kernels
    EXPECT_LE(total, uint64_t(1) << 20);
}

TEST(Opencl, CorruptCacheFileFallsBackToSource) {
    TempDir kernels;
    TempDir cache;
    kernels.write("kernels/tiny.cl", kTinyKernel);
    ScopedEnv kernel_dir("CLBDPT_KERNEL_DIR", kernels.path().string());
    ScopedEnv cache_dir("CLBDPT_CACHE_DIR", cache.path().string());
    const DeviceEntry entry = select_device("");

    DeviceContext first(entry);
    ASSERT_FALSE(first.program("kernels/tiny.cl", {"VALUE=1"}).from_cache);
    for (const auto& f : fs::directory_iterator(cache.path())) std::ofstream(f.path(), std::ios::trunc) << "garbage";

    DeviceContext second(entry);
    const ProgramBuild& rebuilt = second.program("kernels/tiny.cl", {"VALUE=1"});
    EXPECT_FALSE(rebuilt.from_cache);
    cl::Kernel kernel(rebuilt.program, "add_one");  // usable
}

TEST(Opencl, UnwritableCacheDirDoesNotFail) {
    TempDir kernels;
    TempDir cache;
    kernels.write("kernels/tiny.cl", kTinyKernel);
    cache.write("file", "a file where the cache directory should be");
    ScopedEnv kernel_dir("CLBDPT_KERNEL_DIR", kernels.path().string());
    ScopedEnv cache_dir("CLBDPT_CACHE_DIR", (cache.path() / "file" / "sub").string());

    DeviceContext device(select_device(""));
    const ProgramBuild& built = device.program("kernels/tiny.cl", {"VALUE=2"});
    EXPECT_FALSE(built.from_cache);
    cl::Kernel kernel(built.program, "add_one");
}

TEST(Opencl, ProgramCacheDirFollowsEnvironment) {
    {
        ScopedEnv cache("CLBDPT_CACHE_DIR", "/some/where");
        EXPECT_EQ(program_cache_dir(), "/some/where");
    }
    ScopedEnv cache("CLBDPT_CACHE_DIR", "");
    {
        ScopedEnv xdg("XDG_CACHE_HOME", "/xdg");
        EXPECT_EQ(program_cache_dir(), "/xdg/clbdpt");
    }
    ScopedEnv xdg("XDG_CACHE_HOME", "");
    ScopedEnv home("HOME", "/home/someone");
    EXPECT_EQ(program_cache_dir(), "/home/someone/.cache/clbdpt");
}

// ---- Pinned host memory --------------------------------------------------------------------------

TEST(Opencl, PinnedHostArrayTakesReadBacksAndMoves) {
    DeviceContext device(select_device(""));
    std::vector<cl_int> values(1000);
    for (size_t i = 0; i < values.size(); ++i) values[i] = cl_int(i * 7 + 1);
    cl::Buffer buffer(device.context(), CL_MEM_READ_WRITE | CL_MEM_COPY_HOST_PTR, sizeof(cl_int) * values.size(),
                      values.data());
    PinnedHostArray<cl_int> host(device.context(), device.queue(), values.size());
    ASSERT_NE(host.data(), nullptr);
    EXPECT_EQ(host.size(), values.size());
    device.queue().enqueueReadBuffer(buffer, CL_TRUE, 0, sizeof(cl_int) * values.size(), host.data());
    for (size_t i = 0; i < values.size(); ++i) ASSERT_EQ(host[i], values[i]) << i;
    // Moved, the memory stays mapped and holds the same values; the source is left empty.
    cl_int* mapped = host.data();
    PinnedHostArray<cl_int> moved(std::move(host));
    EXPECT_EQ(moved.data(), mapped);
    EXPECT_EQ(host.data(), nullptr);
    EXPECT_EQ(moved[999], values[999]);
    PinnedHostArray<cl_int> empty(device.context(), device.queue(), 0);
    EXPECT_EQ(empty.data(), nullptr);
    empty = std::move(moved);  // the empty one takes it over; nothing is unmapped twice
    EXPECT_EQ(empty[0], values[0]);
}

}  // namespace
}  // namespace clbdpt
