// A render's image writer: a process forked when the render has loaded its scene, which loads
// the image module (OpenImageIO's 260 libraries: 0.3-0.4 s of one core, film/image_io_module.h)
// while the render starts OpenCL, loads its kernels and begins its passes, and then writes the
// images the render hands it over a socket. In the render's own process that load would come
// before or after the render, on the clock; in a process of its own it runs on the core the
// render's single-threaded start leaves idle (no thread would do: glibc's dlopen lock would hold
// PoCL's loads behind it, and the render's threads would wait on the loader's page-table changes;
// both measured).
//
// write_image (film/image_io.h) goes through the writer when there is one and writes in its own
// process otherwise, or if the writer has died: the writer saves time, it is never needed.
#pragma once

#include <cstdint>
#include <optional>
#include <string>

#include "film/image_io_module.h"

namespace clbdpt {

// Forks the writer. Does nothing, and returns false, where the process has started threads (a
// fork copies only the calling thread, which could leave a lock held: under MPI, say; idle ones
// that libraries start as they load do not count), where this process has loaded the image
// module itself (a scene's textures), or if the fork fails.
bool start_image_writer_process();

// The largest image (its pixels' bytes) handed to the writer. The writer holds a copy of what
// it writes, so a film near the machine's memory would risk the render's end on the copy; an
// image this large takes long enough to render that loading OpenImageIO here costs nothing.
constexpr uint64_t kImageWriterMaxBytes = uint64_t(64) << 20;

// Writes through the writer (as ImageIoModule::write_rgb): "" on success, else why; nullopt if
// there is no writer, it has died or the image is larger than kImageWriterMaxBytes, for the
// caller to write the image itself.
std::optional<std::string> write_in_image_writer_process(const std::string& path, const std::string& temp_path,
                                                         int width, int height, const float* float_rgb,
                                                         const uint8_t* srgb8, const ImageAttributes& metadata);

// The writer's process id, -1 if there is none (for tests).
int image_writer_process_id();

// Ends the writer (it exits when its socket closes) and waits for it. Also run at exit.
void stop_image_writer_process();

}  // namespace clbdpt
