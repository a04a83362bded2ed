// Replays the inputs kept from fuzzing the scene loaders (scripts/fuzz.sh) through the same
// path as the fuzz target: every input either loads or is refused with a clbdpt::Error naming
// a file; nothing else escapes, and under scripts/sanitize.sh no sanitizer report either.
// tests/data/fuzz/ holds every input that once crashed, and a sample of the fuzzer's corpus.
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <vector>

#include "fuzz/fuzz_scene_files.h"
#include "render/device_scene.h"
#include "scene/scene.h"
#include "util/error.h"

namespace {

namespace fs = std::filesystem;

TEST(FuzzRegression, EveryKeptInputLoadsOrIsRefusedCleanly) {
    const fs::path inputs = fs::path(CLBDPT_TEST_DATA_DIR) / "fuzz";
    std::vector<fs::path> files;
    for (const auto& entry : fs::directory_iterator(inputs))
        if (entry.is_regular_file()) files.push_back(entry.path());
    std::sort(files.begin(), files.end());
    ASSERT_GE(files.size(), 10u) << "the kept inputs are missing from " << inputs;

    const fs::path dir = fs::temp_directory_path() / ("clbdpt_fuzz_regression_" + std::to_string(::getpid()));
    fs::create_directories(dir);
    int loaded = 0, refused = 0;
    for (const fs::path& file : files) {
        std::ifstream in(file, std::ios::binary);
        const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
        const std::string scene_path = clbdpt::write_fuzz_scene_files(
            reinterpret_cast<const uint8_t*>(bytes.data()), bytes.size(), dir.string());
        try {
            clbdpt::Scene scene = clbdpt::load_scene(scene_path);
            clbdpt::build_device_scene(scene, 8, 8);
            ++loaded;
        } catch (const clbdpt::Error& e) {
            // The message names the file it is about (one of the input's files).
            EXPECT_NE(std::string(e.what()).find(dir.string()), std::string::npos) << file << ": " << e.what();
            ++refused;
        }
    }
    fs::remove_all(dir);
    // Both outcomes occur: the sample is not all garbage, nor all valid.
    EXPECT_GT(loaded, 0);
    EXPECT_GT(refused, 0);
}

}  // namespace
