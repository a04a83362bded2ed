// A render's image I/O process: forked as the render starts, it loads the image module
// (OpenImageIO's 260 libraries: 0.3-0.4 s of one core, film/image_io_module.h) while the render
// parses its scene, starts OpenCL and loads its kernels on the other core, and then reads and
// writes the images the render asks for over a socket: a scene's textures and environment map,
// the render's output. In the render's own process that load would come before or after the
// render, on the clock; in a process of its own it runs on the core that the render's
// single-threaded start leaves idle. (No thread would do: glibc's dlopen lock would hold PoCL's
// loads behind it, and the render's threads would wait on the loader's page-table changes; both
// measured, docs/throughput.md.)
//
// read_image_rgb, read_texture_image and write_image (film/image_io.h) go through the process
// when there is one, and do the work themselves otherwise, or if it has died: the process saves
// time, it is never needed.
#pragma once

#include <cstdint>
#include <optional>
#include <string>

#include "film/image_io_module.h"

namespace clbdpt {

// Forks the image I/O process. Does nothing, and returns false, where the process has started
// threads (a fork copies only the calling thread, which could leave a lock held: under MPI,
// say; idle ones that libraries start as they load do not count), where this process has loaded
// the image module itself, or if the fork fails.
bool start_image_io_process();

// The largest image (its pixels' bytes) written through the process. It holds a copy of what it
// writes, so a film near the machine's memory would risk the render's end on the copy; an image
// this large takes long enough to render that loading OpenImageIO here costs nothing. (A read's
// copy there is gone before the render allocates its film.)
constexpr uint64_t kImageIoProcessMaxBytes = uint64_t(64) << 20;

// Writes through the process (as ImageIoModule::write_rgb): "" on success, else why; nullopt if
// there is no process, it has died or the image is larger than kImageIoProcessMaxBytes, for the
// caller to write the image itself.
std::optional<std::string> write_in_image_io_process(const std::string& path, const std::string& temp_path,
                                                     int width, int height, const float* float_rgb,
                                                     const uint8_t* srgb8, const ImageAttributes& metadata);

// Reads through the process (as ImageIoModule::read): "" on success, else why; nullopt if there
// is no process or it has died, for the caller to read the image itself.
std::optional<std::string> read_in_image_io_process(const std::string& path, bool own_format, StoredImage* image);

// While one lives, the process is stopped (SIGSTOP; SIGCONT at its end): the strategy pilot
// times its candidates' passes, and the process's loading of OpenImageIO (0.35 s of a core)
// would slow the first ones it meets and not the others. It loads during the render instead.
class ImageIoProcessPause {
public:
    ImageIoProcessPause();
    ~ImageIoProcessPause();
    ImageIoProcessPause(const ImageIoProcessPause&) = delete;
    ImageIoProcessPause& operator=(const ImageIoProcessPause&) = delete;

private:
    int pid_ = -1;
};

// The process's id, -1 if there is none (for tests).
int image_io_process_id();

// Ends the process and waits for it. Also run at exit.
void stop_image_io_process();

}  // namespace clbdpt
