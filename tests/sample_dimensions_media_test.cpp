// The table of sample draws with media (cl/sample_dimensions.h built with HAS_MEDIA): every
// segment of both subpaths has a distance draw of its own, beside the bounce's lobe and
// direction, and nothing shares a draw at any depth. (sample_dimensions_test.cpp checks the
// table without media; this file includes the header in a namespace of its own, so the two
// builds of its inline functions do not collide.)
#include <gtest/gtest.h>

#include <map>
#include <string>
#include <vector>

namespace {
int g_media_depth = 5;
}

namespace media_table {
#define MAX_DEPTH g_media_depth
#define HAS_MEDIA
#include "sample_dimensions.h"
}  // namespace media_table

namespace clbdpt::test {
namespace {

using namespace media_table;

struct Draws {
    std::string name;
    unsigned first = 0, count = 1;
};

// A camera subpath has max_depth + 1 scattering vertices, each reached by a segment (its
// distance draw) and all but the last sampling a direction; a light subpath has max_depth.
std::vector<Draws> decisions_with_media() {
    const int d = g_media_depth;
    std::vector<Draws> v = {{"pixel", SAMPLE_DRAW_PIXEL},
                            {"lens", SAMPLE_DRAW_LENS},
                            {"trace light subpath", SAMPLE_DRAW_TRACE_LIGHT_SUBPATH},
                            {"light and its point", SAMPLE_DRAW_LIGHT_POSITION},
                            {"light direction", SAMPLE_DRAW_LIGHT_DIRECTION}};
    for (int k = 0; k <= d; ++k) {
        v.push_back({"camera bounce " + std::to_string(k), sample_draw_camera_bounce(k), 2});
        v.push_back({"camera segment " + std::to_string(k), sample_draw_camera_bounce(k) + SAMPLE_DRAW_BOUNCE_DISTANCE});
    }
    for (int k = 0; k < d; ++k) {
        v.push_back({"light bounce " + std::to_string(k), sample_draw_light_bounce(k), 2});
        v.push_back({"light segment " + std::to_string(k), sample_draw_light_bounce(k) + SAMPLE_DRAW_BOUNCE_DISTANCE});
    }
    for (int s = 1; s <= d + 1; ++s) v.push_back({"lens for s=" + std::to_string(s), sample_draw_lens_connection(s)});
    for (int t = 2; t <= d + 1; ++t)
        v.push_back({"light for t=" + std::to_string(t), sample_draw_light_connection(t), SAMPLE_DRAWS_PER_LIGHT_CONNECTION});
    return v;
}

TEST(SampleDimensions, WithMediaEverySegmentHasItsOwnDistanceDraw) {
    for (g_media_depth = 0; g_media_depth <= 16; ++g_media_depth) {
        std::map<unsigned, std::string> owner;
        for (const Draws& d : decisions_with_media()) {
            for (unsigned k = d.first; k < d.first + d.count; ++k) {
                EXPECT_LT(k, unsigned(SAMPLE_DRAW_COUNT)) << d.name << " at max depth " << g_media_depth;
                auto [it, fresh] = owner.emplace(k, d.name);
                EXPECT_TRUE(fresh) << it->second << " and " << d.name << " share draw " << k << " at max depth "
                                   << g_media_depth;
            }
        }
    }
    g_media_depth = 5;
}

}  // namespace
}  // namespace clbdpt::test
