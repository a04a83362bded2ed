// One fuzz input is a small set of scene files: the bytes are split at lines "@@@" into the
// scene itself (scene.json when it starts with '{', else scene.obj), a.obj, a.mtl, a.png and
// a.vdb, written into a directory, so a JSON scene can name a mesh and a density grid, an OBJ
// its MTL library, an MTL a texture, and the fuzzer mutates all of them at once. Shared by the libFuzzer target and the regression test that
// replays the inputs it found (tests/data/fuzz/).
#pragma once

#include <cstddef>
#include <cstdint>
#include <fstream>
#include <string>

namespace clbdpt {

// Writes the files of `data` into `dir` (which exists) and returns the scene file's path.
inline std::string write_fuzz_scene_files(const uint8_t* data, size_t size, const std::string& dir) {
    static const char* const kNames[] = {"a.obj", "a.mtl", "a.png", "a.vdb"};
    constexpr int kParts = 1 + int(sizeof kNames / sizeof kNames[0]);
    const std::string text(reinterpret_cast<const char*>(data), size);
    const std::string separator = "\n@@@\n";
    size_t begin = 0;
    std::string scene_path;
    for (int part = 0; part < kParts; ++part) {
        size_t end = text.find(separator, begin);
        const bool last = part == kParts - 1 || end == std::string::npos;
        if (last) end = text.size();
        const std::string body = text.substr(begin, end - begin);
        std::string name = part > 0 ? kNames[part - 1] : (!body.empty() && body[0] == '{' ? "scene.json" : "scene.obj");
        std::ofstream(dir + "/" + name, std::ios::binary | std::ios::trunc) << body;
        if (part == 0) scene_path = dir + "/" + name;
        if (last) {
            // Files a previous input left behind must not leak into this one.
            for (int k = part; k < kParts - 1; ++k) std::remove((dir + "/" + kNames[k]).c_str());
            break;
        }
        begin = end + separator.size();
    }
    return scene_path;
}

}  // namespace clbdpt
