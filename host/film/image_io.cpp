// Image files through OpenImageIO. Output is written to "<path>.tmp-<pid>" beside the target and
// renamed over it at the end (rename is atomic within a folder), so an interrupted or failed
// write never leaves a truncated image where the user expects a finished one.
#include "film/image_io.h"


#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <memory>

#include <OpenImageIO/imageio.h>
#include <OpenImageIO/strutil.h>

#include "util/atomic_file.h"
#include "util/error.h"

namespace clbdpt {
namespace {

std::string lower_extension(const std::string& path) {
    std::string ext = std::filesystem::path(path).extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
    return ext;
}

std::string first_line(const std::string& message, const std::string& fallback) {
    std::string line = message.substr(0, message.find('\n'));
    while (!line.empty() && (line.back() == '\r' || line.back() == ' ')) line.pop_back();
    return line.empty() ? fallback : line;
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

    // The plugin is chosen from the real name; the temporary name only has to be openable.
    std::unique_ptr<OIIO::ImageOutput> out = OIIO::ImageOutput::create(path);
    if (!out) {
        throw Error("cannot write '" + path + "': " + first_line(OIIO::geterror(), "no OpenImageIO plugin for it"));
    }

    const bool linear_float = lower_extension(path) == ".exr";
    OIIO::ImageSpec spec(width, height, 3, linear_float ? OIIO::TypeDesc::FLOAT : OIIO::TypeDesc::UINT8);
    spec.attribute("oiio:ColorSpace", linear_float ? "Linear" : "sRGB");
    spec.attribute("Software", "clbdpt");
    if (linear_float) spec.attribute("compression", "zip");
    const std::string ext = lower_extension(path);
    if (ext == ".jpg" || ext == ".jpeg") spec.attribute("CompressionQuality", 95);
    for (const auto& [key, value] : metadata.strings) spec.attribute(key, value);

    TemporaryFile temp(path);
    auto fail = [&](const std::string& why) {
        throw Error("cannot write '" + path + "': " + first_line(why, "OpenImageIO error"));
    };
    if (!out->open(temp.path(), spec)) fail(out->geterror());
    bool written;
    if (linear_float) {
        written = out->write_image(OIIO::TypeDesc::FLOAT, rgb.data());
    } else {
        const std::vector<uint8_t> encoded = to_srgb8(rgb);
        written = out->write_image(OIIO::TypeDesc::UINT8, encoded.data());
    }
    if (!written) {
        const std::string why = out->geterror();
        out->close();
        fail(why);
    }
    if (!out->close()) fail(out->geterror());
    out.reset();
    temp.commit();
}

namespace {

// Opens an image file that must hold a 2D image; throws Error naming the file otherwise.
std::unique_ptr<OIIO::ImageInput> open_2d_image(const std::string& path) {
    std::unique_ptr<OIIO::ImageInput> in = OIIO::ImageInput::open(path);
    if (!in) throw Error("cannot read '" + path + "': " + first_line(OIIO::geterror(), "cannot open"));
    const OIIO::ImageSpec& spec = in->spec();
    if (spec.width <= 0 || spec.height <= 0 || spec.nchannels <= 0 || spec.depth > 1) {
        throw Error("cannot read '" + path + "': not a 2D image");
    }
    return in;
}

}  // namespace

std::vector<float> read_image_rgb(const std::string& path, int* width, int* height) {
    std::unique_ptr<OIIO::ImageInput> in = open_2d_image(path);
    const OIIO::ImageSpec& spec = in->spec();
    const int channels = spec.nchannels;
    const size_t pixels = static_cast<size_t>(spec.width) * static_cast<size_t>(spec.height);
    std::vector<float> all(pixels * static_cast<size_t>(channels));
    if (!in->read_image(0, 0, 0, channels, OIIO::TypeDesc::FLOAT, all.data())) {
        throw Error("cannot read '" + path + "': " + first_line(in->geterror(), "read failed"));
    }
    // 8- and 16-bit files tagged sRGB (PNG and JPEG are, by default) hold encoded values;
    // undo the curve so callers always get linear radiance.
    const bool srgb_encoded = !spec.format.is_floating_point() &&
                              OIIO::Strutil::iequals(spec.get_string_attribute("oiio:ColorSpace"), "sRGB");
    in->close();
    if (srgb_encoded) {
        for (float& v : all) v = srgb_eotf(v);
    }

    // 1 or 2 channels (grey, grey + alpha) -> grey in all three; otherwise the first three.
    std::vector<float> rgb(pixels * 3);
    for (size_t p = 0; p < pixels; ++p) {
        const float* src = &all[p * static_cast<size_t>(channels)];
        for (int c = 0; c < 3; ++c) rgb[p * 3 + static_cast<size_t>(c)] = channels >= 3 ? src[c] : src[0];
    }
    *width = spec.width;
    *height = spec.height;
    return rgb;
}

namespace {

// Reads all of `in` as `type` and spreads its channels to RGBA by `source` (the file channel
// feeding r, g, b, a; -1: opaque). `opaque` is alpha's value of 1 in T.
template <typename T>
std::vector<T> read_rgba(OIIO::ImageInput& in, const std::string& path, OIIO::TypeDesc type, const int source[4],
                         T opaque) {
    const OIIO::ImageSpec& spec = in.spec();
    const size_t pixels = size_t(spec.width) * size_t(spec.height), channels = size_t(spec.nchannels);
    std::vector<T> all(pixels * channels);
    if (!in.read_image(0, 0, 0, spec.nchannels, type, all.data()))
        throw Error("cannot read '" + path + "': " + first_line(in.geterror(), "read failed"));
    std::vector<T> rgba(pixels * 4);
    for (size_t p = 0; p < pixels; ++p)
        for (int c = 0; c < 4; ++c) rgba[p * 4 + size_t(c)] = source[c] < 0 ? opaque : all[p * channels + size_t(source[c])];
    return rgba;
}

}  // namespace

TextureImage read_texture_image(const std::string& path) {
    std::unique_ptr<OIIO::ImageInput> in = open_2d_image(path);
    const OIIO::ImageSpec& spec = in->spec();
    const int channels = spec.nchannels;
    TextureImage image;
    image.width = spec.width;
    image.height = spec.height;
    image.is_float = spec.format.is_floating_point();
    image.has_alpha = channels == 2 || channels >= 4;
    // Which file channel feeds r, g, b, a (-1: alpha, opaque).
    int source[4] = {0, 1, 2, 3};
    if (channels < 3) source[1] = source[2] = 0;
    if (!image.has_alpha) source[3] = -1;
    else if (channels == 2) source[3] = 1;
    if (image.is_float) image.rgba32f = read_rgba<float>(*in, path, OIIO::TypeDesc::FLOAT, source, 1.0f);
    else image.rgba8 = read_rgba<uint8_t>(*in, path, OIIO::TypeDesc::UINT8, source, uint8_t(255));
    in->close();
    return image;
}

}  // namespace clbdpt
