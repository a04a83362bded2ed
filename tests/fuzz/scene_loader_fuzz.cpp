// libFuzzer target for everything the host does with a user's scene before a kernel runs:
// the JSON, OBJ and MTL loaders (textures and .vdb files they name included) and the device
// scene built from the result (BVH, light distribution, camera). A clbdpt::Error is the
// expected answer to bad input; anything else that escapes, and every sanitizer report, is a
// finding. Run by scripts/fuzz.sh.
#include <unistd.h>

#include <cstdint>
#include <filesystem>
#include <string>

#include "fuzz_scene_files.h"
#include "render/device_scene.h"
#include "scene/scene.h"
#include "util/error.h"

namespace {

// Small films: the fuzzer is after the loaders, not after allocating large images.
constexpr int kFilmSize = 8;

// The directory the inputs' files are written to, removed when the fuzzer exits.
struct FuzzDir {
    std::string path = std::filesystem::temp_directory_path().string() + "/clbdpt_fuzz_" + std::to_string(::getpid());
    FuzzDir() { std::filesystem::create_directories(path); }
    ~FuzzDir() {
        std::error_code ec;
        std::filesystem::remove_all(path, ec);
    }
};

const std::string& fuzz_dir() {
    static const FuzzDir dir;
    return dir.path;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    const std::string path = clbdpt::write_fuzz_scene_files(data, size, fuzz_dir());
    try {
        clbdpt::Scene scene = clbdpt::load_scene(path);
        clbdpt::build_device_scene(scene, kFilmSize, kFilmSize);
    } catch (const clbdpt::Error&) {
        // Bad input, reported as it should be.
    }
    return 0;
}
