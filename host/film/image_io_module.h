// The boundary between clbdpt and its image module, libclbdpt_image_io.so, which holds every call
// into OpenImageIO.
//
// Why a module: Debian's libOpenImageIO pulls in some 260 shared libraries (OpenCV, FFmpeg,
// GDAL, DICOM, ...). Linked into the executable, the dynamic linker spends 0.3-0.4 s of one
// core on them before main() on every run, and each later dlopen (PoCL, LLVM, every kernel
// binary) searches their symbols too. Loaded by dlopen with RTLD_LOCAL, they cost nothing where
// no image is read or written, and a render loads them in its image I/O process
// (film/image_io_process.h), on the core the render's start leaves idle.
//
// The module is built by the same compiler from the same tree, so C++ types cross the boundary;
// errors cross as strings (an exception thrown in a dlopen'ed object and caught here would need
// their type information to match across objects).
#pragma once

#include <cstdint>
#include <string>
#include <utility>
#include <vector>

namespace clbdpt {

// An image file's pixels as stored, all channels interleaved, row 0 at the top.
struct StoredImage {
    int width = 0;
    int height = 0;
    int channels = 0;
    bool is_float = false;      // the file holds floating-point samples
    bool srgb_encoded = false;  // integer samples tagged sRGB (PNG and JPEG are, by default)
    std::vector<float> f32;     // read as float: every format (integers scaled to [0,1])
    std::vector<uint8_t> u8;    // read as 8-bit: integer files when asked for their own format
};

using ImageAttributes = std::vector<std::pair<std::string, std::string>>;

struct ImageIoModule {
    // Must equal kImageIoModuleAbi: a module from another build is refused, not called.
    uint32_t abi;
    // Writes `width` x `height` RGB to `temp_path`, in the format `path`'s extension names:
    // 32-bit float (`float_rgb`) for .exr, else 8-bit (`srgb8`, already encoded). Returns "" on
    // success, else one line saying why.
    std::string (*write_rgb)(const std::string& path, const std::string& temp_path, int width, int height,
                             const float* float_rgb, const uint8_t* srgb8, const ImageAttributes& metadata);
    // Reads a 2D image: as float, or (`own_format`) as 8-bit if the file holds integers. Returns
    // "" on success, else one line saying why.
    std::string (*read)(const std::string& path, bool own_format, StoredImage* image);
};

// Changed whenever ImageIoModule or StoredImage changes.
constexpr uint32_t kImageIoModuleAbi = 1;

// The module's one exported symbol.
extern "C" {
typedef const ImageIoModule* (*ImageIoModuleEntry)();
}
#define CLBDPT_IMAGE_IO_MODULE_ENTRY "clbdpt_image_io_module"

// The loaded module; loads it on first use. Throws Error naming the module's path and the
// loader's reason if it cannot be loaded.
const ImageIoModule& image_io_module();

// Whether this process has loaded the module (successfully or not).
bool image_io_module_loaded();

}  // namespace clbdpt
