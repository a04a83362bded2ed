// Closest-hit queries against the flattened BVH on the host, for the few hundred probe rays of
// set-up decisions (choose_automatic_view). Rendering traces on the device (cl/bvh.h).
#pragma once

#include <vector>

#include "shared/types.h"
#include "util/vec3.h"

namespace clbdpt {

// Distance along the unit direction d from o to the nearest triangle, or INFINITY.
float closest_hit_distance(const std::vector<BvhNode>& nodes, const std::vector<Triangle>& triangles, Vec3 o, Vec3 d);

}  // namespace clbdpt
