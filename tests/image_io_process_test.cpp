// The render's image I/O process: it writes and reads what this process would, bit for bit; if
// it dies, write_image and the readers do the work themselves; it is not forked beside a thread.
//
// Each case runs in a fresh process (a death test in gtest's "threadsafe" style re-runs this
// binary for it): start_image_io_process forks only from a process without threads of its
// own, and an earlier test in the same process may have started OpenCL's.
#include <signal.h>
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <future>
#include <iterator>
#include <string>
#include <thread>
#include <vector>

#include <gtest/gtest.h>

#include "film/image_io.h"
#include "film/image_io_module.h"
#include "film/image_io_process.h"
#include "util/error.h"

namespace clbdpt {
namespace {

namespace fs = std::filesystem;

// Fails the fresh process (exit status 1, the reason on stderr) unless `ok`.
void require(bool ok, const std::string& what) {
    if (ok) return;
    std::fprintf(stderr, "FAILED: %s\n", what.c_str());
    std::fflush(stderr);
    std::_Exit(1);
}

std::string read_bytes(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

class ImageIoProcessTest : public ::testing::Test {
protected:
    void SetUp() override {
        ::testing::GTEST_FLAG(death_test_style) = "threadsafe";
        dir_ = fs::temp_directory_path() /
               ("clbdpt_image_io_process_test_" + std::to_string(::getpid()) + "_" +
                ::testing::UnitTest::GetInstance()->current_test_info()->name());
        fs::remove_all(dir_);
        fs::create_directories(dir_);
    }
    void TearDown() override {
        std::error_code ec;
        fs::remove_all(dir_, ec);
    }
    std::string file(const std::string& name) const { return (dir_ / name).string(); }
    fs::path dir_;
};

// A 7x5 image with values no half float holds, and some out of [0, 1] for the PNG's clamp.
std::vector<float> test_image() {
    std::vector<float> rgb(7 * 5 * 3);
    for (size_t i = 0; i < rgb.size(); ++i) rgb[i] = 0.0137f * float(i) + 1e-6f * float(i * i) - 0.05f;
    return rgb;
}

TEST_F(ImageIoProcessTest, WritesWhatThisProcessWrites) {
    auto body = [this] {
        const std::vector<float> rgb = test_image();
        ImageMetadata meta;
        meta.strings.push_back({"clbdpt:integrator", "pt"});
        require(start_image_io_process(), "the process starts");
        require(image_io_process_id() > 0, "the process has an id");
        const int process = image_io_process_id();
        write_image(file("there.exr"), 7, 5, rgb, meta);
        write_image(file("there.png"), 7, 5, rgb, meta);
        require(image_io_process_id() == process, "the same process wrote both");
        require(!image_io_module_loaded(), "the process wrote them, not this one");
        stop_image_io_process();
        require(image_io_process_id() == -1, "the process is gone once stopped");
        write_image(file("here.exr"), 7, 5, rgb, meta);
        write_image(file("here.png"), 7, 5, rgb, meta);

        int w = 0, h = 0;
        const std::vector<float> back = read_image_rgb(file("there.exr"), &w, &h);
        require(w == 7 && h == 5 && back == rgb, "the EXR written there holds the pixels exactly");
        // A PNG holds no time stamp: the two files are the same bytes.
        require(read_bytes(file("there.png")) == read_bytes(file("here.png")), "the PNGs are identical");
        require(!read_bytes(file("there.png")).empty(), "the PNG is not empty");
        int entries = 0;
        for (auto it = fs::directory_iterator(dir_); it != fs::directory_iterator(); ++it) ++entries;
        require(entries == 4, "no temporary file is left");
        std::_Exit(0);
    };
    EXPECT_EXIT(body(), ::testing::ExitedWithCode(0), "");
}

TEST_F(ImageIoProcessTest, ReadsWhatThisProcessReads) {
    auto body = [this] {
        const std::vector<float> rgb = test_image();
        require(start_image_io_process(), "the process starts");
        write_image(file("image.exr"), 7, 5, rgb);
        write_image(file("image.png"), 7, 5, rgb);
        int w = 0, h = 0;
        const std::vector<float> exr_there = read_image_rgb(file("image.exr"), &w, &h);
        const std::vector<float> png_there = read_image_rgb(file("image.png"), &w, &h);
        const TextureImage texture_there = read_texture_image(file("image.png"));
        std::string missing_there;
        try {
            read_image_rgb(file("missing.exr"), &w, &h);
        } catch (const Error& e) {
            missing_there = e.what();
        }
        require(!image_io_module_loaded(), "the process read them, not this one");
        require(exr_there == rgb, "the EXR read there holds the pixels exactly");
        require(missing_there.find(file("missing.exr")) != std::string::npos,
                "a missing file's error names it: " + missing_there);
        stop_image_io_process();
        require(read_image_rgb(file("image.png"), &w, &h) == png_there, "the PNG reads the same here");
        const TextureImage texture_here = read_texture_image(file("image.png"));
        require(texture_here.rgba8 == texture_there.rgba8 && !texture_there.rgba8.empty() &&
                    texture_here.width == texture_there.width && !texture_there.is_float,
                "the texture reads the same here, as 8-bit values");
        std::_Exit(0);
    };
    EXPECT_EXIT(body(), ::testing::ExitedWithCode(0), "");
}

TEST_F(ImageIoProcessTest, ADeadProcessLeavesTheWriteToThisOne) {
    auto body = [this] {
        require(start_image_io_process(), "the process starts");
        ::kill(image_io_process_id(), SIGKILL);
        const std::vector<float> rgb = test_image();
        write_image(file("out.exr"), 7, 5, rgb);
        require(image_io_process_id() == -1, "the dead process is dropped");
        int w = 0, h = 0;
        require(read_image_rgb(file("out.exr"), &w, &h) == rgb, "the image is written all the same");
        std::_Exit(0);
    };
    EXPECT_EXIT(body(), ::testing::ExitedWithCode(0), "");
}

TEST_F(ImageIoProcessTest, ALargeImageIsWrittenHere) {
    auto body = [this] {
        require(start_image_io_process(), "the process starts");
        // One row more than kImageIoProcessMaxBytes holds, in float RGB.
        const int width = 1024, height = int(kImageIoProcessMaxBytes / (width * 3 * sizeof(float))) + 1;
        std::vector<float> rgb(size_t(width) * size_t(height) * 3, 0.25f);
        rgb.back() = 2.0f;
        write_image(file("large.exr"), width, height, rgb);
        require(image_io_module_loaded(), "this process wrote it");
        require(image_io_process_id() > 0, "the process is kept for smaller images");
        int w = 0, h = 0;
        require(read_image_rgb(file("large.exr"), &w, &h) == rgb, "the image is written");
        std::_Exit(0);
    };
    EXPECT_EXIT(body(), ::testing::ExitedWithCode(0), "");
}

TEST_F(ImageIoProcessTest, NotForkedBesideAThread) {
    auto body = [this] {
        std::promise<void> release;
        std::thread waiting([f = release.get_future()]() mutable { f.wait(); });
        const bool started = start_image_io_process();
        release.set_value();
        waiting.join();
        require(!started, "no fork beside a running thread");
        require(image_io_process_id() == -1, "no process");
        std::_Exit(0);
    };
    EXPECT_EXIT(body(), ::testing::ExitedWithCode(0), "");
}

}  // namespace
}  // namespace clbdpt
