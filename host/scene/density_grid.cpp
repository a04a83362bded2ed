#include "scene/density_grid.h"

#include <algorithm>

namespace clbdpt {

float DensityGrid::max_value() const {
    float m = 0.0f;
    for (float v : values) m = std::max(m, v);
    return m;
}

void place_grid_in_box(DensityGrid& grid, Vec3 lo, Vec3 hi, int padding) {
    for (int axis = 0; axis < 3; ++axis) {
        // g = (p - lo) / (hi - lo) * inner - 0.5 + padding, inner = the voxels inside the box.
        const float inner = float(grid.size[axis] - 2 * padding);
        const float scale = inner / (hi[axis] - lo[axis]);
        for (int j = 0; j < 3; ++j) grid.world_to_grid[axis][j] = j == axis ? scale : 0.0f;
        grid.world_to_grid[axis][3] = -lo[axis] * scale - 0.5f + float(padding);
    }
}

}  // namespace clbdpt
