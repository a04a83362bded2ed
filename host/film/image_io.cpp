// Image files through OpenImageIO, in a module loaded where it is needed
// (film/image_io_module.h). Output is written to "<path>.tmp-<pid>" beside the target and
// renamed over it at the end (rename is atomic within a folder), so an interrupted or failed
// write never leaves a truncated image where the user expects a finished one.
#include "film/image_io.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <optional>

#include "film/image_io_module.h"
#include "film/image_io_process.h"
#include "util/atomic_file.h"
#include "util/error.h"

namespace clbdpt {
namespace {

std::string lower_extension(const std::string& path) {
    std::string ext = std::filesystem::path(path).extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
    return ext;
}

// sRGB opto-electronic transfer function (IEC 61966-2-1), linear [0,1] -> encoded [0,1].
float srgb_oetf(float linear) {
    return linear <= 0.0031308f ? 12.92f * linear : 1.055f * std::pow(linear, 1.0f / 2.4f) - 0.055f;
}

// Its inverse, encoded [0,1] -> linear [0,1].
float srgb_eotf(float encoded) {
    return encoded <= 0.04045f ? encoded / 12.92f : std::pow((encoded + 0.055f) / 1.055f, 2.4f);
}

std::vector<uint8_t> to_srgb8(const std::vector<float>& rgb) {
    std::vector<uint8_t> out(rgb.size());
    for (size_t i = 0; i < rgb.size(); ++i) {
        const float encoded = srgb_oetf(std::clamp(rgb[i], 0.0f, 1.0f));
        out[i] = static_cast<uint8_t>(std::lround(encoded * 255.0f));
    }
    return out;
}

}  // namespace

bool is_supported_output(const std::string& path) {
    const std::string ext = lower_extension(path);
    return ext == ".exr" || ext == ".png" || ext == ".jpg" || ext == ".jpeg" || ext == ".tif" || ext == ".tiff";
}

void write_image(const std::string& path, int width, int height, const std::vector<float>& rgb,
                 const ImageMetadata& metadata) {
    if (width <= 0 || height <= 0 ||
        rgb.size() != static_cast<size_t>(width) * static_cast<size_t>(height) * 3) {
        throw Error("cannot write '" + path + "': " + std::to_string(rgb.size()) + " values for a " +
                    std::to_string(width) + "x" + std::to_string(height) + " RGB image");
    }
    for (size_t i = 0; i < rgb.size(); ++i) {
        if (!std::isfinite(rgb[i])) {
            const size_t pixel = i / 3;
            throw Error("refusing to write " + path + ": pixel (" + std::to_string(pixel % static_cast<size_t>(width)) +
                        "," + std::to_string(pixel / static_cast<size_t>(width)) + ") is NaN/Inf");
        }
    }
    if (!is_supported_output(path)) {
        throw Error("cannot write '" + path + "': unsupported image format (use .exr, .png, .jpg, .jpeg, .tif or .tiff)");
    }

    TemporaryFile temp(path);
    const bool linear_float = lower_extension(path) == ".exr";
    const std::vector<uint8_t> encoded = linear_float ? std::vector<uint8_t>() : to_srgb8(rgb);
    const float* float_rgb = linear_float ? rgb.data() : nullptr;
    const uint8_t* srgb8 = linear_float ? nullptr : encoded.data();
    // A render's image I/O process has OpenImageIO loaded already; elsewhere (or should that
    // process be gone) the module is loaded here.
    std::optional<std::string> why =
        write_in_image_io_process(path, temp.path(), width, height, float_rgb, srgb8, metadata.strings);
    if (!why) why = image_io_module().write_rgb(path, temp.path(), width, height, float_rgb, srgb8, metadata.strings);
    if (!why->empty()) throw Error("cannot write '" + path + "': " + *why);
    temp.commit();
}

namespace {

// Reads all of an image file, through the render's image I/O process where there is one, else
// through the module here; throws Error naming the file.
StoredImage read_stored(const std::string& path, bool own_format) {
    StoredImage image;
    std::optional<std::string> why = read_in_image_io_process(path, own_format, &image);
    if (!why) why = image_io_module().read(path, own_format, &image);
    if (!why->empty()) throw Error("cannot read '" + path + "': " + *why);
    return image;
}

}  // namespace

std::vector<float> read_image_rgb(const std::string& path, int* width, int* height) {
    StoredImage image = read_stored(path, false);
    // 8- and 16-bit files tagged sRGB hold encoded values; undo the curve so callers always get
    // linear radiance.
    if (image.srgb_encoded) {
        for (float& v : image.f32) v = srgb_eotf(v);
    }

    // 1 or 2 channels (grey, grey + alpha) -> grey in all three; otherwise the first three.
    const size_t pixels = size_t(image.width) * size_t(image.height), channels = size_t(image.channels);
    std::vector<float> rgb(pixels * 3);
    for (size_t p = 0; p < pixels; ++p) {
        const float* src = &image.f32[p * channels];
        for (size_t c = 0; c < 3; ++c) rgb[p * 3 + c] = channels >= 3 ? src[c] : src[0];
    }
    *width = image.width;
    *height = image.height;
    return rgb;
}

namespace {

// Spreads an image's channels to RGBA by `source` (the file channel feeding r, g, b, a; -1:
// opaque). `opaque` is alpha's value of 1 in T.
template <typename T>
std::vector<T> spread_to_rgba(const std::vector<T>& all, size_t pixels, size_t channels, const int source[4],
                              T opaque) {
    std::vector<T> rgba(pixels * 4);
    for (size_t p = 0; p < pixels; ++p)
        for (int c = 0; c < 4; ++c)
            rgba[p * 4 + size_t(c)] = source[c] < 0 ? opaque : all[p * channels + size_t(source[c])];
    return rgba;
}

}  // namespace

TextureImage read_texture_image(const std::string& path) {
    const StoredImage stored = read_stored(path, true);
    const int channels = stored.channels;
    TextureImage image;
    image.width = stored.width;
    image.height = stored.height;
    image.is_float = stored.is_float;
    image.has_alpha = channels == 2 || channels >= 4;
    // Which file channel feeds r, g, b, a (-1: alpha, opaque).
    int source[4] = {0, 1, 2, 3};
    if (channels < 3) source[1] = source[2] = 0;
    if (!image.has_alpha) source[3] = -1;
    else if (channels == 2) source[3] = 1;
    const size_t pixels = size_t(stored.width) * size_t(stored.height);
    if (image.is_float) image.rgba32f = spread_to_rgba<float>(stored.f32, pixels, size_t(channels), source, 1.0f);
    else image.rgba8 = spread_to_rgba<uint8_t>(stored.u8, pixels, size_t(channels), source, uint8_t(255));
    return image;
}

}  // namespace clbdpt
