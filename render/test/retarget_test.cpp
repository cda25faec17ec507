// Re-targeting one renderer (one EGL context) at a run's dispersed warehouse.
#include <gtest/gtest.h>
#include <opencv2/core.hpp>

#include "render/renderer.hpp"
#include "test_warehouse.hpp"

namespace shelfcross::render {
namespace {

TEST(RendererRetarget, AnotherWarehouseChangesThePictureAndBackRestoresItsBytes) {
  RenderOptions opts;
  opts.noise_stddev = 3.0;
  Renderer r(test::paper_test_shelf(), CameraIntrinsics{}, opts);
  Eigen::Isometry3d X_WC = Eigen::Isometry3d::Identity();
  X_WC.linear() = rotation_body_from_camera(0.0);
  X_WC.translation() = Eigen::Vector3d(1.5, 0.0, 1.0);
  const cv::Mat before = r.render(X_WC, 1);
  Warehouse moved = test::paper_test_shelf();
  moved.shelves[0].boxes = {{2, 2, 9}};
  moved.lighting.ambient *= 0.7;
  r.set_warehouse(moved);
  EXPECT_GT(cv::norm(before, r.render(X_WC, 1), cv::NORM_INF), 0.0);
  r.set_warehouse(test::paper_test_shelf());
  EXPECT_EQ(cv::norm(before, r.render(X_WC, 1), cv::NORM_INF), 0.0);
  // The same warehouse again is free and changes nothing.
  r.set_warehouse(test::paper_test_shelf());
  EXPECT_EQ(cv::norm(before, r.render(X_WC, 1), cv::NORM_INF), 0.0);
}

}  // namespace
}  // namespace shelfcross::render
