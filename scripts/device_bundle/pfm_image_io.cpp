// Stand-in for libclbdpt_image_io.so on a machine without OpenImageIO (scripts/device_bundle.sh):
// PFM (3-channel float, little-endian) in and out, whatever the file name says.
#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

#include "film/image_io_module.h"

namespace clbdpt {
namespace {

std::string write_rgb(const std::string&, const std::string& temp_path, int width, int height,
                      const float* float_rgb, const uint8_t* srgb8, const ImageAttributes&) {
    FILE* file = std::fopen(temp_path.c_str(), "wb");
    if (!file) return "cannot open " + temp_path;
    std::fprintf(file, "PF\n%d %d\n-1.0\n", width, height);
    std::vector<float> row(size_t(width) * 3);
    for (int y = height - 1; y >= 0; --y) {  // PFM stores the bottom row first
        const size_t first = size_t(y) * row.size();
        for (size_t i = 0; i < row.size(); ++i)
            row[i] = float_rgb ? float_rgb[first + i] : float(srgb8[first + i]) / 255.0f;
        std::fwrite(row.data(), sizeof(float), row.size(), file);
    }
    return std::fclose(file) == 0 ? "" : "cannot write " + temp_path;
}

std::string read(const std::string& path, bool, StoredImage* image) {
    FILE* file = std::fopen(path.c_str(), "rb");
    if (!file) return "cannot open";
    char tag[3] = {};
    int width = 0, height = 0;
    float scale = 0;
    if (std::fscanf(file, "%2s %d %d %f", tag, &width, &height, &scale) != 4 || std::strcmp(tag, "PF") != 0 ||
        width <= 0 || height <= 0) {
        std::fclose(file);
        return "not a 3-channel PFM file";
    }
    std::fgetc(file);  // the one whitespace before the pixels
    image->width = width;
    image->height = height;
    image->channels = 3;
    image->is_float = true;
    image->f32.resize(size_t(width) * size_t(height) * 3);
    const size_t row = size_t(width) * 3;
    for (int y = height - 1; y >= 0; --y) {
        if (std::fread(&image->f32[size_t(y) * row], sizeof(float), row, file) != row) {
            std::fclose(file);
            return "truncated PFM file";
        }
    }
    std::fclose(file);
    return "";
}

const ImageIoModule kModule{kImageIoModuleAbi, write_rgb, read};

}  // namespace
}  // namespace clbdpt

extern "C" __attribute__((visibility("default"))) const clbdpt::ImageIoModule* clbdpt_image_io_module() {
    return &clbdpt::kModule;
}
