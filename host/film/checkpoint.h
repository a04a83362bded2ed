// A render's progress on disk (--checkpoint, --resume): the film's sums exactly as they stand
// after `film.spp` complete passes, with what the render needs to go on where it stopped and
// to refuse going on with anything else:
//   - a hash of the scene as the kernels see it (render/scene_fingerprint.h) and the settings
//     that change the image as one line of key=value pairs; a resume under a different scene
//     or settings is refused, naming what differs;
//   - the strategy mix the render used (an automatic choice is not made again on resume).
// Passes are numbered from 0 and their random numbers depend on the pass number only, so a
// render resumed on the same device adds the same passes to the same sums in the same order
// and ends bit for bit where an uninterrupted one would.
//
// File layout (little-endian, as the host writes it): the 8 bytes "CLBDPTCK", a header of
// fixed-size fields, the settings line, the sums as doubles, and a 64-bit FNV-1a hash of everything before it, so a
// truncated or damaged file is recognised rather than resumed from.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "film/film.h"
#include "shared/types.h"

namespace clbdpt {

struct CheckpointInfo {
    uint64_t scene_fingerprint = 0;
    std::string settings;  // "key=value key=value ..."
    // The strategy mix the passes used (render/features.h's Integrator as an int).
    int32_t integrator = 0;
    float light_subpaths = 1.0f;
    int32_t inner_connections = 1;
    int32_t roulette_light_from = RUSSIAN_ROULETTE_OFF;  // Russian roulette in light subpaths
};

struct Checkpoint {
    CheckpointInfo info;
    Film film;
};

// Writes atomically and durably (temporary file, fsync, rename). Throws Error naming the path.
void write_checkpoint(const std::string& path, const CheckpointInfo& info, const Film& film);

// Throws Error naming the path if it cannot be read or is not a whole clbdpt checkpoint.
Checkpoint read_checkpoint(const std::string& path);

// The key=value pairs of two settings lines that differ, as "key: a -> b" (empty: none).
std::vector<std::string> settings_differences(const std::string& from, const std::string& to);

}  // namespace clbdpt
