// The image module (film/image_io_module.h): OpenImageIO's reading and writing, built into
// libclbdpt_image_io.so and loaded by dlopen. Everything else about images (checks, the sRGB
// curve, channel layouts, temporary files) stays in film/image_io.cpp.
#include <filesystem>
#include <memory>
#include <string>

#include <OpenImageIO/imageio.h>
#include <OpenImageIO/strutil.h>

#include "film/image_io_module.h"

namespace clbdpt {
namespace {

std::string first_line(const std::string& message, const std::string& fallback) {
    std::string line = message.substr(0, message.find('\n'));
    while (!line.empty() && (line.back() == '\r' || line.back() == ' ')) line.pop_back();
    return line.empty() ? fallback : line;
}

std::string write_rgb(const std::string& path, const std::string& temp_path, int width, int height,
                      const float* float_rgb, const uint8_t* srgb8, const ImageAttributes& metadata) {
    // The plugin is chosen from the real name; the temporary name only has to be openable.
    std::unique_ptr<OIIO::ImageOutput> out = OIIO::ImageOutput::create(path);
    if (!out) return first_line(OIIO::geterror(), "no OpenImageIO plugin for it");

    const std::string ext = OIIO::Strutil::lower(std::filesystem::path(path).extension().string());
    const bool linear_float = float_rgb != nullptr;
    OIIO::ImageSpec spec(width, height, 3, linear_float ? OIIO::TypeDesc::FLOAT : OIIO::TypeDesc::UINT8);
    spec.attribute("oiio:ColorSpace", linear_float ? "Linear" : "sRGB");
    spec.attribute("Software", "clbdpt");
    if (linear_float) spec.attribute("compression", "zip");
    if (ext == ".jpg" || ext == ".jpeg") spec.attribute("CompressionQuality", 95);
    for (const auto& [key, value] : metadata) spec.attribute(key, value);

    if (!out->open(temp_path, spec)) return first_line(out->geterror(), "OpenImageIO error");
    const bool written = linear_float ? out->write_image(OIIO::TypeDesc::FLOAT, float_rgb)
                                      : out->write_image(OIIO::TypeDesc::UINT8, srgb8);
    if (!written) {
        const std::string why = out->geterror();
        out->close();
        return first_line(why, "OpenImageIO error");
    }
    if (!out->close()) return first_line(out->geterror(), "OpenImageIO error");
    return "";
}

std::string read(const std::string& path, bool own_format, StoredImage* image) {
    std::unique_ptr<OIIO::ImageInput> in = OIIO::ImageInput::open(path);
    if (!in) return first_line(OIIO::geterror(), "cannot open");
    const OIIO::ImageSpec& spec = in->spec();
    if (spec.width <= 0 || spec.height <= 0 || spec.nchannels <= 0 || spec.depth > 1) return "not a 2D image";
    image->width = spec.width;
    image->height = spec.height;
    image->channels = spec.nchannels;
    image->is_float = spec.format.is_floating_point();
    image->srgb_encoded = !image->is_float &&
                          OIIO::Strutil::iequals(spec.get_string_attribute("oiio:ColorSpace"), "sRGB");
    const size_t values = size_t(spec.width) * size_t(spec.height) * size_t(spec.nchannels);
    bool read_ok;
    if (own_format && !image->is_float) {
        image->u8.resize(values);
        read_ok = in->read_image(0, 0, 0, spec.nchannels, OIIO::TypeDesc::UINT8, image->u8.data());
    } else {
        image->f32.resize(values);
        read_ok = in->read_image(0, 0, 0, spec.nchannels, OIIO::TypeDesc::FLOAT, image->f32.data());
    }
    if (!read_ok) return first_line(in->geterror(), "read failed");
    in->close();
    return "";
}

const ImageIoModule kModule{kImageIoModuleAbi, write_rgb, read};

}  // namespace
}  // namespace clbdpt

extern "C" __attribute__((visibility("default"))) const clbdpt::ImageIoModule* clbdpt_image_io_module() {
    return &clbdpt::kModule;
}
