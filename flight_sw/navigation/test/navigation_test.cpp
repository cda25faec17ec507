// Navigation: PnP pose of a drawn cell (eq. 5-8) at known poses; the optimal viewpoint.

#include <cmath>

#include <gtest/gtest.h>

#include "flight_sw/navigation/navigation.hpp"
#include "flight_sw/perception/shelf_view.hpp"
#include "flight_sw/test/shelf_drawing.hpp"
#include "shelfcross/rotation.hpp"

namespace shelfcross::flight_sw {
namespace {

constexpr double kDeg = deg_to_rad(1.0);  // one degree

struct Case {
  double dy_m, dz_m, yaw_deg, pitch_deg, roll_deg, mount_pitch_deg;
};

// Draws the paper shelf, finds the four corner tags of cell (2, 3) seen from body pose
// (1.5 m in front of the cell face + the case's offsets and attitude) and checks the PnP body
// pose in the cell frame against the truth within tol_m and tol_deg.
void check_cell_pose(const std::vector<Case>& cases, double tol_m, double tol_deg) {
  testing::Scene scene;
  scene.shelves = {testing::paper_shelf({3.0, 0.0, 0.0})};
  const testing::DrawnShelf& shelf = scene.shelves[0];
  FlightConfig config;
  const CellIndex cell{2, 3};  // level 2, column 3 (a narrow 34 cm column)
  // Cell centre in S: midway between posts 2, 3 and beams 1, 2.
  const Eigen::Vector3d centre_S(0.0, 0.5 * (testing::post_y(shelf, 2) + testing::post_y(shelf, 3)),
                                 0.5 * (testing::beam_z(shelf, 1) + testing::beam_z(shelf, 2)));
  const Eigen::Vector3d centre_W = testing::shelf_to_world(shelf, centre_S);
  for (const Case& c : cases) {
    CameraMount mount;
    mount.pitch_rad = c.mount_pitch_deg * kDeg;
    // Body 1.5 m in front of the cell's face (x_K = -1.5), offset laterally and vertically.
    const Eigen::Vector3d p_KB(-1.5, c.dy_m, c.dz_m);
    const Eigen::Vector3d p_WB = centre_W + p_KB;  // shelf yaw 0: K axes = W axes
    const Eigen::Isometry3d X_WC = testing::camera_pose_W(p_WB, c.yaw_deg * kDeg, c.pitch_deg * kDeg,
                                                          c.roll_deg * kDeg, mount);
    const cv::Mat img = testing::Drawer(config.camera, true).draw(scene, X_WC);
    // At 1.5 m the shelf does not fit the view: take the detected tag nearest to where each
    // corner tag projects (the detector's centroid is what is being tested).
    TagDetector det(config.perception);
    std::vector<TagBlob> tags;
    det.detect(img, cv::Rect(0, 0, img.cols, img.rows), tags);
    const auto obj = cell_corner_tags_K(config.shelf, cell);
    std::vector<cv::Point2d> px;
    for (const cv::Point3d& o : obj) {
      const Eigen::Vector3d p_C = X_WC.inverse() * (centre_W + Eigen::Vector3d(o.x, o.y, o.z));
      std::vector<cv::Point2d> proj;
      cv::projectPoints(std::vector<cv::Point3d>{{p_C.x(), p_C.y(), p_C.z()}}, cv::Vec3d(0, 0, 0),
                        cv::Vec3d(0, 0, 0),
                        cv::Matx33d(config.camera.fx_px, 0, config.camera.cx_px, 0, config.camera.fy_px,
                                    config.camera.cy_px, 0, 0, 1),
                        cv::Vec<double, 5>(config.camera.k1, config.camera.k2, config.camera.p1,
                                           config.camera.p2, config.camera.k3),
                        proj);
      const TagBlob* best = nullptr;
      for (const TagBlob& t : tags) {
        if (!best || cv::norm(t.centre_px - proj[0]) < cv::norm(best->centre_px - proj[0])) best = &t;
      }
      ASSERT_TRUE(best);
      ASSERT_LT(cv::norm(best->centre_px - proj[0]), 1.0);
      px.push_back(best->centre_px);
    }
    const auto pose = estimate_pose({obj.begin(), obj.end()}, px, config.camera, mount);
    ASSERT_TRUE(pose);
    SCOPED_TRACE("case dy " + std::to_string(c.dy_m) + " yaw " + std::to_string(c.yaw_deg));
    EXPECT_LT((pose->p_FB_m() - p_KB).norm(), tol_m) << pose->p_FB_m().transpose();
    EXPECT_NEAR(pose->yaw_rad, c.yaw_deg * kDeg, tol_deg * kDeg);
    EXPECT_NEAR(pose->pitch_rad, c.pitch_deg * kDeg, tol_deg * kDeg);
    EXPECT_NEAR(pose->roll_rad, c.roll_deg * kDeg, tol_deg * kDeg);
    EXPECT_LT(pose->reprojection_rms_px, 0.5);
  }
}

TEST(CellPose, PnPWithin1cmAndHalfDegreeAt1p5m) {
  check_cell_pose({{0.0, 0.0, 0.0, 0.0, 0.0, 0.0},
                   {0.15, 0.0, 0.0, 0.0, 0.0, 0.0},
                   {0.05, -0.05, -8.0, 3.0, -2.0, 0.0},
                   {0.0, 0.1, 3.0, -2.0, 4.0, 10.0}},
                  0.01, 0.5);
}

// Four tag centroids a third of a metre apart at 1.5 m constrain the heading weakly: a 0.2 px
// centroid error moves it by about 0.3 deg. This pose is measured at 1.7 cm and 0.63 deg
// with the drawn images: the bound documents it rather than hides it.
TEST(CellPose, PnPOffsetAndTurnedWithin2cmAnd1Degree) {
  check_cell_pose({{-0.1, 0.08, 6.0, 0.0, 0.0, 0.0}}, 0.02, 1.0);
}

TEST(CellGeometry, CornerTagsAndOpening) {
  KnownShelf s;  // columns 0.34 0.48 0.34 0.48, rows 0.34
  const auto q = cell_corner_tags_K(s, {1, 2});
  // Bottom-left as seen on approach: +y (left), -z.
  EXPECT_NEAR(q[0].y, 0.24, 1e-12);
  EXPECT_NEAR(q[0].z, -0.17, 1e-12);
  EXPECT_NEAR(q[2].y, -0.24, 1e-12);
  EXPECT_NEAR(q[2].z, 0.17, 1e-12);
  EXPECT_NEAR(q[1].x, -s.tag_offset_m, 1e-12);
  // Column 2 centre: grid width 1.64, column 2 spans y = 0.48 .. 0.00.
  EXPECT_NEAR(cell_centre_G(s, {1, 2}).y(), 0.24, 1e-12);
  EXPECT_NEAR(cell_centre_G(s, {1, 2}).z(), -0.68 + 0.17, 1e-12);
  EXPECT_NEAR(cell_opening_m(s, {1, 2}).x(), 0.46, 1e-12);
  EXPECT_NEAR(cell_opening_m(s, {1, 2}).y(), 0.32, 1e-12);
}

TEST(OptimalViewpoint, WholeGridJustFitsTheView) {
  FlightConfig config;
  const Eigen::Vector3d p_GB = optimal_viewpoint_G(config.shelf, config.camera, config.mount, 0.0);
  // Camera at the viewpoint, heading 0: the outer tag edges project inside the image and
  // the binding extent (height here: 1.42 m over the 43 deg view) touches an edge.
  const Eigen::Vector3d p_GC = p_GB + config.mount.p_BC_B_m;
  const double range = -p_GC.x() - config.shelf.tag_offset_m;
  const double half_h = 0.5 * (1.36 + 0.06);
  const double tan_v = std::min(config.camera.cy_px, config.camera.height_px - 1 - config.camera.cy_px) /
                       config.camera.fy_px;
  EXPECT_NEAR(range, half_h / tan_v, 1e-9);
  EXPECT_GT(range, 0.5 * (1.64 + 0.06) / (config.camera.cx_px / config.camera.fx_px));
  EXPECT_NEAR(p_GC.y(), 0.0, 1e-12);
  EXPECT_NEAR(p_GC.z(), 0.0, 1e-12);
}

}  // namespace
}  // namespace shelfcross::flight_sw
