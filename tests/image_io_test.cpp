// Image output: exact EXR round trips, tonemapped PNG, and failures that leave no file behind;
// the render's image I/O process reads and writes the same bits, and is never needed.
#include <signal.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <future>
#include <iterator>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include <OpenImageIO/imageio.h>
#include <gtest/gtest.h>

#include "film/image_io.h"
#include "film/image_io_module.h"
#include "film/image_io_process.h"
#include "util/error.h"

namespace clbdpt {
namespace {

namespace fs = std::filesystem;

// A fresh empty folder per test, removed afterwards.
class ImageIoTest : public ::testing::Test {
protected:
    void SetUp() override {
        dir_ = fs::temp_directory_path() /
               ("clbdpt_image_io_test_" + std::to_string(::getpid()) + "_" +
                ::testing::UnitTest::GetInstance()->current_test_info()->name());
        fs::remove_all(dir_);
        fs::create_directories(dir_);
    }
    void TearDown() override {
        std::error_code ec;
        fs::remove_all(dir_, ec);
    }
    std::string file(const std::string& name) const { return (dir_ / name).string(); }
    size_t entries() const {
        size_t n = 0;
        for (auto it = fs::directory_iterator(dir_); it != fs::directory_iterator(); ++it) ++n;
        return n;
    }
    fs::path dir_;
};

std::string write_error(const std::string& path, int width, int height, const std::vector<float>& rgb) {
    try {
        write_image(path, width, height, rgb);
    } catch (const Error& e) {
        return e.what();
    }
    return "";
}

float srgb_encode(float linear) {
    return linear <= 0.0031308f ? 12.92f * linear : 1.055f * std::pow(linear, 1.0f / 2.4f) - 0.055f;
}

TEST_F(ImageIoTest, ExrRoundTripIsExact) {
    const int width = 5, height = 3;
    std::vector<float> rgb(width * height * 3);
    for (size_t i = 0; i < rgb.size(); ++i) {
        // Values no 16-bit half could hold exactly: the file must be 32-bit float.
        rgb[i] = 0.1234567f * static_cast<float>(i) + 1e-7f * static_cast<float>(i * i) + (i % 7 == 0 ? 65504.5f : 0.0f);
    }
    ImageMetadata metadata;
    metadata.strings.push_back({"clbdpt:integrator", "bdpt"});
    write_image(file("out.exr"), width, height, rgb, metadata);
    EXPECT_EQ(entries(), 1u);  // no temporary left next to it

    int w = 0, h = 0;
    const std::vector<float> back = read_image_rgb(file("out.exr"), &w, &h);
    EXPECT_EQ(w, width);
    EXPECT_EQ(h, height);
    ASSERT_EQ(back.size(), rgb.size());
    for (size_t i = 0; i < rgb.size(); ++i) EXPECT_EQ(back[i], rgb[i]) << "at " << i;

    auto in = OIIO::ImageInput::open(file("out.exr"));
    ASSERT_TRUE(in);
    EXPECT_EQ(in->spec().format, OIIO::TypeDesc::FLOAT);
    EXPECT_EQ(in->spec().get_string_attribute("clbdpt:integrator"), "bdpt");
}

TEST_F(ImageIoTest, ExrRowZeroIsTheTop) {
    // 1x2: top pixel red, bottom blue.
    write_image(file("rows.exr"), 1, 2, {1, 0, 0, 0, 0, 1});
    auto in = OIIO::ImageInput::open(file("rows.exr"));
    ASSERT_TRUE(in);
    std::vector<float> scanline(3);
    ASSERT_TRUE(in->read_scanline(0, 0, OIIO::TypeDesc::FLOAT, scanline.data()));
    EXPECT_EQ(scanline, (std::vector<float>{1, 0, 0}));
}

TEST_F(ImageIoTest, PngIsClampedSrgb8) {
    const std::vector<float> rgb = {0.0f, 0.5f, 1.0f, 2.0f, -1.0f, 0.002f};
    write_image(file("out.png"), 2, 1, rgb);
    EXPECT_EQ(entries(), 1u);

    auto in = OIIO::ImageInput::open(file("out.png"));
    ASSERT_TRUE(in);
    EXPECT_EQ(in->spec().width, 2);
    EXPECT_EQ(in->spec().nchannels, 3);
    std::vector<unsigned char> bytes(6);
    ASSERT_TRUE(in->read_image(0, 0, 0, 3, OIIO::TypeDesc::UINT8, bytes.data()));
    const std::vector<int> expected = {0, static_cast<int>(std::lround(255 * srgb_encode(0.5f))), 255, 255, 0,
                                       static_cast<int>(std::lround(255 * srgb_encode(0.002f)))};
    for (size_t i = 0; i < 6; ++i) EXPECT_EQ(static_cast<int>(bytes[i]), expected[i]) << "at " << i;
    EXPECT_EQ(expected[1], 188);

    // read_image_rgb undoes the sRGB curve: the clamped linear values come back to 8-bit accuracy.
    int w = 0, h = 0;
    const std::vector<float> back = read_image_rgb(file("out.png"), &w, &h);
    ASSERT_EQ(back.size(), 6u);
    const float clamped[] = {0.0f, 0.5f, 1.0f, 1.0f, 0.0f, 0.002f};
    for (size_t i = 0; i < 6; ++i) EXPECT_NEAR(back[i], clamped[i], 0.003f) << "at " << i;
}

TEST_F(ImageIoTest, JpegAndTiffAreWritten) {
    const std::vector<float> rgb(4 * 4 * 3, 0.25f);
    write_image(file("out.jpg"), 4, 4, rgb);
    write_image(file("out.tif"), 4, 4, rgb);
    EXPECT_TRUE(fs::is_regular_file(file("out.jpg")));
    EXPECT_TRUE(fs::is_regular_file(file("out.tif")));
    EXPECT_EQ(entries(), 2u);
}

TEST_F(ImageIoTest, NanPixelIsRefusedAndNoFileIsLeft) {
    std::vector<float> rgb(3 * 2 * 3, 0.5f);
    rgb[(1 * 3 + 2) * 3 + 1] = std::nanf("");  // pixel (2, 1), green
    EXPECT_EQ(write_error(file("nan.exr"), 3, 2, rgb), "refusing to write " + file("nan.exr") + ": pixel (2,1) is NaN/Inf");
    rgb[(1 * 3 + 2) * 3 + 1] = 0.5f;
    rgb[0] = INFINITY;
    EXPECT_EQ(write_error(file("inf.png"), 3, 2, rgb), "refusing to write " + file("inf.png") + ": pixel (0,0) is NaN/Inf");
    EXPECT_EQ(entries(), 0u);
}

TEST_F(ImageIoTest, UnwritablePathFailsAndLeavesNothing) {
    const std::string path = file("no_such_folder/out.exr");
    const std::string message = write_error(path, 1, 1, {0.5f, 0.5f, 0.5f});
    EXPECT_NE(message.find("cannot write '" + path + "'"), std::string::npos) << message;
    EXPECT_EQ(entries(), 0u);
}

TEST_F(ImageIoTest, FailedRenameRemovesTheTemporary) {
    // The target is a folder: the temporary is written, the rename fails, and it is removed.
    fs::create_directories(file("taken.png"));
    const std::string message = write_error(file("taken.png"), 1, 1, {0.5f, 0.5f, 0.5f});
    EXPECT_NE(message.find("cannot write '" + file("taken.png") + "'"), std::string::npos) << message;
    EXPECT_EQ(entries(), 1u);
    EXPECT_TRUE(fs::is_directory(file("taken.png")));
}

TEST_F(ImageIoTest, BadArguments) {
    EXPECT_NE(write_error(file("out.bmpx"), 1, 1, {0, 0, 0}).find("unsupported image format"), std::string::npos);
    EXPECT_NE(write_error(file("out.exr"), 2, 2, {0, 0, 0}).find("cannot write"), std::string::npos);
    EXPECT_EQ(entries(), 0u);
}

TEST_F(ImageIoTest, SupportedOutputs) {
    EXPECT_TRUE(is_supported_output("a.exr"));
    EXPECT_TRUE(is_supported_output("dir/a.PNG"));
    EXPECT_TRUE(is_supported_output("a.jpg"));
    EXPECT_TRUE(is_supported_output("a.jpeg"));
    EXPECT_TRUE(is_supported_output("a.tif"));
    EXPECT_FALSE(is_supported_output("a.hdr"));
    EXPECT_FALSE(is_supported_output("exr"));
}

TEST_F(ImageIoTest, ReadsGreyAndRgbaAsRgb) {
    {
        auto out = OIIO::ImageOutput::create(file("grey.exr"));
        ASSERT_TRUE(out);
        OIIO::ImageSpec spec(2, 1, 1, OIIO::TypeDesc::FLOAT);
        ASSERT_TRUE(out->open(file("grey.exr"), spec));
        const float grey[] = {0.25f, 3.0f};
        ASSERT_TRUE(out->write_image(OIIO::TypeDesc::FLOAT, grey));
        ASSERT_TRUE(out->close());
    }
    {
        auto out = OIIO::ImageOutput::create(file("rgba.exr"));
        ASSERT_TRUE(out);
        OIIO::ImageSpec spec(1, 1, 4, OIIO::TypeDesc::FLOAT);
        ASSERT_TRUE(out->open(file("rgba.exr"), spec));
        const float rgba[] = {1.0f, 2.0f, 3.0f, 0.5f};
        ASSERT_TRUE(out->write_image(OIIO::TypeDesc::FLOAT, rgba));
        ASSERT_TRUE(out->close());
    }
    int w = 0, h = 0;
    EXPECT_EQ(read_image_rgb(file("grey.exr"), &w, &h), (std::vector<float>{0.25f, 0.25f, 0.25f, 3, 3, 3}));
    EXPECT_EQ(w, 2);
    EXPECT_EQ(h, 1);
    EXPECT_EQ(read_image_rgb(file("rgba.exr"), &w, &h), (std::vector<float>{1, 2, 3}));
}

TEST_F(ImageIoTest, ReadingAMissingFileNamesIt) {
    int w = 0, h = 0;
    try {
        read_image_rgb(file("absent.exr"), &w, &h);
        FAIL() << "no error";
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find(file("absent.exr")), std::string::npos) << e.what();
    }
}

// The folder of the test running in this fresh process. The process ends by _Exit, so no
// TearDown removes it: end_fresh_process does.
fs::path g_fresh_process_dir;

[[noreturn]] void end_fresh_process(int status) {
    std::error_code ec;
    fs::remove_all(g_fresh_process_dir, ec);
    std::_Exit(status);
}

// Fails the fresh process (exit status 1, the reason on stderr) unless `ok`.
void require(bool ok, const std::string& what) {
    if (ok) return;
    std::fprintf(stderr, "FAILED: %s\n", what.c_str());
    std::fflush(stderr);
    end_fresh_process(1);
}

std::string read_bytes(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

// The render's image I/O process (film/image_io_process.h). Each case runs in a fresh process (a
// death test in gtest's "threadsafe" style re-runs this binary for it): the process is forked
// only from a process without threads of its own, and an earlier test in the same process may
// have started OpenCL's.
class ImageIoProcessTest : public ImageIoTest {
protected:
    void SetUp() override {
        ::testing::GTEST_FLAG(death_test_style) = "threadsafe";
        ImageIoTest::SetUp();
        g_fresh_process_dir = dir_;
    }
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
        require(entries() == 4, "no temporary file is left");
        end_fresh_process(0);
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
        end_fresh_process(0);
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
        end_fresh_process(0);
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
        end_fresh_process(0);
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
        end_fresh_process(0);
    };
    EXPECT_EXIT(body(), ::testing::ExitedWithCode(0), "");
}

}  // namespace
}  // namespace clbdpt
