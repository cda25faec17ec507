// The rolling shutter (render/rolling_shutter.hpp): a still camera's picture is the global
// shutter's bit for bit; a yawing camera's rows each show the world from their own instant, so
// the picture shears. For a pure yaw at rate omega over a readout T, row v (of `rows`) is exposed
// at tau = v / rows of the readout, when the camera's heading was omega T (1 - tau) short of its
// heading at the readout's end; near the image centre a turn by d psi moves the picture
// sideways by f_px d psi, so against the global-shutter picture at the readout's end row v sits
//   shift(v) = -f_px omega T (1 - v / rows)   pixels (+ yaw turns left: the picture moves right),
// and the picture shears by f_px omega T (v1 - v0) / rows between rows v0 and v1; top to bottom,
// shear_px ~= f_px * yaw_rate * readout.
#include <gtest/gtest.h>

#include <cmath>
#include <iostream>

#include <opencv2/imgproc.hpp>

#include "render/renderer.hpp"
#include "render/rolling_shutter.hpp"
#include "test_warehouse.hpp"

namespace shelfcross::render {
namespace {

RenderOptions options(double noise_stddev, double margin_px) {
  RenderOptions o;
  o.noise_stddev = noise_stddev;
  o.rolling_shutter_margin_px = margin_px;
  return o;
}

Renderer& rolling_renderer() {
  static Renderer r(test::paper_test_shelf(), CameraIntrinsics{}, options(2.0, 40.0));
  return r;
}

// The sideways shift (pixels, sub-pixel) that best matches `band` of picture a to the same band
// of picture b over the central columns: the least sum of absolute differences over integer
// shifts, refined by a parabola through its neighbours. a's content at column c + shift is b's
// at c.
double band_shift_px(const cv::Mat& a, const cv::Mat& b, int v0, int v1) {
  cv::Mat ga, gb;
  cv::cvtColor(a.rowRange(v0, v1), ga, cv::COLOR_BGR2GRAY);
  cv::cvtColor(b.rowRange(v0, v1), gb, cv::COLOR_BGR2GRAY);
  const int c0 = 300, c1 = 660, max_shift = 25;
  std::vector<double> sad;
  for (int d = -max_shift; d <= max_shift; ++d) {
    double s = 0.0;
    for (int v = 0; v < ga.rows; ++v)
      for (int c = c0; c < c1; ++c) s += std::abs(ga.at<std::uint8_t>(v, c + d) - gb.at<std::uint8_t>(v, c));
    sad.push_back(s);
  }
  std::size_t k = 1;
  for (std::size_t i = 1; i + 1 < sad.size(); ++i)
    if (sad[i] < sad[k]) k = i;
  const double l = sad[k - 1], m = sad[k], r = sad[k + 1];
  const double denom = l - 2.0 * m + r;
  const double frac = denom > 0.0 ? 0.5 * (l - r) / denom : 0.0;
  return static_cast<double>(k) - max_shift + frac;
}

TEST(RollingShutter, StillCameraGivesTheGlobalShutterPictureBitForBit) {
  Renderer& r = rolling_renderer();
  for (const Eigen::Isometry3d& X : {test::camera_looking_forward({0.8, 0.0, 0.98}),
                                     test::camera_looking_forward({2.2, 0.3, 0.7}, 0.3, 0.1)}) {
    cv::Mat global, rolling;
    r.render_into(X, 17, global);
    r.render_rolling_into(X, X, 17, rolling);
    ASSERT_EQ(global.size(), rolling.size());
    EXPECT_EQ(cv::norm(global, rolling, cv::NORM_INF), 0.0);
  }
}

TEST(RollingShutter, YawingCameraShearsByTheReadoutsTurn) {
  // Noise-free, so that the bands match on the picture alone.
  static Renderer r(test::paper_test_shelf(), CameraIntrinsics{}, options(0.0, 40.0));
  const CameraIntrinsics K;
  const double yaw_rate_radps = 0.5, readout_s = 0.02;
  const double psi_end = 0.05;
  const Eigen::Vector3d p_WC(1.3, 0.0, 0.98);
  const Eigen::Isometry3d X_end = test::camera_looking_forward(p_WC, psi_end);
  const Eigen::Isometry3d X_start = test::camera_looking_forward(p_WC, psi_end - yaw_rate_radps * readout_s);
  cv::Mat global, rolling;
  r.render_into(X_end, 0, global);
  r.render_rolling_into(X_start, X_end, 0, rolling);
  const double rows = K.height_px;
  const double full_px = K.fx_px * yaw_rate_radps * readout_s;  // 9.2 px for the default camera
  double top_shift = 0.0, bottom_shift = 0.0;
  for (int v0 : {40, 200, 360, 520, 660}) {
    const int v1 = v0 + 20;
    const double tau = 0.5 * (v0 + v1 - 1) / rows;
    const double expected = -full_px * (1.0 - tau);
    const double measured = band_shift_px(rolling, global, v0, v1);
    std::cout << "rows " << v0 << ".." << v1 << ": shift " << measured << " px, expected " << expected << "\n";
    EXPECT_NEAR(measured, expected, 0.75) << "rows " << v0 << ".." << v1;
    if (v0 == 40) top_shift = measured;
    if (v0 == 660) bottom_shift = measured;
  }
  // The shear between the two bands: f_px * yaw_rate * readout * (rows apart) / rows.
  EXPECT_NEAR(bottom_shift - top_shift, full_px * 620.0 / rows, 0.8);
}

TEST(RollingShutter, EachRowIsTheGlobalPictureOfItsInstant) {
  // Row v of the rolling picture against row v of a global picture rendered at the pose of its
  // instant: they differ only at edges, where a drawn edge moved within its chord tolerance
  // (each mesh is its own; a near-horizontal edge moving by a fraction of a pixel flips a run
  // of pixel centres): every differing pixel takes a colour that the global picture has within
  // one pixel of it, and few pixels of a row differ.
  static Renderer r(test::paper_test_shelf(), CameraIntrinsics{}, options(0.0, 40.0));
  const Eigen::Isometry3d X_start = test::camera_looking_forward({1.0, 0.2, 0.9}, -0.02, 0.05);
  const Eigen::Isometry3d X_end = test::camera_looking_forward({1.03, 0.18, 0.92}, 0.03, 0.03);
  cv::Mat rolling, global;
  r.render_rolling_into(X_start, X_end, 0, rolling);
  const int rows = rolling.rows;
  // (Rows 1 and 718: the first and last rows' neighbourhoods would reach out of the picture.)
  for (int v : {1, 5, 90, 250, 361, 500, 714, 718}) {
    r.render_into(interpolate_pose(X_start, X_end, static_cast<double>(v) / rows), 0, global);
    int differ = 0, off_edge = 0;
    for (int c = 0; c < rolling.cols; ++c) {
      const cv::Vec3b got = rolling.at<cv::Vec3b>(v, c);
      if (got == global.at<cv::Vec3b>(v, c)) continue;
      ++differ;
      bool near_edge = false;
      for (int dv = -1; dv <= 1; ++dv)
        for (int dc = -1; dc <= 1; ++dc) {
          const int vv = v + dv, cc = c + dc;
          if (vv >= 0 && vv < rows && cc >= 0 && cc < rolling.cols && global.at<cv::Vec3b>(vv, cc) == got)
            near_edge = true;
        }
      if (!near_edge) ++off_edge;
    }
    EXPECT_EQ(off_edge, 0) << "row " << v;
    EXPECT_LE(differ, rolling.cols / 20) << "row " << v;
  }
}

TEST(RollingShutter, MarginMustBeInRange) {
  EXPECT_THROW(Renderer(test::paper_test_shelf(), CameraIntrinsics{}, options(0.0, -1.0)), RenderError);
}

}  // namespace
}  // namespace shelfcross::render
