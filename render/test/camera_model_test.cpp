// The camera model agrees with OpenCV's (cv::projectPoints), its inverse is exact, and the GL
// projection matrix puts a point on the pixel centre convention the ground truth uses.
#include <gtest/gtest.h>

#include <random>

#include <opencv2/calib3d.hpp>

#include "render/camera_model.hpp"
#include "render/ground_truth.hpp"
#include "render/lens_mesh.hpp"
#include "render/render_error.hpp"
#include "test_warehouse.hpp"

namespace shelfcross::render {
namespace {

TEST(CameraModel, DistortionEqualsOpenCvProjectPoints) {
  const CameraIntrinsics K;
  const cv::Matx33d Kcv(K.fx_px, 0, K.cx_px, 0, K.fy_px, K.cy_px, 0, 0, 1);
  const std::vector<double> D = {K.k1, K.k2, K.p1, K.p2, K.k3};
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(-0.6, 0.6);
  std::vector<cv::Point3d> pts;
  for (int i = 0; i < 200; ++i) pts.emplace_back(u(rng), u(rng) * 0.8, 1.0 + std::abs(u(rng)) * 3);
  std::vector<cv::Point2d> px;
  cv::projectPoints(pts, cv::Vec3d(0, 0, 0), cv::Vec3d(0, 0, 0), Kcv, D, px);
  for (size_t i = 0; i < pts.size(); ++i) {
    const Eigen::Vector2d mine = project_camera_point(K, {pts[i].x, pts[i].y, pts[i].z});
    EXPECT_NEAR(mine.x(), px[i].x, 1e-9);
    EXPECT_NEAR(mine.y(), px[i].y, 1e-9);
  }
}

TEST(CameraModel, UndistortInvertsDistort) {
  const CameraIntrinsics K;
  for (double x = -0.55; x <= 0.55; x += 0.05) {
    for (double y = -0.42; y <= 0.42; y += 0.06) {
      Eigen::Vector2d back;
      ASSERT_TRUE(undistort_normalized(K, distort_normalized(K, {x, y}), back));
      EXPECT_NEAR(back.x(), x, 1e-12);
      EXPECT_NEAR(back.y(), y, 1e-12);
    }
  }
}

TEST(CameraModel, GlProjectionHitsOpenCvPixelCentres) {
  // A point projecting to pixel centre (u, v) must land in the middle of GL window pixel
  // (u, v) (rows not flipped, see camera_model.hpp): x_win = u + 0.5, y_win = v + 0.5.
  const double fx = 900, fy = 880, cx = 470.3, cy = 350.8;
  const int W = 960, H = 720;
  const Eigen::Matrix4d P = gl_clip_from_camera(fx, fy, cx, cy, W, H, 0.05, 50.0);
  for (const auto& [u, v, Z] : {std::tuple{0.0, 0.0, 1.0}, {959.0, 719.0, 3.0}, {123.4, 567.8, 0.7}}) {
    const Eigen::Vector4d p_C((u - cx) / fx * Z, (v - cy) / fy * Z, Z, 1.0);
    const Eigen::Vector4d clip = P * p_C;
    const double x_win = (clip.x() / clip.w() + 1.0) * 0.5 * W;
    const double y_win = (clip.y() / clip.w() + 1.0) * 0.5 * H;
    EXPECT_NEAR(x_win, u + 0.5, 1e-9);
    EXPECT_NEAR(y_win, v + 0.5, 1e-9);
  }
  EXPECT_NEAR((P * Eigen::Vector4d(0, 0, 0.05, 1)).z() / 0.05, -1.0, 1e-12);
  EXPECT_NEAR((P * Eigen::Vector4d(0, 0, 50.0, 1)).z() / 50.0, 1.0, 1e-12);
}

TEST(CameraModel, ProjectorEqualsOpenCvForWorldPoints) {
  const Warehouse w = test::paper_test_shelf();
  const CameraIntrinsics K;
  const GroundTruthProjector gt(w, K);
  const Eigen::Isometry3d X_WC = test::camera_looking_forward({1.0, 0.2, 1.1}, 0.1, 0.05);
  const Eigen::Isometry3d X_CW = X_WC.inverse();
  cv::Mat rvec;
  cv::Matx33d R;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) R(i, j) = X_CW.linear()(i, j);
  cv::Rodrigues(cv::Mat(R), rvec);
  const Eigen::Vector3d t = X_CW.translation();
  const cv::Matx33d Kcv(K.fx_px, 0, K.cx_px, 0, K.fy_px, K.cy_px, 0, 0, 1);
  const std::vector<double> D = {K.k1, K.k2, K.p1, K.p2, K.k3};
  for (const auto& tag : gt.tags(X_WC)) {
    if (!tag.in_front) continue;
    std::vector<cv::Point2d> px;
    cv::projectPoints(std::vector<cv::Point3d>{{tag.p_W_m.x(), tag.p_W_m.y(), tag.p_W_m.z()}}, rvec,
                      cv::Vec3d(t.x(), t.y(), t.z()), Kcv, D, px);
    EXPECT_NEAR(tag.pixel.x, px[0].x, 1e-6);
    EXPECT_NEAR(tag.pixel.y, px[0].y, 1e-6);
  }
}

TEST(CameraModel, InvalidIntrinsicsAreRefused) {
  CameraIntrinsics K;
  K.fx_px = 0.0;
  EXPECT_THROW(make_lens_grids(K, 0.2), RenderError);
  K = CameraIntrinsics{};
  K.k1 = -2.0;  // folds over inside the image
  EXPECT_THROW(make_lens_grids(K, 0.2), RenderError);
}

}  // namespace
}  // namespace shelfcross::render
