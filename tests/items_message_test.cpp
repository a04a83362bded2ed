// The bytes that carry rendered items between MPI processes (mpi/items_message.h): a round
// trip gives back every value bit for bit, a remote failure comes back as its error, and a
// truncated or padded message is refused rather than read past its end.
#include <gtest/gtest.h>

#include <cstring>
#include <limits>

#include "mpi/items_message.h"
#include "util/error.h"

namespace clbdpt {
namespace {

RenderedItems sample_items() {
    RenderedItems r;
    r.sample_index = 7;
    r.first_item = 4096;
    r.item_count = 3;
    r.run_pixel = 11;
    r.run_length = 2;
    r.camera = {1.0f, -0.0f, std::numeric_limits<float>::denorm_min(), 3e38f, 0.1f, 2.5f, 0, 1, 2};
    r.dropped_items = {1};
    r.splats = {{0.25f, 0.5f, 1e-30f, 5}, {1, 2, 3, 9}};
    r.strategy_slots = 42;
    r.strategy_stride = 7;
    r.strategy_splats = {{3, {0.5f, 0.25f, 0.125f, 5}}};
    r.counts.samples = 3;
    r.counts.rays = 1234567890123ull;
    r.counts.dropped_samples = 1;
    DroppedSample d;
    d.x = 1;
    d.y = 2;
    d.sample = 7;
    d.s = 2;
    d.t = 3;
    r.counts.first_dropped = {d};
    return r;
}

TEST(ItemsMessage, RoundTripIsExact) {
    const std::vector<RenderedItems> sent = {sample_items(), RenderedItems()};
    const std::vector<RenderedItems> got = decode_results(encode_results(sent));
    ASSERT_EQ(got.size(), 2u);
    const RenderedItems &a = sent[0], &b = got[0];
    EXPECT_EQ(b.sample_index, a.sample_index);
    EXPECT_EQ(b.first_item, a.first_item);
    EXPECT_EQ(b.item_count, a.item_count);
    EXPECT_EQ(b.run_pixel, a.run_pixel);
    EXPECT_EQ(b.run_length, a.run_length);
    ASSERT_EQ(b.camera.size(), a.camera.size());
    EXPECT_EQ(std::memcmp(b.camera.data(), a.camera.data(), a.camera.size() * sizeof(float)), 0);
    EXPECT_EQ(b.dropped_items, a.dropped_items);
    ASSERT_EQ(b.splats.size(), 2u);
    EXPECT_EQ(std::memcmp(b.splats.data(), a.splats.data(), 2 * sizeof(SplatRecord)), 0);
    ASSERT_EQ(b.strategy_splats.size(), 1u);
    EXPECT_EQ(b.strategy_splats[0].slot, 3);
    EXPECT_EQ(b.strategy_slots, 42);
    EXPECT_EQ(b.strategy_stride, 7);
    EXPECT_EQ(b.counts.rays, a.counts.rays);
    ASSERT_EQ(b.counts.first_dropped.size(), 1u);
    EXPECT_EQ(b.counts.first_dropped[0].t, 3);
    EXPECT_EQ(got[1].item_count, 0);

    const std::vector<ItemRun> runs = {{3, 0, 4096}, {4, 8192, 100}};
    const std::vector<ItemRun> back = decode_runs(encode_runs(runs));
    ASSERT_EQ(back.size(), 2u);
    EXPECT_EQ(back[1].pass, 4u);
    EXPECT_EQ(back[1].first_item, 8192);
    EXPECT_EQ(back[1].item_count, 100);
    EXPECT_TRUE(decode_runs(encode_runs({})).empty());
}

TEST(ItemsMessage, FailureAndDamageAreErrors) {
    try {
        decode_results(encode_failure("pthread: launch failed"));
        FAIL() << "a failure message must throw";
    } catch (const Error& e) {
        EXPECT_STREQ(e.what(), "pthread: launch failed");
    }
    const std::vector<uint8_t> whole = encode_results({sample_items()});
    for (size_t cut : {size_t(0), size_t(1), whole.size() / 2, whole.size() - 1}) {
        const std::vector<uint8_t> truncated(whole.begin(), whole.begin() + long(cut));
        EXPECT_THROW(decode_results(truncated), Error) << cut;
    }
    std::vector<uint8_t> padded = whole;
    padded.push_back(0);
    EXPECT_THROW(decode_results(padded), Error);
    std::vector<uint8_t> runs = encode_runs({{1, 2, 3}});
    runs.pop_back();
    EXPECT_THROW(decode_runs(runs), Error);
}

// The leader accepts results run by run or joined across consecutive passes (as DeviceWorker
// renders them, and as CI's MPI run first showed), and nothing else.
TEST(ItemsMessage, ResultsMustBeTheRunsAskedFor) {
    constexpr int kPixels = 100;
    // The last 40 items of pass 3, then passes 4 and 5 whole.
    const std::vector<ItemRun> runs = {{3, 60, 40}, {4, 0, 100}, {5, 0, 100}};
    auto result = [](uint32_t pass, int first_item, int item_count, int run_length) {
        RenderedItems r;
        r.sample_index = pass;
        r.first_item = first_item;
        r.item_count = item_count;
        r.run_length = run_length;
        return r;
    };
    const RenderedItems r3 = result(3, 60, 40, 0), r4 = result(4, 0, 100, 0), r5 = result(5, 0, 100, 0);
    EXPECT_TRUE(results_match_runs(runs, {r3, r4, r5}, kPixels));
    EXPECT_TRUE(results_match_runs(runs, {result(3, 60, 240, kPixels)}, kPixels));
    EXPECT_TRUE(results_match_runs(runs, {result(3, 60, 140, kPixels), r5}, kPixels));
    EXPECT_TRUE(results_match_runs(runs, {r3, result(4, 0, 200, kPixels)}, kPixels));

    EXPECT_FALSE(results_match_runs(runs, {r3, r4}, kPixels));                             // one missing
    EXPECT_FALSE(results_match_runs(runs, {r3, r4, r5, r5}, kPixels));                     // one too many
    EXPECT_FALSE(results_match_runs(runs, {r3, r5, r4}, kPixels));                         // out of order
    EXPECT_FALSE(results_match_runs(runs, {result(3, 60, 239, kPixels)}, kPixels));        // short by an item
    EXPECT_FALSE(results_match_runs(runs, {result(3, 60, 241, kPixels)}, kPixels));        // past the runs
    EXPECT_FALSE(results_match_runs(runs, {result(3, 60, 240, 0)}, kPixels));              // not marked joined
    EXPECT_FALSE(results_match_runs(runs, {result(3, 60, 240, 50)}, kPixels));             // another film
    EXPECT_FALSE(results_match_runs(runs, {result(3, 60, 40, kPixels), r4, r5}, kPixels));  // a "join" of one
    RenderedItems shifted = result(3, 60, 240, kPixels);
    shifted.run_pixel = 1;
    EXPECT_FALSE(results_match_runs(runs, {shifted}, kPixels));
    // Passes 4 and 6 do not follow one another: they cannot be one result.
    EXPECT_FALSE(results_match_runs({{4, 0, 100}, {6, 0, 100}}, {result(4, 0, 200, kPixels)}, kPixels));
    RenderedItems outside = r4;
    outside.splats = {{1, 1, 1, kPixels}};
    EXPECT_FALSE(results_match_runs(runs, {r3, outside, r5}, kPixels));
    RenderedItems bad_slot = r4;
    bad_slot.strategy_slots = 2;
    bad_slot.strategy_splats = {{2, {1, 1, 1, 0}}};
    EXPECT_FALSE(results_match_runs(runs, {r3, bad_slot, r5}, kPixels));
}

}  // namespace
}  // namespace clbdpt
