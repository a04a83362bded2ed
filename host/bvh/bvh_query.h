// Closest-hit queries against the flattened BVH on the host, for the few hundred probe rays of
// set-up decisions (choose_automatic_view; the media around the camera and the lights).
// Rendering traces on the device (cl/bvh.h).
#pragma once

#include <vector>

#include "shared/types.h"
#include "util/vec3.h"

namespace clbdpt {

// Distance along the unit direction d from o to the nearest triangle, or INFINITY.
float closest_hit_distance(const std::vector<BvhNode>& nodes, const std::vector<Triangle>& triangles, Vec3 o, Vec3 d);

// The nearest triangle (index in BVH order) hit along the unit direction d from o, or -1;
// *distance receives its distance, or INFINITY.
int closest_hit_triangle(const std::vector<BvhNode>& nodes, const std::vector<Triangle>& triangles, Vec3 o, Vec3 d,
                         float* distance);

}  // namespace clbdpt
