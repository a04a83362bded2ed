// Loading the image module (film/image_io_module.h): found beside the running executable, else
// in the build folder it was built in; loaded once.
#include "film/image_io_module.h"

#include <dlfcn.h>
#include <unistd.h>

#include <atomic>
#include <mutex>
#include <string>
#include <vector>

#include "util/error.h"

#ifndef CLBDPT_IMAGE_IO_MODULE_FILE
#error "CLBDPT_IMAGE_IO_MODULE_FILE (the module's file name) is set by CMakeLists.txt"
#endif
#ifndef CLBDPT_IMAGE_IO_MODULE_BUILD_DIR
#error "CLBDPT_IMAGE_IO_MODULE_BUILD_DIR (the folder it is built in) is set by CMakeLists.txt"
#endif

namespace clbdpt {
namespace {

std::string executable_dir() {
    std::string buf(4096, '\0');
    const ssize_t n = ::readlink("/proc/self/exe", buf.data(), buf.size());
    if (n <= 0 || size_t(n) >= buf.size()) return "";
    buf.resize(size_t(n));
    const size_t slash = buf.rfind('/');
    return slash == std::string::npos ? "" : buf.substr(0, slash);
}

// The module, or null with *error saying why.
const ImageIoModule* load_module(std::string* error) {
    std::vector<std::string> candidates;
    const std::string exe_dir = executable_dir();
    if (!exe_dir.empty()) candidates.push_back(exe_dir + "/" CLBDPT_IMAGE_IO_MODULE_FILE);
    candidates.push_back(CLBDPT_IMAGE_IO_MODULE_BUILD_DIR "/" CLBDPT_IMAGE_IO_MODULE_FILE);
    for (const std::string& path : candidates) {
        if (::access(path.c_str(), F_OK) != 0) continue;
        // RTLD_LOCAL: OpenImageIO's libraries stay out of the global scope that later dlopens
        // (PoCL's, the kernels') search.
        void* handle = ::dlopen(path.c_str(), RTLD_NOW | RTLD_LOCAL);
        if (!handle) {
            const char* why = ::dlerror();
            *error = "cannot load the image module '" + path + "': " + (why ? why : "dlopen failed");
            return nullptr;
        }
        auto entry = reinterpret_cast<ImageIoModuleEntry>(::dlsym(handle, CLBDPT_IMAGE_IO_MODULE_ENTRY));
        const ImageIoModule* module = entry ? entry() : nullptr;
        if (!module || module->abi != kImageIoModuleAbi) {
            *error = "the image module '" + path + "' is from another build of clbdpt";
            return nullptr;
        }
        return module;
    }
    std::string tried;
    for (const std::string& path : candidates) tried += (tried.empty() ? "" : ", ") + path;
    *error = "cannot find the image module " CLBDPT_IMAGE_IO_MODULE_FILE " (looked for " + tried + ")";
    return nullptr;
}

}  // namespace

namespace {
std::once_flag load_once;
std::atomic<bool> loaded{false};
}  // namespace

const ImageIoModule& image_io_module() {
    static const ImageIoModule* module = nullptr;
    static std::string error;
    std::call_once(load_once, [] {
        module = load_module(&error);
        loaded = true;
    });
    if (!module) throw Error(error);
    return *module;
}

bool image_io_module_loaded() { return loaded; }

}  // namespace clbdpt
