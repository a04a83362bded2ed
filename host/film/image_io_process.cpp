// The image I/O process (film/image_io_process.h). Requests over a Unix stream socket, each
// answered before the next: a write (path, temporary path, width, height, metadata pairs, the
// pixels: float RGB for .exr, sRGB-encoded bytes otherwise) is answered by the write's error,
// "" on success; a read (path, whether in the file's own format) by the read's error and, on
// success, the image's size, channels, format and pixels.
#include "film/image_io_process.h"

#include <fcntl.h>
#include <signal.h>
#include <sys/prctl.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <mutex>
#include <vector>

namespace clbdpt {
namespace {

bool send_all(int fd, const void* data, size_t size) {
    const char* p = static_cast<const char*>(data);
    while (size > 0) {
        // MSG_NOSIGNAL: a process that died is an error return here, not a SIGPIPE.
        const ssize_t n = ::send(fd, p, size, MSG_NOSIGNAL);
        if (n < 0 && errno == EINTR) continue;
        if (n <= 0) return false;
        p += n;
        size -= size_t(n);
    }
    return true;
}

bool receive_all(int fd, void* data, size_t size) {
    char* p = static_cast<char*>(data);
    while (size > 0) {
        const ssize_t n = ::recv(fd, p, size, 0);
        if (n < 0 && errno == EINTR) continue;
        if (n <= 0) return false;  // end of file: the other side is gone
        p += n;
        size -= size_t(n);
    }
    return true;
}

bool send_u64(int fd, uint64_t v) { return send_all(fd, &v, sizeof v); }
bool receive_u64(int fd, uint64_t* v) { return receive_all(fd, v, sizeof *v); }

bool send_string(int fd, const std::string& s) { return send_u64(fd, s.size()) && send_all(fd, s.data(), s.size()); }

bool receive_string(int fd, std::string* s) {
    uint64_t size;
    if (!receive_u64(fd, &size) || size > (uint64_t(1) << 20)) return false;  // paths and metadata only
    s->resize(size_t(size));
    return receive_all(fd, s->data(), s->size());
}

constexpr uint64_t kWrite = 1, kRead = 2;

bool send_image(int fd, const StoredImage& image) {
    return send_u64(fd, uint64_t(image.width)) && send_u64(fd, uint64_t(image.height)) &&
           send_u64(fd, uint64_t(image.channels)) && send_u64(fd, image.is_float) &&
           send_u64(fd, image.srgb_encoded) && send_u64(fd, image.f32.size()) && send_u64(fd, image.u8.size()) &&
           send_all(fd, image.f32.data(), image.f32.size() * sizeof(float)) &&
           send_all(fd, image.u8.data(), image.u8.size());
}

bool receive_image(int fd, StoredImage* image) {
    uint64_t width, height, channels, is_float, srgb_encoded, floats, bytes;
    if (!receive_u64(fd, &width) || !receive_u64(fd, &height) || !receive_u64(fd, &channels) ||
        !receive_u64(fd, &is_float) || !receive_u64(fd, &srgb_encoded) || !receive_u64(fd, &floats) ||
        !receive_u64(fd, &bytes))
        return false;
    image->width = int(width);
    image->height = int(height);
    image->channels = int(channels);
    image->is_float = is_float != 0;
    image->srgb_encoded = srgb_encoded != 0;
    image->f32.resize(size_t(floats));
    image->u8.resize(size_t(bytes));
    return receive_all(fd, image->f32.data(), image->f32.size() * sizeof(float)) &&
           receive_all(fd, image->u8.data(), image->u8.size());
}

// From /proc/self/status; 0 if it cannot be read.
int thread_count() {
    std::FILE* f = std::fopen("/proc/self/status", "r");
    if (!f) return 0;
    char line[256];
    int threads = 0;
    while (std::fgets(line, sizeof line, f))
        if (std::sscanf(line, "Threads: %d", &threads) == 1) break;
    std::fclose(f);
    return threads;
}

// Threads before main(): libraries may start idle ones as they load (OpenVDB's log4cplus
// does), which a fork leaves behind harmlessly. A thread beyond those is clbdpt's or MPI's.
const int threads_at_start = thread_count();

// The process's life: load the module, then serve requests until the socket closes.
[[noreturn]] void serve(int fd, pid_t render) {
    // Ctrl-C is the render's to handle: it goes on to write what it has, through this process.
    // The render's handlers (cli/interrupt.h) are not this process's: SIGTERM simply ends it.
    ::signal(SIGINT, SIG_IGN);
    ::signal(SIGTERM, SIG_DFL);
    ::prctl(PR_SET_PDEATHSIG, SIGKILL);
    if (::getppid() != render) ::_exit(0);  // the render died before prctl
    // A library that calls exit() here (libjpeg's default error handler does) would run the
    // render's exit handlers in a copy of its process, where log4cplus's finaliser waits for a
    // thread the fork did not copy: a hang, found by a test. The render sees end of file instead.
    std::atexit([] { ::_exit(3); });
    // Errors go back over the socket. Holding the render's standard streams would keep a pipe
    // that reads them (a test, a script) open past the render's end.
    const int null = ::open("/dev/null", O_RDWR);
    if (null >= 0)
        for (int stream : {STDIN_FILENO, STDOUT_FILENO, STDERR_FILENO}) ::dup2(null, stream);
    const ImageIoModule* module = nullptr;
    std::string load_error;
    try {
        module = &image_io_module();
    } catch (const std::exception& e) {
        load_error = e.what();
    }
    for (;;) {
        uint64_t kind;
        if (!receive_u64(fd, &kind)) break;
        if (kind == kRead) {
            std::string path;
            uint64_t own_format;
            if (!receive_string(fd, &path) || !receive_u64(fd, &own_format)) break;
            StoredImage image;
            const std::string why = module ? module->read(path, own_format != 0, &image) : load_error;
            if (!send_string(fd, why) || (why.empty() && !send_image(fd, image))) break;
            continue;
        }
        std::string path, temp_path;
        uint64_t width, height, is_float, pairs;
        if (kind != kWrite || !receive_string(fd, &path) || !receive_string(fd, &temp_path) ||
            !receive_u64(fd, &width) || !receive_u64(fd, &height) || !receive_u64(fd, &is_float) ||
            !receive_u64(fd, &pairs))
            break;
        ImageAttributes metadata(static_cast<size_t>(pairs));
        bool ok = true;
        for (auto& [key, value] : metadata) ok = ok && receive_string(fd, &key) && receive_string(fd, &value);
        const size_t values = size_t(width) * size_t(height) * 3;
        std::vector<float> float_rgb(is_float ? values : 0);
        std::vector<uint8_t> srgb8(is_float ? 0 : values);
        ok = ok && (is_float ? receive_all(fd, float_rgb.data(), values * sizeof(float))
                             : receive_all(fd, srgb8.data(), values));
        if (!ok) break;
        const std::string why =
            module ? module->write_rgb(path, temp_path, int(width), int(height), is_float ? float_rgb.data() : nullptr,
                                       is_float ? nullptr : srgb8.data(), metadata)
                   : load_error;
        if (!send_string(fd, why)) break;
    }
    // No exit handlers: they belong to the render's process, whose state this is a copy of.
    ::_exit(0);
}

struct IoProcess {
    std::mutex mutex;
    pid_t pid = -1;
    int fd = -1;

