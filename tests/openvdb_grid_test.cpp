// Density grids read from OpenVDB files (host/scene/openvdb_grid.cpp): where the voxels land,
// and one clear line for each way a file can be unusable. The files are written here with
// OpenVDB itself, so the test needs the build to have it (CI installs libopenvdb-dev); a build
// without it checks its one error instead.
#include <gtest/gtest.h>

#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <vector>

#include "scene/density_grid.h"
#include "util/error.h"

#ifdef CLBDPT_HAS_OPENVDB
#include <openvdb/openvdb.h>
#endif

namespace clbdpt {
namespace {

namespace fs = std::filesystem;

std::string read_error(const std::string& path, const std::string& grid) {
    try {
        read_openvdb_grid(path, grid);
    } catch (const Error& e) {
        return e.what();
    }
    return "";
}

#ifdef CLBDPT_HAS_OPENVDB

class OpenVdbFiles : public ::testing::Test {
protected:
    void SetUp() override {
        openvdb::initialize();
        dir_ = fs::temp_directory_path() / ("clbdpt_vdb_test_" + std::to_string(::getpid()) + "_" +
                                            ::testing::UnitTest::GetInstance()->current_test_info()->name());
        fs::create_directories(dir_);
    }
    void TearDown() override {
        std::error_code ec;
        fs::remove_all(dir_, ec);
    }
    std::string write(const std::string& name, const openvdb::GridPtrVec& grids) {
        const std::string path = (dir_ / name).string();
        openvdb::io::File(path).write(grids);
        return path;
    }
    fs::path dir_;
};

// A float grid of voxel size 0.5 translated by (1, 0, 0), three active voxels; voxel (2, 3, 4)
// is centred at (2, 1.5, 2) in scene space.
openvdb::FloatGrid::Ptr sample_grid() {
    auto grid = openvdb::FloatGrid::create(0.0f);
    grid->setName("density");
    auto transform = openvdb::math::Transform::createLinearTransform(0.5);
    transform->postTranslate(openvdb::Vec3d(1, 0, 0));
    grid->setTransform(transform);
    auto accessor = grid->getAccessor();
    accessor.setValue(openvdb::Coord(2, 3, 4), 2.5f);
    accessor.setValue(openvdb::Coord(3, 3, 4), 1.0f);
    accessor.setValue(openvdb::Coord(2, 5, 4), -0.25f);  // simulation noise: read as 0, counted
    return grid;
}

TEST_F(OpenVdbFiles, VoxelsLandWhereTheFilePutsThem) {
    const std::string path = write("smoke.vdb", {sample_grid()});
    const DensityGrid g = read_openvdb_grid(path, "density");
    // Active box (2..3, 3..5, 4..4) plus one voxel of background on every side.
    EXPECT_EQ(g.size[0], 4);
    EXPECT_EQ(g.size[1], 5);
    EXPECT_EQ(g.size[2], 3);
    EXPECT_EQ(g.negative_voxels, 1);
    EXPECT_FLOAT_EQ(g.max_value(), 2.5f);
    auto at = [&](int i, int j, int k) { return g.values[size_t(i + g.size[0] * (j + g.size[1] * k))]; };
    EXPECT_FLOAT_EQ(at(1, 1, 1), 2.5f);  // voxel (2, 3, 4)
    EXPECT_FLOAT_EQ(at(2, 1, 1), 1.0f);  // voxel (3, 3, 4)
    EXPECT_FLOAT_EQ(at(1, 3, 1), 0.0f);  // the negative one
    EXPECT_FLOAT_EQ(at(0, 0, 0), 0.0f);  // background
    const float p[3] = {2.0f, 1.5f, 2.0f}, expected[3] = {1, 1, 1};
    for (int axis = 0; axis < 3; ++axis) {
        const float* row = g.world_to_grid[axis];
        EXPECT_NEAR(row[0] * p[0] + row[1] * p[1] + row[2] * p[2] + row[3], expected[axis], 1e-5f) << axis;
    }
}

// "bounds" in the scene file fits the active voxels into a box instead.
TEST_F(OpenVdbFiles, BoundsPlaceTheActiveVoxels) {
    DensityGrid g = read_openvdb_grid(write("smoke.vdb", {sample_grid()}), "density");
    place_grid_in_box(g, {0, 0, 0}, {2, 3, 1}, 1);
    // The active voxels (2 x 3 x 1) fill the box: voxel (2, 3, 4), the first, is centred at
    // (0.5, 0.5, 0.5), one voxel in from the padding.
    const float p[3] = {0.5f, 0.5f, 0.5f}, expected[3] = {1, 1, 1};
    for (int axis = 0; axis < 3; ++axis) {
        const float* row = g.world_to_grid[axis];
        EXPECT_NEAR(row[0] * p[0] + row[1] * p[1] + row[2] * p[2] + row[3], expected[axis], 1e-5f) << axis;
    }
}

TEST_F(OpenVdbFiles, DoubleGridsToo) {
    auto grid = openvdb::DoubleGrid::create(0.0);
    grid->setName("density");
    grid->getAccessor().setValue(openvdb::Coord(0, 0, 0), 0.75);
    const DensityGrid g = read_openvdb_grid(write("d.vdb", {grid}), "density");
    EXPECT_FLOAT_EQ(g.max_value(), 0.75f);
}

TEST_F(OpenVdbFiles, UnusableFilesGetOneClearLine) {
    auto temperature = sample_grid();
    temperature->setName("temperature");
    auto flame = sample_grid();
    flame->setName("flame");
    const std::string named = write("fire.vdb", {temperature, flame});
    EXPECT_EQ(read_error(named, "density"), named + ": no grid named \"density\" (grids: flame, temperature)");

    auto velocity = openvdb::Vec3SGrid::create();
    velocity->setName("density");
    velocity->getAccessor().setValue(openvdb::Coord(0, 0, 0), openvdb::Vec3s(1, 0, 0));
    const std::string vectors = write("v.vdb", {velocity});
    EXPECT_EQ(read_error(vectors, "density"), vectors + ": grid \"density\" holds vec3s values, not float or double");

    auto empty = openvdb::FloatGrid::create(0.0f);
    empty->setName("density");
    const std::string nothing = write("empty.vdb", {empty});
    EXPECT_EQ(read_error(nothing, "density"), nothing + ": grid \"density\" has no active voxels");

    auto nan = sample_grid();
    nan->getAccessor().setValue(openvdb::Coord(3, 4, 4), NAN);
    const std::string bad = write("nan.vdb", {nan});
    EXPECT_EQ(read_error(bad, "density"), bad + ": grid \"density\" has a non-finite voxel at (3, 4, 4)");

    const std::string garbage = (dir_ / "garbage.vdb").string();
    std::ofstream(garbage) << "not a volume";
    EXPECT_EQ(read_error(garbage, "density").rfind(garbage + ": not a readable OpenVDB file (", 0), 0u)
        << read_error(garbage, "density");

    const std::string missing = (dir_ / "missing.vdb").string();
    EXPECT_EQ(read_error(missing, "density"), missing + ": no such file");
}

// Two 10 KB files found by fuzzing: one whose damaged metadata states a length of gigabytes
// (OpenVDB would allocate it: 12 GiB in all, 23 s, before noticing; the allocation cap turns
// it into the damaged-file line at once), one whose damaged counts kept OpenVDB reading a
// failed stream for minutes (a stream that throws at the first failed read ends it).
TEST_F(OpenVdbFiles, DamagedSizesAndCountsAreRefusedAtOnce) {
    const std::string damaged = std::string(CLBDPT_TEST_DATA_DIR) + "/damaged_sizes.vdb";
    EXPECT_EQ(read_error(damaged, "density"),
              damaged + ": not a readable OpenVDB file (it states sizes far beyond its own; damaged?)");
    // A file whose damaged counts made OpenVDB go on reading past its end, for minutes.
    const std::string short_file = std::string(CLBDPT_TEST_DATA_DIR) + "/failed_stream.vdb";
    EXPECT_EQ(read_error(short_file, "density"),
              short_file + ": not a readable OpenVDB file (it ends early or cannot be read; damaged?)");
    // The cap is gone afterwards: a large allocation succeeds.
    std::vector<char> large(size_t(256) << 20);
    EXPECT_EQ(large.size(), size_t(256) << 20);
}

#else

TEST(OpenVdbFiles, ThisBuildRefusesThemClearly) {
    EXPECT_FALSE(openvdb_supported());
    EXPECT_EQ(read_error("smoke.vdb", "density"),
              "smoke.vdb: this build of clbdpt cannot read OpenVDB files (install libopenvdb-dev and rebuild)");
}

#endif

}  // namespace
}  // namespace clbdpt
