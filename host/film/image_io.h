// Writing images through OpenImageIO. The format follows the extension: .exr is linear float
// RGB with metadata; .png/.jpg/.jpeg/.tif are tonemapped (clamp to [0,1], sRGB curve) 8-bit.
// Writes go to a temporary file in the same folder that is renamed at the end, so a failed
// write never leaves a half-written output behind.
#pragma once

#include <string>
#include <utility>
#include <vector>

namespace clbdpt {

struct ImageMetadata {
    std::vector<std::pair<std::string, std::string>> strings;  // e.g. {"clbdpt:integrator", "bdpt"}
};

// rgb: width * height * 3 floats, row 0 at the top. Throws Error (naming the file) on failure,
// and on a non-finite pixel (a NaN in an image is a bug upstream, never written out).
void write_image(const std::string& path, int width, int height, const std::vector<float>& rgb,
                 const ImageMetadata& metadata = {});

// Reads an image as linear float RGB (used for environment maps and tests). Throws Error.
std::vector<float> read_image_rgb(const std::string& path, int* width, int* height);

// True if the extension is one write_image can produce.
bool is_supported_output(const std::string& path);

}  // namespace clbdpt
