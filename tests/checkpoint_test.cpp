// The checkpoint file (film/checkpoint.h): the film's sums come back bit for bit, every
// damaged or foreign file is refused with its name, and settings differences are named.
#include "film/checkpoint.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <sstream>

#include "util/error.h"

namespace {

namespace fs = std::filesystem;
using clbdpt::Checkpoint;
using clbdpt::CheckpointInfo;
using clbdpt::Film;

std::string temp_path(const std::string& name) {
    return (fs::temp_directory_path() / ("clbdpt_checkpoint_" + std::to_string(::getpid()) + "_" + name)).string();
}

std::string error_of(const std::string& path) {
    try {
        clbdpt::read_checkpoint(path);
    } catch (const clbdpt::Error& e) {
        return e.what();
    }
    return "";
}

Film example_film(bool strategies) {
    Film film(5, 3);
    film.spp = 17;
    // Values whose every bit matters: denormals, negative zero, the largest double, fractions
    // with long mantissas.
    for (size_t i = 0; i < film.camera_sum.size(); ++i) {
        film.camera_sum[i] = std::ldexp(1.0 / 3.0 + double(i), int(i) - 7);
        film.light_sum[i] = i == 0 ? std::numeric_limits<double>::denorm_min()
                            : i == 1 ? -0.0
                            : i == 2 ? std::numeric_limits<double>::max()
                                     : std::sqrt(double(i));
    }
    if (strategies) {
        film.strategy_stride = 6;
        film.strategy_sum.resize(film.camera_sum.size() * 5 * 6);
        for (size_t i = 0; i < film.strategy_sum.size(); ++i) film.strategy_sum[i] = std::sin(double(i));
    }
    return film;
}

bool same_bits(const std::vector<double>& a, const std::vector<double>& b) {
    return a.size() == b.size() && (a.empty() || std::memcmp(a.data(), b.data(), sizeof(double) * a.size()) == 0);
}

TEST(Checkpoint, RoundTripIsBitExact) {
    for (bool strategies : {false, true}) {
        const std::string path = temp_path("round_trip");
        CheckpointInfo info;
        info.scene_fingerprint = 0x0123456789abcdefull;
        info.settings = "integrator=auto sampler=sobol max_depth=5 seed=0";
        info.integrator = 1;
        info.light_subpaths = 0.25f;
        info.inner_connections = 0;
        const Film film = example_film(strategies);
        clbdpt::write_checkpoint(path, info, film);
        const Checkpoint c = clbdpt::read_checkpoint(path);
        fs::remove(path);
        EXPECT_EQ(c.info.scene_fingerprint, info.scene_fingerprint);
        EXPECT_EQ(c.info.settings, info.settings);
        EXPECT_EQ(c.info.integrator, 1);
        EXPECT_EQ(c.info.light_subpaths, 0.25f);
        EXPECT_EQ(c.info.inner_connections, 0);
        EXPECT_EQ(c.film.width, 5);
        EXPECT_EQ(c.film.height, 3);
        EXPECT_EQ(c.film.spp, 17);
        EXPECT_TRUE(same_bits(c.film.camera_sum, film.camera_sum));
        EXPECT_TRUE(same_bits(c.film.light_sum, film.light_sum));
        EXPECT_TRUE(same_bits(c.film.strategy_sum, film.strategy_sum)) << strategies;
        EXPECT_EQ(c.film.strategy_stride, strategies ? 6 : 0);
        EXPECT_FALSE(fs::exists(path + ".tmp-" + std::to_string(::getpid())));
    }
}

// Every single-byte change and every truncation of a checkpoint is caught (the header's
// checks, the size, or the hash), never read as another film.
TEST(Checkpoint, EveryDamagedByteAndEveryTruncationIsRefused) {
    const std::string path = temp_path("damaged");
    clbdpt::write_checkpoint(path, CheckpointInfo{}, example_film(false));
    std::ifstream in(path, std::ios::binary);
    std::stringstream buffer;
    buffer << in.rdbuf();
    const std::string bytes = buffer.str();
    const std::string damaged_path = temp_path("damaged_copy");
    for (size_t i = 0; i < bytes.size(); ++i) {
        std::string copy = bytes;
        copy[i] = char(copy[i] ^ 0x01);
        std::ofstream(damaged_path, std::ios::binary) << copy;
        const std::string message = error_of(damaged_path);
        ASSERT_NE(message, "") << "byte " << i;
        EXPECT_NE(message.find(damaged_path), std::string::npos) << message;
    }
    for (size_t size : {size_t(0), size_t(7), size_t(8), size_t(63), size_t(64), bytes.size() / 2, bytes.size() - 1}) {
        std::ofstream(damaged_path, std::ios::binary) << bytes.substr(0, size);
        EXPECT_NE(error_of(damaged_path), "") << "truncated to " << size;
    }
    fs::remove(path);
    fs::remove(damaged_path);
    EXPECT_NE(error_of(damaged_path).find("cannot read checkpoint"), std::string::npos);
}

TEST(Checkpoint, SettingsDifferencesAreNamed) {
    using clbdpt::settings_differences;
    EXPECT_TRUE(settings_differences("a=1 b=2", "a=1 b=2").empty());
    const std::vector<std::string> d = settings_differences("a=1 b=2 c=3", "a=1 b=5 d=4");
    ASSERT_EQ(d.size(), 3u);
    EXPECT_EQ(d[0], "b: 2 -> 5");
    EXPECT_EQ(d[1], "c: 3 -> (none)");
    EXPECT_EQ(d[2], "d: (none) -> 4");
}

}  // namespace
