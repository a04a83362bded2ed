// The strategy pilot's sparse grid (render_item_pixel with a stride and its inverse,
// render_pixel_item; render/strategy_pilot.h),
// without OpenCL: which pixels a sparse pass visits, and which renders get a pilot.
#include <gtest/gtest.h>

#include <set>

#include "render/strategy_pilot.h"
#include "shared/types.h"

namespace clbdpt {
namespace {

// Stride 1 is the film in row order; a stride k > 1 visits one pixel of each k x k block, blocks
// cut at the film's right and bottom edges included, and no pixel twice; render_pixel_item maps
// each visited pixel back to its item and every other pixel to -1.
TEST(SparseGrid, OnePixelOfEachBlock) {
    for (int i = 0; i < 37 * 23; ++i) ASSERT_EQ(render_item_pixel(i, 37, 23, 1), i);
    for (int stride : {2, 3, 5, 8}) {
        const int width = 37, height = 23, columns = (width + stride - 1) / stride;
        const int items = render_item_count(width, height, stride);
        ASSERT_EQ(items, columns * ((height + stride - 1) / stride));
        std::set<int> pixels;
        for (int i = 0; i < items; ++i) {
            const int p = render_item_pixel(i, width, height, stride);
            const int x = p % width, y = p / width;
            ASSERT_LT(y, height) << "stride " << stride << " item " << i;
            EXPECT_EQ(x / stride, i % columns) << "stride " << stride << " item " << i;
            EXPECT_EQ(y / stride, i / columns) << "stride " << stride << " item " << i;
            pixels.insert(p);
            EXPECT_EQ(render_pixel_item(p, width, height, stride), i) << "stride " << stride << " item " << i;
        }
        EXPECT_EQ(int(pixels.size()), items) << "stride " << stride;
        // Every other pixel maps to no item (the pilot drops the light splats that land there).
        for (int p = 0; p < width * height; ++p) {
            if (pixels.count(p)) continue;
            ASSERT_EQ(render_pixel_item(p, width, height, stride), -1) << "stride " << stride << " pixel " << p;
        }
    }
}

// The pixel's place in its block varies from block to block, so the grid does not line up with
// a scene's axis-aligned edges (a light's outline): over a 256 x 256 film at stride 5, every
// column and every row of the blocks is used, each by roughly a fifth of the blocks (within 30%:
// 2 704 blocks, about 540 per offset, a binomial standard deviation of 21).
TEST(SparseGrid, PlaceInTheBlockVaries) {
    const int width = 256, height = 256, stride = 5;
    const int items = render_item_count(width, height, stride);
    int column_count[5] = {}, row_count[5] = {};
    for (int i = 0; i < items; ++i) {
        const int p = render_item_pixel(i, width, height, stride);
        if ((p % width) / stride == width / stride || (p / width) / stride == height / stride) continue;  // cut blocks
        ++column_count[(p % width) % stride];
        ++row_count[(p / width) % stride];
    }
    const int full_blocks = (width / stride) * (height / stride);
    for (int k = 0; k < stride; ++k) {
        EXPECT_NEAR(column_count[k], full_blocks / stride, 0.3 * full_blocks / stride) << "column offset " << k;
        EXPECT_NEAR(row_count[k], full_blocks / stride, 0.3 * full_blocks / stride) << "row offset " << k;
    }
}

// The pilot runs when a grid of at least 2048 pixels (or the whole film) costs at most a tenth
// of the render's samples: a 128 x 128 film of 64 spp gets one (a coarser grid than a long
// render's), 4 spp are too few for a 32 x 32 film or a 128 x 128 one.
TEST(SparseGrid, WhichRendersGetAPilot) {
    EXPECT_TRUE(strategy_pilot_fits(256, 256, 64));
    EXPECT_TRUE(strategy_pilot_fits(128, 128, 64));
    EXPECT_TRUE(strategy_pilot_fits(32, 32, 160));
    EXPECT_FALSE(strategy_pilot_fits(32, 32, 4));
    EXPECT_FALSE(strategy_pilot_fits(128, 128, 4));
    EXPECT_FALSE(strategy_pilot_fits(64, 64, 1));
    EXPECT_FALSE(strategy_pilot_fits(256, 256, 0));
}

}  // namespace
}  // namespace clbdpt
