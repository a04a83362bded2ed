// Running the clbdpt binary from tests: a command's status and output, and a fresh folder per
// test for what it writes.
#pragma once

#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <array>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <string>
#include <vector>

#include "film/image_io.h"

namespace clbdpt_cli_test {

namespace fs = std::filesystem;

struct CommandResult {
    int status = -1;
    std::string output;  // stdout and stderr together
};

inline CommandResult run(const std::string& args, const std::string& env = "") {
    CommandResult r;
    std::string cmd = env + std::string(CLBDPT_BINARY) + " " + args + " 2>&1";
    FILE* pipe = popen(cmd.c_str(), "r");
    if (!pipe) return r;
    std::array<char, 4096> buf;
    size_t n;
    while ((n = fread(buf.data(), 1, buf.size(), pipe)) > 0) r.output.append(buf.data(), n);
    int st = pclose(pipe);
    r.status = WIFEXITED(st) ? WEXITSTATUS(st) : -1;
    return r;
}

// Exact equality of two images' floats (an EXR keeps them as rendered).
inline void expect_same_image(const std::string& a_path, const std::string& b_path) {
    int w = 0, h = 0, w2 = 0, h2 = 0;
    const std::vector<float> a = clbdpt::read_image_rgb(a_path, &w, &h);
    const std::vector<float> b = clbdpt::read_image_rgb(b_path, &w2, &h2);
    ASSERT_EQ(a.size(), b.size());
    ASSERT_FALSE(a.empty());
    EXPECT_EQ(std::memcmp(a.data(), b.data(), a.size() * sizeof(float)), 0) << a_path << " differs from " << b_path;
}

inline std::string data(const std::string& name) { return std::string(CLBDPT_TEST_DATA_DIR) + "/" + name; }

class CliTest : public ::testing::Test {
protected:
    void SetUp() override {
        dir_ = fs::temp_directory_path() / ("clbdpt_cli_" + std::to_string(::getpid()) + "_" +
                                            ::testing::UnitTest::GetInstance()->current_test_info()->name());
        fs::remove_all(dir_);
        fs::create_directories(dir_);
    }
    void TearDown() override { fs::remove_all(dir_); }
    std::string out(const std::string& name) const { return (dir_ / name).string(); }
    bool dir_is_empty() const { return fs::is_empty(dir_); }
    fs::path dir_;
};

}  // namespace clbdpt_cli_test
