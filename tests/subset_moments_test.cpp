// Subset moments (cl/kernels/render.cl, RenderParams::subset_moments): a pass of full bdpt
// returns, per item, the sum of its contributions' squares c^2 and the same with each divided
// by W, the share of the path's MIS weights that a mix without inner connections keeps
// (cl/mis.h, mis_weight_and_outer_share). With balance weights, c = f / D_full and
// W = D_outer / D_full, so E_full[sum c^2 / W] = integral of f^2 / D_outer = E_outer[sum c^2]:
// full bdpt's passes estimate the mix's own second moment, and the strategy pilot takes from
// this what the mix's own sparse passes miss (run_strategy_pilot).
#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "test_scenes.h"

namespace clbdpt::test {
namespace {

// Per item of `passes` full passes: the sum of its contributions' squares and the same
// reweighted (RenderedItems::subset_moments).
struct ItemMoments {
    std::vector<double> own, outer;
};

ItemMoments subset_moments(const DeviceScene& scene, const RenderOptions& options, int passes) {
    Renderer renderer(test_device(), scene, options);
    const int items = scene.camera.width * scene.camera.height;
    ItemMoments m;
    for (int j = 0; j < passes; ++j) {
        PassSpec pass;
        pass.seed = pass.position_seed = options.seed;
        pass.sample_index = pass.position_sample_index = uint32_t(j);
        pass.subset_moments = true;
        const RenderedItems r = renderer.render_items(pass, 0, items);
        EXPECT_EQ(r.subset_moments.size(), size_t(items) * 2);
        EXPECT_TRUE(r.dropped_items.empty());
        for (int i = 0; i < items; ++i) {
            m.own.push_back(r.subset_moments[size_t(i) * 2]);
            m.outer.push_back(r.subset_moments[size_t(i) * 2 + 1]);
        }
    }
    return m;
}

// The mean of a[i] - b[i] and its standard error, from the spread of the differences.
struct Difference {
    double mean = 0, standard_error = 0;
};
Difference paired_difference(const std::vector<double>& a, const std::vector<double>& b) {
    double sum = 0, squares = 0;
    const double n = double(a.size());
    for (size_t i = 0; i < a.size(); ++i) {
        const double d = a[i] - b[i];
        sum += d;
        squares += d * d;
    }
    Difference d;
    d.mean = sum / n;
    d.standard_error = std::sqrt(std::max(0.0, squares / n - d.mean * d.mean) / (n - 1));
    return d;
}

// Full bdpt's moments reweighted for the mix without inner connections against that mix's own,
// 128 x 128 items, 32 passes. Both mixes run on the same seed, so their camera subpaths, light
// subpaths and light samples are the same and only the weights differ: the light seen directly,
// most of either moment, is the same in both and drops out of the paired differences.
// A pass of the mix itself has W = 1 for every contribution, and full bdpt's W <= 1.
// - The Cornell box: the two agree within 4.5 standard errors of the items' paired
//   differences (measured: 0.13), where what the reweighting adds is some 270 of them.
// - cornell-specular (glass and mirror: delta vertices in the weights' sums): the mix's own
//   moment has a heavy tail there, paths that it samples by s = 0 alone (seed 21: 20 of 2
//   million samples made twice the sum of the paired differences), so its mean is no check; the
//   reweighting must add a moment, significantly, and keep W <= 1.
TEST(SubsetMoments, FullBdptPredictsTheMixWithoutInnerConnections) {
    for (const char* name : {"cornell-box", "cornell-specular"}) {
        SCOPED_TRACE(name);
        const bool heavy_tail = std::string(name) == "cornell-specular";
        const Scene loaded = load_scene(scene_path(name));
        const DeviceScene scene = build_device_scene(loaded, 128, 128);
        const RenderOptions full = make_options(Integrator::Bdpt, loaded.render.max_depth, 21, SamplerKind::Sobol);
        RenderOptions outer = full;
        outer.inner_connections = false;
        const ItemMoments f = subset_moments(scene, full, 32), o = subset_moments(scene, outer, 32);
        long below = 0, differ = 0;
        for (size_t i = 0; i < f.own.size(); ++i) {
            below += f.outer[i] < f.own[i] * (1.0 - 1e-5);
            differ += std::fabs(o.outer[i] - o.own[i]) > 1e-5 * o.own[i];
        }
        EXPECT_EQ(below, 0) << "a share of the weights above 1";
        EXPECT_EQ(differ, 0) << "the mix's own weights are all outer";
        // What the mix adds to full bdpt's moment, predicted (full bdpt's reweighted) and
        // measured (its own passes); their difference is o.own - f.outer, item by item.
        const Difference added = paired_difference(f.outer, f.own), measured = paired_difference(o.own, f.own);
        const Difference miss = paired_difference(o.own, f.outer);
        EXPECT_GT(added.mean, 4.5 * added.standard_error) << "inner connections carry light here";
        if (heavy_tail) continue;
        const double z = std::fabs(miss.mean) / miss.standard_error;
        report_stat(std::string(name) + "/subset moments, full bdpt reweighted vs without inner connections", z, 4.5,
                    z <= 4.5);
        EXPECT_LE(z, 4.5) << "added to full bdpt's moment: predicted " << added.mean << " +- "
                          << added.standard_error << ", measured " << measured.mean << " +- "
                          << measured.standard_error << ", their difference +- " << miss.standard_error;
        EXPECT_GT(added.mean, 4.5 * miss.standard_error) << "the test could not tell a reweighting from none";
    }
}

}  // namespace
}  // namespace clbdpt::test
