// The bytes that carry rendered items between processes (render/ under MPI): runs handed out
// by the leader, and the RenderedItems a device sends back, exactly (floats as their bits), so
// that the leader's film is the one a single process would add up.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "film/rendered_items.h"
#include "render/work_units.h"

namespace clbdpt {

std::vector<uint8_t> encode_runs(const std::vector<ItemRun>& runs);
std::vector<ItemRun> decode_runs(const std::vector<uint8_t>& bytes);

// A device's answer: its results, or the error it failed with.
std::vector<uint8_t> encode_results(const std::vector<RenderedItems>& results);
std::vector<uint8_t> encode_failure(const std::string& what);
// Throws clbdpt::Error with the remote error for a failure, and for a damaged message.
std::vector<RenderedItems> decode_results(const std::vector<uint8_t>& bytes);

// Whether a remote device's results are the runs it was asked for, on a film of `pixels`
// pixels: one result per run, or one per runs of consecutive passes that it joined
// (joinable_runs), with every splat inside the film. The film trusts what it adds.
bool results_match_runs(const std::vector<ItemRun>& runs, const std::vector<RenderedItems>& results, int pixels);

}  // namespace clbdpt
