// Ground-truth projector: visibility (front/back faces, behind the camera, image bounds,
// occlusion), aruco corner order, the camera mount, and refusal of bad warehouses.
#include <gtest/gtest.h>

#include "render/ground_truth.hpp"
#include "render/render_error.hpp"
#include "test_warehouse.hpp"

namespace shelfcross::render {
namespace {

int count_visible(const std::vector<TagProjection>& tags, bool front) {
  int n = 0;
  for (const auto& t : tags) n += (t.visible && t.front_face == front);
  return n;
}

TEST(GroundTruth, FrontalViewSeesAllFrontTagsAndNoBackTags) {
  const GroundTruthProjector gt(test::paper_test_shelf(), CameraIntrinsics{});
  const auto tags = gt.tags(test::camera_looking_forward({0.8, 0.0, 0.98}));
  ASSERT_EQ(tags.size(), 50u);  // 5 x 5 intersections, two faces
  EXPECT_EQ(count_visible(tags, true), 25);
  EXPECT_EQ(count_visible(tags, false), 0);
  for (const auto& t : tags) {
    if (!t.front_face) {
      EXPECT_FALSE(t.facing);
    }
  }
  // Column boundary 0 is the left edge as seen on approach: leftmost in the image.
  const auto find = [&](int i, int j) {
    for (const auto& t : tags)
      if (t.front_face && t.column_boundary == i && t.level_boundary == j) return t;
    ADD_FAILURE();
    return tags[0];
  };
  EXPECT_LT(find(0, 2).pixel.x, find(4, 2).pixel.x);
  EXPECT_GT(find(2, 0).pixel.y, find(2, 4).pixel.y);  // level 0 is lowest: largest v
  // Tag corners in aruco order as seen from the front.
  const auto t = find(1, 1);
  EXPECT_LT(t.corners[0].x, t.corners[1].x);
  EXPECT_LT(t.corners[0].y, t.corners[3].y);
  EXPECT_GT(t.corners[2].x, t.corners[3].x);
  EXPECT_NEAR(t.area_centroid.x, t.pixel.x, 0.2);  // near-frontal: centroid ~ centre
  EXPECT_NEAR(t.area_px2, std::pow(0.06 * 921.17 / (3.0 - 0.8 - 0.011), 2), 40.0);
}

TEST(GroundTruth, ViewFromBehindSeesBackTagsAndMirroredCornerOrder) {
  const GroundTruthProjector gt(test::paper_test_shelf(), CameraIntrinsics{});
  const Eigen::Isometry3d X_WC = test::camera_looking_forward({5.6, 0.0, 0.98}, M_PI);
  const auto tags = gt.tags(X_WC);
  EXPECT_EQ(count_visible(tags, true), 0);
  EXPECT_EQ(count_visible(tags, false), 25);
  for (const auto& m : gt.markers(X_WC)) {
    if (!m.visible) continue;
    EXPECT_FALSE(m.front_face);
    EXPECT_LT(m.corners[0].x, m.corners[1].x);  // TL left of TR as seen from behind
    EXPECT_LT(m.corners[1].y, m.corners[2].y);  // TR above BR
  }
}

TEST(GroundTruth, PointsBehindTheCameraDoNotProject) {
  const GroundTruthProjector gt(test::paper_test_shelf(), CameraIntrinsics{});
  const Eigen::Isometry3d X_WC = test::camera_looking_forward({0.8, 0.0, 0.98});
  EXPECT_FALSE(gt.project({0.0, 0.0, 1.0}, X_WC).has_value());
  // Far off-axis (beyond the lens model's footprint): refused, not folded into the image.
  EXPECT_FALSE(gt.project({0.9, 5.0, 1.0}, X_WC).has_value());
  const auto p = gt.project({3.0, 0.0, 0.98}, X_WC);
  ASSERT_TRUE(p.has_value());
  EXPECT_NEAR(p->x, CameraIntrinsics{}.cx_px, 1e-9);
  EXPECT_NEAR(p->y, CameraIntrinsics{}.cy_px, 1e-9);
  // Looking away from the shelf: nothing visible.
  for (const auto& t : gt.tags(test::camera_looking_forward({0.8, 0.0, 0.98}, M_PI)))
    EXPECT_FALSE(t.visible);
}

TEST(GroundTruth, PostInFrontOfAMarkerOccludesIt) {
  const Warehouse w = test::paper_test_shelf();
  const GroundTruthProjector gt(w, CameraIntrinsics{});
  // Box (level 2, column 3) front marker centre M; post i = 3 on the front face at x_S = 0.
  const ShelfSpec& s = w.shelves[0];
  const MarkerQuad* mq = nullptr;
  for (const auto& m : gt.layout().markers)
    if (m.level == 2 && m.column == 3 && m.front_face) mq = &m;
  ASSERT_NE(mq, nullptr);
  const Eigen::Vector3d M = mq->centre_W_m;
  const Eigen::Vector3d P = shelf_pose_W(s) * Eigen::Vector3d(0.0, post_y_S_m(s, 3), M.z());
  // A camera on the line from M through the post, 1.5 m out, looking at M.
  const Eigen::Vector3d C = M + (P - M).normalized() * 1.5;
  const double yaw = std::atan2(M.y() - C.y(), M.x() - C.x());
  const Eigen::Isometry3d X_WC = test::camera_looking_forward(C, yaw);
  EXPECT_TRUE(gt.occluded(M, C));
  for (const auto& m : gt.markers(X_WC)) {
    if (m.level == 2 && m.column == 3 && m.front_face) {
      EXPECT_TRUE(m.in_image);
      EXPECT_TRUE(m.facing);
      EXPECT_TRUE(m.occluded);
      EXPECT_FALSE(m.visible);
    }
  }
  // Straight in front of it, nothing is in the way.
  EXPECT_FALSE(gt.occluded(M, M + Eigen::Vector3d(-1.5, 0.0, 0.0)));
}

TEST(GroundTruth, CameraPoseFromBodyPoseAndMount) {
  Eigen::Isometry3d X_WB = Eigen::Isometry3d::Identity();
  X_WB.linear() = Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  X_WB.translation() = Eigen::Vector3d(1.0, 2.0, 1.5);
  CameraMount mount;
  mount.pitch_rad = 0.1;
  const Eigen::Isometry3d X_WC = camera_pose_W(X_WB, mount);
  // Optical axis z_C = body x tilted down by the mount pitch.
  const Eigen::Vector3d z_C_W = X_WC.linear().col(2);
  const Eigen::Vector3d expected =
      X_WB.linear() * Eigen::Vector3d(std::cos(0.1), 0.0, -std::sin(0.1));
  EXPECT_LT((z_C_W - expected).norm(), 1e-12);
  EXPECT_LT((X_WC.translation() - X_WB * mount.p_BC_B_m).norm(), 1e-12);
  // x_C is body right (-y_B) at zero roll.
  EXPECT_LT((X_WC.linear().col(0) - X_WB.linear() * Eigen::Vector3d(0, -1, 0)).norm(), 1e-12);
}

TEST(GroundTruth, BadWarehousesAreRefusedWithAReason) {
  Warehouse w = test::paper_test_shelf();
  w.aruco_dictionary = "DICT_9X9_7";
  EXPECT_THROW(GroundTruthProjector(w, CameraIntrinsics{}), RenderError);
  w = test::paper_test_shelf();
  w.shelves[0].boxes.push_back({5, 1, 1});
  try {
    GroundTruthProjector gt(w, CameraIntrinsics{});
    FAIL() << "no error";
  } catch (const RenderError& e) {
    EXPECT_NE(std::string(e.what()).find("outside the 4 x 4 grid"), std::string::npos) << e.what();
  }
  w = test::paper_test_shelf();
  w.shelves[0].boxes[0].marker_id = 50;  // DICT_4X4_50 has 0..49
  EXPECT_THROW(GroundTruthProjector(w, CameraIntrinsics{}), RenderError);
  w = test::paper_test_shelf();
  w.marker_size_m = 0.2;  // with its quiet zone larger than the 0.22 m box face
  EXPECT_THROW(GroundTruthProjector(w, CameraIntrinsics{}), RenderError);
}

}  // namespace
}  // namespace shelfcross::render
