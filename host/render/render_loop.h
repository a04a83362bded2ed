// The whole render on one or more devices: passes (one sample of every pixel) are handed out
// one at a time to whichever device is free, each device adds into its own film, and the
// films are merged in device order at the end. With a time budget, devices start passes until
// it is spent (whole passes only).
#pragma once

#include <vector>

#include "render/renderer.h"

namespace clbdpt {

// renderers: one per device, built with the same scene and options. stats: totals over all
// devices, seconds = wall time.
Film render_image(const std::vector<Renderer*>& renderers, const RenderOptions& options, RenderStats* stats);

}  // namespace clbdpt
