// The kernel sources under cl/, embedded into the binary at build time by
// cmake/EmbedKernels.cmake. Paths are relative to cl/ ("bvh.h", "kernels/render.cl").
#pragma once

#include <cstddef>

namespace clbdpt {

struct EmbeddedFile {
    const char* path;
    const char* text;
};

const EmbeddedFile* embedded_kernel_files(std::size_t* count);

}  // namespace clbdpt
