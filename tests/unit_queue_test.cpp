// The render loop's sharing of work units (render/unit_queue.h, render/render_loop.h) with fake
// devices of unequal speed, without OpenCL: whatever device renders which units, whenever they
// finish, fail or are taken over, the film equals one device's bit for bit, because results are
// added in unit order. Fake results are floats of widely varied magnitudes with splats scattered
// over the image, so any change in the order of additions changes the sums' last bits.
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <cstring>
#include <thread>

#include "film/rendered_items.h"
#include "render/render_loop.h"
#include "render/work_units.h"
#include "util/error.h"

namespace clbdpt {
namespace {

constexpr int kWidth = 128, kHeight = 96;  // 12288 items: three units per pass

uint32_t hash(uint32_t a, uint32_t b) {
    uint32_t h = a * 0x9E3779B1u ^ (b + 0x7F4A7C15u) * 0x85EBCA77u;
    h ^= h >> 15;
    h *= 0x2C1B3C6Du;
    h ^= h >> 13;
    return h;
}

float value(uint32_t a, uint32_t b) {
    const uint32_t h = hash(a, b);
    // 24 significant bits over scales 2^-32 .. 2^31: sums of such floats round in double
    // precision, so their order shows in the last bits.
    return std::ldexp(float(h & 0xFFFFFF) / 16777216.0f, int(h >> 26) - 32);
}

// What a device would return for items [first, first + count) of pass `pass`.
RenderedItems fake_items(uint32_t pass, int first, int count) {
    RenderedItems r;
    r.sample_index = pass;
    r.first_item = first;
    r.item_count = count;
    r.camera.resize(size_t(count) * 3);
    for (int i = 0; i < count; ++i) {
        const uint32_t item = uint32_t(first + i);
        for (int c = 0; c < 3; ++c) r.camera[size_t(i) * 3 + c] = value(pass * 3 + uint32_t(c), item);
        for (uint32_t k = 0; k < hash(pass, item) % 3; ++k)
            r.splats.push_back({value(item, pass + k), value(item + 1, pass), value(item + 2, pass),
                                int(hash(item, pass * 7 + k) % uint32_t(kWidth * kHeight))});
    }
    r.counts.samples = uint64_t(count);
    r.counts.rays = uint64_t(count) * 2;
    return r;
}

// One device, whole passes in order: what every render below must equal.
Film reference(int spp) {
    Film film(kWidth, kHeight);
    for (int pass = 0; pass < spp; ++pass) {
        add_to_film(film, fake_items(uint32_t(pass), 0, kWidth * kHeight));
        ++film.spp;
    }
    return film;
}

void expect_same_film(const Film& a, const Film& b) {
    ASSERT_EQ(a.spp, b.spp);
    ASSERT_EQ(a.camera_sum.size(), b.camera_sum.size());
    EXPECT_EQ(std::memcmp(a.camera_sum.data(), b.camera_sum.data(), a.camera_sum.size() * sizeof(double)), 0);
    EXPECT_EQ(std::memcmp(a.light_sum.data(), b.light_sum.data(), a.light_sum.size() * sizeof(double)), 0);
}

// A device rendering `items_per_second`, waiting in small steps so that a take-over can stop
// it; it fails (throws, as a driver error would) on its run number fail_on_run (from 1).
class FakeDevice : public UnitWorker {
public:
    FakeDevice(std::string name, double items_per_second, int fail_on_run = -1)
        : name_(std::move(name)), items_per_second_(items_per_second), fail_on_run_(fail_on_run) {}
    std::string name() const override { return name_; }
    std::vector<RenderedItems> render(const std::vector<ItemRun>& runs,
                                      const std::function<bool()>& cancelled) override {
        if (++runs_taken_ == fail_on_run_) throw Error("injected failure");
        std::vector<RenderedItems> out;
        for (const ItemRun& run : runs) {
            const auto end = std::chrono::steady_clock::now() +
                             std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                                 std::chrono::duration<double>(run.item_count / items_per_second_));
            while (std::chrono::steady_clock::now() < end) {
                if (cancelled && cancelled()) return out;
                std::this_thread::sleep_for(std::chrono::microseconds(200));
            }
            out.push_back(fake_items(run.pass, run.first_item, run.item_count));
        }
        return out;
    }

private:
    std::string name_;
    double items_per_second_;
    int fail_on_run_;
    std::atomic<int> runs_taken_{0};
};

RenderOptions options_for(int spp, double time_budget = 0) {
    RenderOptions o;
    o.spp = spp;
    o.time_budget = time_budget;
    return o;
}

TEST(WorkUnits, RunsCoverUnitsPassByPass) {
    const WorkUnits units(10000, 3, 4096);  // bands of 4096, 4096 and 1808 items
    EXPECT_EQ(units.units_per_pass, 3);
    EXPECT_EQ(units.items_in(0, 6), 20000);
    const std::vector<ItemRun> runs = units.runs(2, 7);
    ASSERT_EQ(runs.size(), 3u);
    EXPECT_EQ(runs[0].pass, 3u);
    EXPECT_EQ(runs[0].first_item, 8192);
    EXPECT_EQ(runs[0].item_count, 1808);
    EXPECT_EQ(runs[1].pass, 4u);
    EXPECT_EQ(runs[1].first_item, 0);
    EXPECT_EQ(runs[1].item_count, 10000);
    EXPECT_EQ(runs[2].pass, 5u);
    EXPECT_EQ(runs[2].item_count, 4096);
    EXPECT_EQ(units.pass_end(4), 6);
    EXPECT_EQ(units.pass_end(6), 6);
}

// Devices of speeds 1 : 4 : 10 render one image: the film is one device's bit for bit, every
// sample counts once, and the faster devices take the larger shares.
TEST(UnitQueue, UnequalDevicesGiveOneDevicesFilm) {
    FakeDevice slow("slow", 1e5), middle("middle", 4e5), fast("fast", 1e6);
    RenderStats stats;
    const int spp = 40;
    const Film film = render_image(std::vector<UnitWorker*>{&slow, &middle, &fast}, kWidth, kHeight,
                                   options_for(spp), &stats);
    expect_same_film(film, reference(spp));
    EXPECT_EQ(stats.samples, uint64_t(spp) * kWidth * kHeight);
    EXPECT_EQ(stats.rays, 2 * stats.samples);
    ASSERT_EQ(stats.device_shares.size(), 3u);
    uint64_t added = 0;
    for (const RenderStats::DeviceShare& d : stats.device_shares) added += d.samples;
    EXPECT_EQ(added, stats.samples);
    EXPECT_LT(stats.device_shares[0].samples, stats.device_shares[1].samples);
    EXPECT_LT(stats.device_shares[1].samples, stats.device_shares[2].samples);
}

// A device 200x slower than the other holds its first unit for 0.25 s, longer than the whole
// render takes the fast one; the fast device takes that unit over at the end, the slow copy is
// told to stop and counted as wasted, and the render does not wait for it.
TEST(UnitQueue, FastDeviceTakesOverASlowDevicesLastUnit) {
    FakeDevice slow("slow", 4096 / 0.25), fast("fast", 2e6);  // 0.25 s and 2 ms per unit
    RenderStats stats;
    const int spp = 4;
    const auto start = std::chrono::steady_clock::now();
    const Film film = render_image(std::vector<UnitWorker*>{&slow, &fast}, kWidth, kHeight, options_for(spp), &stats);
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    expect_same_film(film, reference(spp));
    EXPECT_EQ(stats.device_shares[0].samples, 0u);
    EXPECT_EQ(stats.device_shares[0].wasted_samples, 4096u);
    EXPECT_EQ(stats.device_shares[1].samples, uint64_t(spp) * kWidth * kHeight);
    EXPECT_LT(seconds, 0.2) << "the render waited for the slow device's unit";
}

// A device that fails on its second run leaves; its run goes to the others, the image is
// unchanged, and the failure is reported. The last device failing fails the render.
TEST(UnitQueue, FailingDeviceLosesNothing) {
    FakeDevice failing("failing", 5e5, 2), steady("steady", 5e5);
    RenderStats stats;
    const int spp = 12;
    std::vector<std::string> dropped;
    RenderSchedule schedule;
    schedule.device_dropped = [&](const std::string& what) { dropped.push_back(what); };
    const Film film =
        render_image(std::vector<UnitWorker*>{&failing, &steady}, kWidth, kHeight, options_for(spp), &stats, schedule);
    expect_same_film(film, reference(spp));
    ASSERT_EQ(dropped.size(), 1u);
    EXPECT_EQ(dropped[0], "failing: injected failure");
    EXPECT_EQ(stats.samples, uint64_t(spp) * kWidth * kHeight);

    FakeDevice alone("alone", 5e5, 3);
    EXPECT_THROW(render_image(std::vector<UnitWorker*>{&alone}, kWidth, kHeight, options_for(spp), &stats), Error);
}

// A stop request and a time budget end on a pass boundary, and every checkpoint snapshot holds
// whole passes: each equals one device's film of its spp.
TEST(UnitQueue, StopsAndSnapshotsEndOnPassBoundaries) {
    FakeDevice a("a", 3e5), b("b", 1e6);
    std::atomic<bool> stop{false};
    std::vector<Film> snapshots;
    RenderSchedule schedule;
    schedule.checkpoint_seconds = 0.05;
    schedule.checkpoint = [&](const Film& f) {
        snapshots.push_back(f);
        if (snapshots.size() == 2) stop = true;
    };
    schedule.stop_requested = [&] { return stop.load(); };
    RenderStats stats;
    const Film film =
        render_image(std::vector<UnitWorker*>{&a, &b}, kWidth, kHeight, options_for(10000), &stats, schedule);
    ASSERT_GE(snapshots.size(), 2u);
    EXPECT_LT(film.spp, 10000);
    expect_same_film(film, reference(film.spp));
    for (const Film& s : snapshots) expect_same_film(s, reference(s.spp));

    const Film timed = render_image(std::vector<UnitWorker*>{&a, &b}, kWidth, kHeight, options_for(0, 0.1), &stats);
    EXPECT_GE(timed.spp, 1);
    expect_same_film(timed, reference(timed.spp));
}

// A resumed render starts from the checkpoint's film and pass: the same film as without a break.
TEST(UnitQueue, ResumedRenderEqualsAnUninterruptedOne) {
    FakeDevice a("a", 3e5), b("b", 1e6);
    const Film first = reference(5);
    RenderSchedule schedule;
    schedule.resume = &first;
    const Film film = render_image(std::vector<UnitWorker*>{&a, &b}, kWidth, kHeight, options_for(9), nullptr, schedule);
    expect_same_film(film, reference(9));
}

}  // namespace
}  // namespace clbdpt
