// Density grids of heterogeneous media (cl/medium.h): voxel values and where they sit in scene
// space, from the scene file itself (a small built-in grid) or from an OpenVDB file.
#pragma once

#include <string>
#include <vector>

#include "util/vec3.h"

namespace clbdpt {

struct DensityGrid {
    int size[3] = {0, 0, 0};
    std::vector<float> values;  // size[0] * size[1] * size[2], x fastest, then y, then z
    // Rows of the affine map from scene space to voxel coordinates, in which voxel (i, j, k) is
    // centred at (i, j, k) and the grid spans -0.5 .. size - 0.5 along each axis.
    float world_to_grid[3][4] = {};
    int negative_voxels = 0;  // clamped to 0 while reading a file (simulation noise)

    float max_value() const;
};

// Places the grid so that its voxels, less `padding` voxels on every side, fill the box
// [lo, hi] of scene space (lo < hi on every axis).
void place_grid_in_box(DensityGrid& grid, Vec3 lo, Vec3 hi, int padding);

// Whether this build reads OpenVDB files (the libopenvdb-dev package at build time).
bool openvdb_supported();

// Reads the scalar grid `grid_name` of the OpenVDB file `path` (float or double voxels) over
// its active voxels' bounding box plus one voxel of background on every side, placed where the
// file's own transform puts it (linear transforms only). Throws clbdpt::Error naming the file:
// unreadable, no grid of that name (the names it has are listed), not a scalar grid, no
// active voxels, a non-linear transform, NaN or infinite voxels, more than 2^28 voxels.
DensityGrid read_openvdb_grid(const std::string& path, const std::string& grid_name);

}  // namespace clbdpt