    // Closes the socket and reaps the process. Every request it was sent has been answered, so
    // it is killed rather than waited for: a render that failed early would otherwise wait for
    // a load it no longer needs.
    void stop() {
        if (fd >= 0) ::close(fd);
        if (pid > 0) {
            ::kill(pid, SIGKILL);
            while (::waitpid(pid, nullptr, 0) < 0 && errno == EINTR) {
            }
        }
        pid = -1;
        fd = -1;
    }
    ~IoProcess() { stop(); }
};

IoProcess& io_process() {
    static IoProcess instance;
    return instance;
}

}  // namespace

bool start_image_io_process() {
    IoProcess& io = io_process();
    std::lock_guard<std::mutex> lock(io.mutex);
    if (io.pid > 0) return true;
    if (image_io_module_loaded() || threads_at_start == 0 || thread_count() != threads_at_start) return false;
    int fds[2];
    if (::socketpair(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0, fds) != 0) return false;
    const pid_t render = ::getpid();
    std::fflush(nullptr);  // nothing buffered is written twice
    const pid_t pid = ::fork();
    if (pid < 0) {
        ::close(fds[0]);
        ::close(fds[1]);
        return false;
    }
    if (pid == 0) {
        ::close(fds[0]);
        serve(fds[1], render);
    }
    ::close(fds[1]);
    io.pid = pid;
    io.fd = fds[0];
    return true;
}

std::optional<std::string> write_in_image_io_process(const std::string& path, const std::string& temp_path,
                                                     int width, int height, const float* float_rgb,
                                                     const uint8_t* srgb8, const ImageAttributes& metadata) {
    IoProcess& io = io_process();
    std::lock_guard<std::mutex> lock(io.mutex);
    const size_t values = size_t(width) * size_t(height) * 3;
    if (io.fd < 0 || values * (float_rgb ? sizeof(float) : 1) > kImageIoProcessMaxBytes) return std::nullopt;
    bool ok = send_u64(io.fd, kWrite) && send_string(io.fd, path) && send_string(io.fd, temp_path) &&
              send_u64(io.fd, uint64_t(width)) && send_u64(io.fd, uint64_t(height)) &&
              send_u64(io.fd, float_rgb ? 1 : 0) && send_u64(io.fd, metadata.size());
    for (const auto& [key, value] : metadata) ok = ok && send_string(io.fd, key) && send_string(io.fd, value);
    ok = ok && (float_rgb ? send_all(io.fd, float_rgb, values * sizeof(float)) : send_all(io.fd, srgb8, values));
    std::string why;
    if (ok && receive_string(io.fd, &why)) return why;
    io.stop();  // it died: the caller writes the image itself
    return std::nullopt;
}

std::optional<std::string> read_in_image_io_process(const std::string& path, bool own_format, StoredImage* image) {
    IoProcess& io = io_process();
    std::lock_guard<std::mutex> lock(io.mutex);
    if (io.fd < 0) return std::nullopt;
    std::string why;
    if (send_u64(io.fd, kRead) && send_string(io.fd, path) && send_u64(io.fd, own_format ? 1 : 0) &&
        receive_string(io.fd, &why) && (!why.empty() || receive_image(io.fd, image)))
        return why;
    io.stop();  // it died: the caller reads the image itself
    *image = StoredImage();
    return std::nullopt;
}

ImageIoProcessPause::ImageIoProcessPause() {
    IoProcess& io = io_process();
    std::lock_guard<std::mutex> lock(io.mutex);
    if (io.pid > 0 && ::kill(io.pid, SIGSTOP) == 0) pid_ = io.pid;
}

ImageIoProcessPause::~ImageIoProcessPause() {
    if (pid_ > 0) ::kill(pid_, SIGCONT);
}

int image_io_process_id() {
    IoProcess& io = io_process();
    std::lock_guard<std::mutex> lock(io.mutex);
    return io.pid;
}

void stop_image_io_process() {
    IoProcess& io = io_process();
    std::lock_guard<std::mutex> lock(io.mutex);
    io.stop();
}

}  // namespace clbdpt
