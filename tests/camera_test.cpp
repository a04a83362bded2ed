// cl/camera.h through cl/kernels/camera_test.cl, for a pinhole (built without HAS_THIN_LENS) and
// a thin-lens camera (with it), landscape and portrait films:
//  - round trip: a ray generated through raster r, a point on it, camera_sample_wi back from that
//    point: the raster is r again (pinhole: any point; thin lens: points on the focus plane), and
//    in general the ray camera_generate_ray makes for the returned raster and lens sample starts
//    at the returned lens point and runs through the point;
//  - camera_sample_wi's We and pdf_w against camera_we / camera_pdf_we and the formulas
//    We = 1/(A lens_area cos^4), pdf_w = d^2/(cos lens_area), pdf_dir = 1/(A cos^3);
//  - normalisation: the integral of We cos(theta) over lens x directions is 1, also per block of
//    the film (its share of the film area), and pdf_dir integrates to 1 over the film's
//    directions.
#include <gtest/gtest.h>

#include "kernel_test_util.h"

namespace clbdpt::test {
namespace {

struct CameraCase {
    const char* name;
    CameraDesc desc;
    int width, height;
};

std::vector<CameraCase> cameras(bool thin) {
    CameraDesc d;
    d.eye = {1, 2, -6};
    d.target = {0, 0.5f, 0};
    d.up = {0, 1, 0};
    d.fov_degrees = 40;
    d.lens_radius = thin ? 0.2f : 0.0f;
    d.focus_distance = 5.5f;
    CameraDesc wide = d;
    wide.fov_degrees = 75;
    wide.eye = {-3, 1, 2};
    wide.target = {0.5f, 0.7f, -0.3f};
    wide.focus_distance = 2.5f;
    if (thin) return {{"thin lens 320x200", d, 320, 200}, {"thin lens wide 120x200", wide, 120, 200}};
    return {{"pinhole 320x200", d, 320, 200}, {"pinhole wide 120x200", wide, 120, 200}};
}

std::vector<std::string> defines(bool thin) { return thin ? std::vector<std::string>{"HAS_THIN_LENS"} : std::vector<std::string>{}; }

struct RoundTrip {
    D3 o, d, p, lens, wi, o2, d2;
    double t, we, dist, pdf_w, we_eval, pdf_pos, pdf_dir;
    double rx, ry, rx_we, ry_we;
};

std::vector<RoundTrip> round_trip(const Camera& cam, bool thin, const std::vector<cl_float4>& in,
                                  const std::vector<cl_float4>& depth) {
    cl::Kernel k = test_kernel("kernels/camera_test.cl", defines(thin), "camera_roundtrip_test");
    cl::Buffer a = upload(in), b = upload(depth), out = output_buffer<cl_float4>(9 * in.size());
    k.setArg(0, cam);
    k.setArg(1, a);
    k.setArg(2, b);
    k.setArg(3, out);
    launch(k, in.size());
    std::vector<cl_float4> r = download<cl_float4>(out, 9 * in.size());
    std::vector<RoundTrip> res(in.size());
    for (size_t i = 0; i < in.size(); ++i) {
        const cl_float4* x = &r[9 * i];
        RoundTrip& t = res[i];
        t.o = d3(x[0]);
        t.t = x[0].s[3];
        t.d = d3(x[1]);
        t.p = d3(x[2]);
        t.we = x[2].s[3];
        t.lens = d3(x[3]);
        t.dist = x[3].s[3];
        t.wi = d3(x[4]);
        t.pdf_w = x[4].s[3];
        t.rx = x[5].s[0];
        t.ry = x[5].s[1];
        t.we_eval = x[5].s[2];
        t.pdf_pos = x[5].s[3];
        t.pdf_dir = x[6].s[0];
        t.rx_we = x[6].s[1];
        t.ry_we = x[6].s[2];
        t.o2 = d3(x[7]);
        t.d2 = d3(x[8]);
    }
    return res;
}

// Raster positions agree to 1e-3 px: a float raster position of a 320-px film carries ~2e-5 px
// of rounding and the ray through a point 30 units away ~1e-7 rad of direction error, ~5e-5 px.
constexpr double kRasterTolerance = 1e-3;
// We, pdf_w, pdf_dir against the formulas: ~10 float operations, 1e-4 relative.
constexpr double kDensityTolerance = 1e-4;

void check_round_trip(bool thin) {
    std::mt19937_64 rng(thin ? 2 : 1);
    std::uniform_real_distribution<double> uni(0, 1);
    for (const CameraCase& c : cameras(thin)) {
        Camera cam = make_camera(c.desc, c.width, c.height);
        const D3 eye = d3(cam.eye), fwd = d3(cam.forward);
        const double film_area = double(cam.film_area), lens_area = double(cam.lens_area);
        const size_t n = 4096;
        std::vector<cl_float4> in(n), depth(n);
        std::vector<bool> on_focus_plane(n);
        for (size_t i = 0; i < n; ++i) {
            // Rasters away from the film's edge (a point exactly on it may round outside).
            double rx = 0.01 + uni(rng) * (c.width - 0.02), ry = 0.01 + uni(rng) * (c.height - 0.02);
            on_focus_plane[i] = thin && i % 2 == 0;
            double z = on_focus_plane[i] ? double(cam.focus_distance) : 0.5 + 30 * uni(rng) * uni(rng);
            in[i] = {{float(rx), float(ry), float(uni(rng)), float(uni(rng))}};
            depth[i] = {{float(z), float(uni(rng)), float(uni(rng)), 0}};
        }
        std::vector<RoundTrip> r = round_trip(cam, thin, in, depth);
        double worst_raster = 0;
        size_t seen = 0;
        for (size_t i = 0; i < n; ++i) {
            const RoundTrip& x = r[i];
            std::string what = std::string(c.name) + " item " + std::to_string(i);
            // Off the focus plane, another lens point may see the point outside the film.
            if (thin && !on_focus_plane[i] && x.we == 0) continue;
            ASSERT_GT(x.we, 0) << what;
            ++seen;
            // The lens point lies on the lens disk (the eye for a pinhole).
            D3 lens_off = x.lens - eye;
            ASSERT_LT(std::fabs(dot(lens_off, fwd)), 1e-5 * (1 + length(eye))) << what;
            ASSERT_LE(length(lens_off), double(cam.lens_radius) * (1 + 1e-5) + 1e-5 * length(eye)) << what;
            // The point's raster is the one it was generated through, where it must be.
            if (!thin || on_focus_plane[i]) {
                double e = std::hypot(x.rx - in[i].s[0], x.ry - in[i].s[1]);
                worst_raster = std::max(worst_raster, e);
                ASSERT_LT(e, kRasterTolerance) << what;
            }
            // camera_generate_ray for the returned raster and lens sample is the connection.
            ASSERT_LT(length(x.o2 - x.lens), 1e-5 * (1 + length(eye))) << what;
            ASSERT_LT(length(x.d2 + x.wi), 1e-5) << what;
            // Densities and importance.
            D3 to_lens = x.lens - x.p;
            double d2 = dot(to_lens, to_lens);
            double cos_t = dot(-x.wi, fwd);
            ASSERT_LE(rel_diff(x.dist, std::sqrt(d2)), 1e-5) << what;
            ASSERT_LT(length(x.wi - normalize(to_lens)), 1e-5) << what;
            ASSERT_LE(rel_diff(x.we, x.we_eval), 1e-6) << what << ": camera_we";
            ASSERT_EQ(x.rx, x.rx_we) << what;
            ASSERT_EQ(x.ry, x.ry_we) << what;
            ASSERT_LE(rel_diff(x.we, 1 / (film_area * lens_area * std::pow(cos_t, 4))), kDensityTolerance) << what;
            ASSERT_LE(rel_diff(x.pdf_w, d2 / (cos_t * lens_area)), kDensityTolerance) << what;
            ASSERT_LE(rel_diff(x.pdf_pos, 1 / lens_area), 1e-6) << what;
            ASSERT_LE(rel_diff(x.pdf_dir, 1 / (film_area * std::pow(cos_t, 3))), kDensityTolerance) << what;
        }
        EXPECT_GT(seen, n * 3 / 4) << c.name;
        ::testing::Test::RecordProperty(std::string(c.name) + " worst raster error (px)", std::to_string(worst_raster));
    }
}

TEST(Camera, PinholeRoundTrip) { check_round_trip(false); }
TEST(Camera, ThinLensRoundTrip) { check_round_trip(true); }

// The integral of We cos(theta) over lens area x solid angle is 1 (pbrt-v3 16.1.1: with
// pdf_dir = 1/(A cos^3) and dw = cos^3 dA_film on the z = 1 plane, the integral is
// (1/A) * A = 1), estimated with 2^20 directions uniform in a cone covering the film (and lens
// points uniform on the lens); each of 4 x 4 film blocks gets 1/16 of it (the raster mapping is
// area-preserving), and the integral of pdf_dir over the same directions is 1. Every estimate
// must lie within kSigmas standard errors (the per-block test adds 16 comparisons: a correct
// camera fails one with probability ~1e-5).
void check_normalisation(bool thin) {
    for (const CameraCase& c : cameras(thin)) {
        Camera cam = make_camera(c.desc, c.width, c.height);
        double tw = cam.tan_half_width, th = cam.tan_half_height;
        double corner = std::atan(std::hypot(tw, th));
        if (thin) corner = std::atan((cam.focus_distance * std::hypot(tw, th) + cam.lens_radius) / cam.focus_distance);
        float cos_max = float(std::cos(corner + 0.02));
        const size_t n = 1 << 20;
        cl::Kernel k = test_kernel("kernels/camera_test.cl", defines(thin), "camera_normalisation_test");
        cl::Buffer out = output_buffer<cl_float4>(n);
        k.setArg(0, cam);
        k.setArg(1, cos_max);
        k.setArg(2, cl_uint(thin ? 77 : 78));
        k.setArg(3, out);
        launch(k, n);
        std::vector<cl_float4> r = download<cl_float4>(out, n);
        MeanEstimate we = mean_estimate(n, [&](size_t i) { return double(r[i].s[0]); });
        MeanEstimate pdf = mean_estimate(n, [&](size_t i) { return double(r[i].s[1]); });
        EXPECT_NEAR(we.mean, 1.0, kSigmas * we.std_error) << c.name << ": integral of We cos";
        EXPECT_NEAR(pdf.mean, 1.0, kSigmas * pdf.std_error) << c.name << ": integral of pdf_dir";
        EXPECT_LT(we.std_error, 0.01) << c.name << ": the estimate is too noisy to mean anything";
        for (int by = 0; by < 4; ++by)
            for (int bx = 0; bx < 4; ++bx) {
                MeanEstimate block = mean_estimate(n, [&](size_t i) {
                    if (r[i].s[0] == 0) return 0.0;
                    int x = std::min(3, int(r[i].s[2] * 4 / c.width)), y = std::min(3, int(r[i].s[3] * 4 / c.height));
                    return x == bx && y == by ? double(r[i].s[0]) : 0.0;
                });
                EXPECT_NEAR(block.mean, 1.0 / 16, kSigmas * block.std_error)
                    << c.name << ": block (" << bx << ", " << by << ")";
            }
    }
}

TEST(Camera, PinholeImportanceIsNormalised) { check_normalisation(false); }
TEST(Camera, ThinLensImportanceIsNormalised) { check_normalisation(true); }

}  // namespace
}  // namespace clbdpt::test
