// OpenVDB files into dense density grids (scene/density_grid.h). Built with OpenVDB when CMake
// finds it (CLBDPT_HAS_OPENVDB); without it, asking for a file is a clear error.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "scene/density_grid.h"
#include "util/allocation_cap.h"
#include "util/error.h"

#ifdef CLBDPT_HAS_OPENVDB
#include <openvdb/io/Stream.h>
#include <openvdb/openvdb.h>
#endif

namespace clbdpt {

#ifdef CLBDPT_HAS_OPENVDB

bool openvdb_supported() { return true; }

namespace {

template <typename GridType>
DensityGrid dense_copy(const std::string& path, const std::string& grid_name, const GridType& grid) {
    const openvdb::CoordBBox active = grid.evalActiveVoxelBoundingBox();
    if (active.empty()) throw Error(path + ": grid \"" + grid_name + "\" has no active voxels");
    if (!grid.transform().isLinear()) {
        throw Error(path + ": grid \"" + grid_name + "\" has a non-linear (frustum) transform, which is not supported");
    }
    // One voxel of background around the active box, so the density fades to it as in VDB's
    // own trilinear sampling.
    const openvdb::Coord lo = active.min() - openvdb::Coord(1), hi = active.max() + openvdb::Coord(1);
    DensityGrid out;
    uint64_t count = 1;
    for (int axis = 0; axis < 3; ++axis) {
        out.size[axis] = hi[axis] - lo[axis] + 1;
        count *= uint64_t(out.size[axis]);
    }
    if (count > (uint64_t(1) << 28)) {
        throw Error(path + ": grid \"" + grid_name + "\" spans " + std::to_string(out.size[0]) + "x" +
                    std::to_string(out.size[1]) + "x" + std::to_string(out.size[2]) +
                    " voxels, more than the 2^28 a dense copy may have");
    }
    out.values.resize(count);
    auto accessor = grid.getConstAccessor();
    size_t i = 0;
    for (int z = lo.z(); z <= hi.z(); ++z) {
        for (int y = lo.y(); y <= hi.y(); ++y) {
            for (int x = lo.x(); x <= hi.x(); ++x, ++i) {
                const double v = double(accessor.getValue(openvdb::Coord(x, y, z)));
                if (!std::isfinite(v)) {
                    throw Error(path + ": grid \"" + grid_name + "\" has a non-finite voxel at (" + std::to_string(x) +
                                ", " + std::to_string(y) + ", " + std::to_string(z) + ")");
                }
                if (v < 0) ++out.negative_voxels;
                out.values[i] = v < 0 ? 0.0f : float(v);
            }
        }
    }
    // index = world * M^-1 (OpenVDB's row-vector convention); grid = index - lo.
    const openvdb::math::Mat4d inverse = grid.transform().baseMap()->getAffineMap()->getMat4().inverse();
    for (int axis = 0; axis < 3; ++axis) {
        for (int j = 0; j < 3; ++j) out.world_to_grid[axis][j] = float(inverse(j, axis));
        out.world_to_grid[axis][3] = float(inverse(3, axis) - lo[axis]);
    }
    return out;
}

}  // namespace

DensityGrid read_openvdb_grid(const std::string& path, const std::string& grid_name) {
    openvdb::initialize();
    if (!std::filesystem::is_regular_file(path)) throw Error(path + ": no such file");
    openvdb::GridBase::Ptr base;
    std::string names;
    try {
        // Nothing OpenVDB holds for a grid is one block larger than this, nor than the file
        // (what it decompresses comes in leaf-sized pieces); a larger request is damage.
        constexpr size_t kMinCap = size_t(64) << 20;
        const AllocationCap cap(std::max<size_t>(kMinCap, std::filesystem::file_size(path)));
        // Read through a stream that throws at the first read past the end or failed read:
        // OpenVDB goes on reading a failed stream, and a damaged count (found by fuzzing) made
        // it loop for minutes over reads that return nothing.
        std::ifstream in(path, std::ios::binary);
        in.exceptions(std::ios::failbit | std::ios::badbit);
        openvdb::io::Stream stream(in, /*delayLoad=*/false);
        std::vector<std::string> sorted_names;
        for (const openvdb::GridBase::Ptr& grid : *stream.getGrids()) {
            sorted_names.push_back(grid->getName());
            if (!base && grid->getName() == grid_name) base = grid;
        }
        std::sort(sorted_names.begin(), sorted_names.end());
        for (const std::string& name : sorted_names) names += (names.empty() ? "" : ", ") + name;
    } catch (const std::bad_alloc&) {
        throw Error(path + ": not a readable OpenVDB file (it states sizes far beyond its own; damaged?)");
    } catch (const std::ios_base::failure&) {
        throw Error(path + ": not a readable OpenVDB file (it ends early or cannot be read; damaged?)");
    } catch (const openvdb::Exception& e) {
        throw Error(path + ": not a readable OpenVDB file (" + e.what() + ")");
    } catch (const std::exception& e) {
        throw Error(path + ": not a readable OpenVDB file (" + e.what() + ")");
    }
    if (!base) {
        throw Error(path + ": no grid named \"" + grid_name + "\" (" +
                    (names.empty() ? std::string("the file has no grids") : "grids: " + names) + ")");
    }
    if (auto g = openvdb::gridPtrCast<openvdb::FloatGrid>(base)) return dense_copy(path, grid_name, *g);
    if (auto g = openvdb::gridPtrCast<openvdb::DoubleGrid>(base)) return dense_copy(path, grid_name, *g);
    throw Error(path + ": grid \"" + grid_name + "\" holds " + base->valueType() + " values, not float or double");
}

#else

bool openvdb_supported() { return false; }

DensityGrid read_openvdb_grid(const std::string& path, const std::string&) {
    throw Error(path + ": this build of clbdpt cannot read OpenVDB files (install libopenvdb-dev and rebuild)");
}

#endif

}  // namespace clbdpt
