// Writing images through OpenImageIO. The format follows the extension: .exr is linear float
// RGB with metadata; .png/.jpg/.jpeg/.tif are tonemapped (clamp to [0,1], sRGB curve) 8-bit.
// Writes go to a temporary file in the same folder that is renamed at the end, so a failed
// write never leaves a half-written output behind.
#pragma once

#include <cstdint>
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

// An image read for use as a texture: RGBA, row 0 at the top. 8- and 16-bit files become 8-bit
// values as stored (sRGB-encoded if the file is; the kernels decode), float files stay float.
// Grey is replicated to rgb; a missing alpha is opaque.
struct TextureImage {
    int width = 0;
    int height = 0;
    bool is_float = false;
    bool has_alpha = false;         // the file has an alpha channel (2 or 4 channels)
    std::vector<uint8_t> rgba8;     // width * height * 4, when !is_float
    std::vector<float> rgba32f;     // width * height * 4, when is_float
};

// Throws Error naming the file if it cannot be read.
TextureImage read_texture_image(const std::string& path);

// True if the extension is one write_image can produce.
bool is_supported_output(const std::string& path);

}  // namespace clbdpt
