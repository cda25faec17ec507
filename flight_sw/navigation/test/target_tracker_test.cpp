// The target tracker's identity check on drawn frames: a tracked box that slid one
// column or one level is not the target, and the crossing is refused on it; the true cell seen
// the same way is confirmed; tags of a shelf behind, seen through the cells, change nothing.

#include <algorithm>
#include <cmath>

#include <gtest/gtest.h>

#include "flight_sw/guidance/crossing_law.hpp"
#include "flight_sw/navigation/navigation.hpp"
#include "flight_sw/navigation/target_tracker.hpp"
#include "flight_sw/perception/shelf_view.hpp"
#include "flight_sw/test/shelf_drawing.hpp"

namespace shelfcross::flight_sw {
namespace {

// The default scenario's ten boxes (scenarios/paper_test_shelf.yaml): empty cells L1C3, L2C2,
// L3C1, L3C3, L4C2, L4C4.
const std::vector<testing::DrawnBox> kBoxes{{1, 1, 3},  {1, 2, 7},  {1, 4, 12}, {2, 1, 18}, {2, 3, 21},
                                            {2, 4, 25}, {3, 2, 30}, {3, 4, 34}, {4, 1, 41}, {4, 3, 47}};

Inventory inventory_of(const std::vector<testing::DrawnBox>& boxes) {
  Inventory inv(0, 4, 4, 1);
  std::vector<std::pair<CellIndex, int>> seen;
  for (const auto& b : boxes) seen.push_back({CellIndex{b.level, b.column}, b.id});
  inv.observe(seen, true);
  return inv;
}

// The gate's input of a calm, still hover (line hold measured with no wander, no lateral
// command or turn for 10 s): `identity` and the height above the cell as given.
CrossingGateInput calm_still_gate(CellIdentity identity, std::optional<double> height_above_cell_m) {
  CrossingGateInput gate;
  gate.line_hold = {true, 0.0, 0.0};
  gate.still_for_s = 10.0;
  gate.heading_still_for_s = 10.0;
  gate.identity = identity;
  gate.height_above_cell_m = height_above_cell_m;
  return gate;
}

// A pose 0.6 m in front of the cell centre, level, facing it (camera 4.5 cm ahead of the body).
PoseEstimate centred_pose() {
  PoseEstimate pose;
  pose.X_FB.translation() = Eigen::Vector3d(-0.6, 0.0, 0.0);
  pose.X_FC.translation() = Eigen::Vector3d(-0.555, 0.0, 0.0);
  return pose;
}

// What the tracker measured: the camera `range_m` in front of the physical cell `seen` (body on
// its normal, heading 0), the box on that cell's four corner tags; the pose is solved as if the
// box were `believed`. Returns the identity verdict and the crossing gate's answer for a pose
// otherwise fit to cross (fresh, still).
struct Outcome {
  IdentityCheck check;
  std::optional<std::string> refusal;
};

Outcome judge(const testing::Scene& scene, CellIndex seen, CellIndex believed, double range_m) {
  const testing::DrawnShelf& shelf = scene.shelves[0];
  FlightConfig config;
  const Eigen::Vector3d centre_S(0.0, 0.5 * (testing::post_y(shelf, seen.column - 1) + testing::post_y(shelf, seen.column)),
                                 0.5 * (testing::beam_z(shelf, seen.level - 1) + testing::beam_z(shelf, seen.level)));
  const Eigen::Vector3d p_WB = testing::shelf_to_world(shelf, centre_S) + Eigen::Vector3d(-range_m, 0.0, 0.0);
  const Eigen::Isometry3d X_WC = testing::camera_pose_W(p_WB, 0.0);
  const cv::Mat img = testing::Drawer(config.camera, true).draw(scene, X_WC);
  TagDetector detector(config.perception);
  std::vector<TagBlob> tags;
  detector.detect(img, cv::Rect(0, 0, img.cols, img.rows), tags);
  MarkerDetector markers_detector(config.shelf.aruco_dictionary);
  std::vector<MarkerSighting> markers;
  markers_detector.detect(img, markers);
  // The seen cell's corner tags in the picture: the detected tag nearest each projected corner.
  const Eigen::Isometry3d X_CW = X_WC.inverse();
  std::vector<cv::Point2d> corners;
  for (const cv::Point3d& o : cell_corner_tags_K(config.shelf, seen)) {
    const Eigen::Vector3d p_C = X_CW * testing::shelf_to_world(shelf, centre_S + Eigen::Vector3d(o.x, o.y, o.z));
    std::vector<cv::Point2d> proj;
    cv::projectPoints(std::vector<cv::Point3d>{{p_C.x(), p_C.y(), p_C.z()}}, cv::Vec3d(0, 0, 0), cv::Vec3d(0, 0, 0),
                      cv::Matx33d(config.camera.fx_px, 0, config.camera.cx_px, 0, config.camera.fy_px,
                                  config.camera.cy_px, 0, 0, 1),
                      cv::Vec<double, 5>(config.camera.k1, config.camera.k2, config.camera.p1, config.camera.p2,
                                         config.camera.k3),
                      proj);
    const TagBlob* best = nullptr;
    for (const TagBlob& t : tags) {
      if (!best || cv::norm(t.centre_px - proj[0]) < cv::norm(best->centre_px - proj[0])) best = &t;
    }
    EXPECT_NE(best, nullptr);
    EXPECT_LT(cv::norm(best->centre_px - proj[0]), 3.0) << "corner tag not detected";
    corners.push_back(best->centre_px);
  }
  const auto obj = cell_corner_tags_K(config.shelf, believed);
  const auto pose = estimate_pose({obj.begin(), obj.end()}, corners, config.camera, config.mount);
  EXPECT_TRUE(pose.has_value());
  Outcome out;
  out.check = check_cell_identity(believed, *pose, tags, markers, inventory_of(shelf.boxes), config);
  // Hovering: the state height agrees with the picture.
  const CrossingGateInput gate = calm_still_gate(out.check.verdict, pose->p_FB_m().z());
  out.refusal = crossing_refusal(config, believed, *pose, gate);
  return out;
}

testing::Scene paper_scene() {
  testing::Scene scene;
  scene.shelves = {testing::paper_shelf({3.0, 0.0, 0.0})};
  scene.shelves[0].boxes = kBoxes;
  return scene;
}

// The true cell: confirmed from 1.2 m out (a neighbour's marker or an edge in view); at 0.8 m
// the neighbours' markers have left the view and no edge is in it, so a picture alone cannot
// tell (Unknown: the identity then rests on continuity from the full view), but it never
// contradicts the truth.
TEST(CellIdentity, TrueCellIsConfirmedAndMayBeCrossed) {
  const testing::Scene scene = paper_scene();
  for (const CellIndex cell : {CellIndex{2, 2}, CellIndex{3, 3}, CellIndex{1, 3}}) {
    const Outcome close = judge(scene, cell, cell, 0.8);
    EXPECT_NE(close.check.verdict, CellIdentity::Contradicted) << close.check.why;
    EXPECT_EQ(close.check.nodes_missing, 0);
    for (double range : {1.2, 1.8}) {
      const Outcome o = judge(scene, cell, cell, range);
      EXPECT_EQ(o.check.verdict, CellIdentity::Confirmed)
          << "L" << cell.level << "C" << cell.column << " at " << range << " m: " << o.check.why;
      EXPECT_EQ(o.check.markers_disagreeing, 0);
      EXPECT_EQ(o.check.beyond_occupied, 0);
      EXPECT_FALSE(o.refusal.has_value()) << *o.refusal;
    }
  }
}

// The tracked box slid one column: the target is L2 C2 (wide, empty), the box sits on L2 C3
// (narrow, box 21), or the target is L3 C3 (narrow, empty) and the box sits on L3 C4 (wide).
TEST(CellIdentity, BoxSlidOneColumnIsRefused) {
  const testing::Scene scene = paper_scene();
  for (const auto& [seen, believed] : {std::pair{CellIndex{2, 3}, CellIndex{2, 2}}, std::pair{CellIndex{3, 4}, CellIndex{3, 3}},
                                        std::pair{CellIndex{3, 2}, CellIndex{3, 1}}, std::pair{CellIndex{1, 2}, CellIndex{1, 3}}}) {
    for (double range : {0.8, 1.2, 1.8}) {
      const Outcome o = judge(scene, seen, believed, range);
      EXPECT_EQ(o.check.verdict, CellIdentity::Contradicted)
          << "seen L" << seen.level << "C" << seen.column << " believed C" << believed.column << " at " << range
          << " m: " << o.check.why;
      ASSERT_TRUE(o.refusal.has_value());
      EXPECT_NE(o.refusal->find("not identified"), std::string::npos) << *o.refusal;
    }
  }
}

// The tracked box slid one level: the target is L2 C2, the box sits on L3 C2 (box 30), or the
// target is L4 C4 and the box sits on L3 C4 (box 34).
TEST(CellIdentity, BoxSlidOneLevelIsRefused) {
  const testing::Scene scene = paper_scene();
  for (const auto& [seen, believed] : {std::pair{CellIndex{3, 2}, CellIndex{2, 2}}, std::pair{CellIndex{3, 4}, CellIndex{4, 4}},
                                        std::pair{CellIndex{2, 3}, CellIndex{1, 3}}}) {
    for (double range : {0.8, 1.2, 1.8}) {
      const Outcome o = judge(scene, seen, believed, range);
      EXPECT_EQ(o.check.verdict, CellIdentity::Contradicted)
          << "seen L" << seen.level << "C" << seen.column << " believed L" << believed.level << " at " << range
          << " m: " << o.check.why;
      ASSERT_TRUE(o.refusal.has_value());
      EXPECT_NE(o.refusal->find("not identified"), std::string::npos) << *o.refusal;
    }
  }
}

// A uniform grid (every column and level alike, so a slid box gives a pose as good as the
// target's) and no box next to the target: only the edges can tell. Close in, with no edge in
// view, the check must say Unknown (never Confirmed); farther out the edge contradicts.
TEST(CellIdentity, UniformGridWithoutMarkersIsNeverConfirmedWrongly) {
  testing::Scene scene;
  testing::DrawnShelf s = testing::paper_shelf({3.0, 0.0, 0.0});
  s.geometry.column_pitch_m = {0.40, 0.40, 0.40, 0.40};
  s.geometry.row_pitch_m = {0.40, 0.40, 0.40, 0.40};
  s.boxes = {};
  scene.shelves = {s};
  FlightConfig config;
  config.shelf = s.geometry;
  for (double range : {0.7, 1.2, 2.0, 2.4}) {
    // Box on L2 C3, believed L2 C2. Out to 2.0 m neither edge is in view (Unknown); at 2.4 m
    // the grid's right edge and the place beyond its left edge are.
    const testing::DrawnShelf& shelf = scene.shelves[0];
    const CellIndex seen{2, 3}, believed{2, 2};
    const Eigen::Vector3d centre_S(0.0, 0.5 * (testing::post_y(shelf, 2) + testing::post_y(shelf, 3)),
                                   0.5 * (testing::beam_z(shelf, 1) + testing::beam_z(shelf, 2)));
    const Eigen::Isometry3d X_WC =
        testing::camera_pose_W(testing::shelf_to_world(shelf, centre_S) + Eigen::Vector3d(-range, 0, 0), 0.0);
    const cv::Mat img = testing::Drawer(config.camera, true).draw(scene, X_WC);
    TagDetector detector(config.perception);
    std::vector<TagBlob> tags;
    detector.detect(img, cv::Rect(0, 0, img.cols, img.rows), tags);
    ShelfView view;
    // The corner tags: the four detected tags nearest the image centre quadrants' true corners.
    const Eigen::Isometry3d X_CW = X_WC.inverse();
    std::vector<cv::Point2d> corners;
    for (const cv::Point3d& o : cell_corner_tags_K(config.shelf, seen)) {
      const Eigen::Vector3d p_C = X_CW * testing::shelf_to_world(shelf, centre_S + Eigen::Vector3d(o.x, o.y, o.z));
      const cv::Point2d guess(config.camera.cx_px + config.camera.fx_px * p_C.x() / p_C.z(),
                              config.camera.cy_px + config.camera.fy_px * p_C.y() / p_C.z());
      const TagBlob* best = &tags.front();
      for (const TagBlob& t : tags) {
        if (cv::norm(t.centre_px - guess) < cv::norm(best->centre_px - guess)) best = &t;
      }
      corners.push_back(best->centre_px);
    }
    const auto obj = cell_corner_tags_K(config.shelf, believed);
    const auto pose = estimate_pose({obj.begin(), obj.end()}, corners, config.camera, config.mount);
    ASSERT_TRUE(pose.has_value());
    const IdentityCheck check = check_cell_identity(believed, *pose, tags, {}, Inventory(0, 4, 4, 1), config);
    EXPECT_NE(check.verdict, CellIdentity::Confirmed) << range << " m: " << check.why;
    if (range >= 2.4) {
      EXPECT_EQ(check.verdict, CellIdentity::Contradicted) << check.why;
    }
    const CrossingGateInput gate = calm_still_gate(check.verdict, pose->p_FB_m().z());
    EXPECT_TRUE(crossing_refusal(config, believed, *pose, gate).has_value());
  }
}

// A shelf of the same make 1.2 m behind, moved sideways by half a column: its tags, seen through
// the empty cells and beside the front shelf, neither confirm a wrong cell nor contradict the
// true one.
TEST(CellIdentity, ShelfBehindChangesNoVerdict) {
  testing::Scene scene = paper_scene();
  testing::DrawnShelf behind = testing::paper_shelf({4.2, 0.2, 0.0});
  behind.boxes = {{1, 2, 40}, {3, 3, 44}};
  scene.shelves.push_back(behind);
  for (double range : {1.2, 1.8}) {
    const Outcome truth = judge(scene, {2, 2}, {2, 2}, range);
    EXPECT_EQ(truth.check.verdict, CellIdentity::Confirmed) << range << " m: " << truth.check.why;
    const Outcome slid = judge(scene, {2, 3}, {2, 2}, range);
    EXPECT_EQ(slid.check.verdict, CellIdentity::Contradicted) << range << " m: " << slid.check.why;
    EXPECT_TRUE(slid.refusal.has_value());
  }
}

TEST(CrossingGate, RefusesAnUnidentifiedCellEvenPerfectlyCentred) {
  FlightConfig config;
  const PoseEstimate pose = centred_pose();
  CrossingGateInput gate = calm_still_gate(CellIdentity::Unknown, 0.0);
  for (CellIdentity id : {CellIdentity::Unknown, CellIdentity::Contradicted}) {
    gate.identity = id;
    const auto r = crossing_refusal(config, {2, 2}, pose, gate);
    ASSERT_TRUE(r.has_value());
    EXPECT_NE(r->find("not identified"), std::string::npos);
  }
  gate.identity = CellIdentity::Confirmed;
  EXPECT_FALSE(crossing_refusal(config, {2, 2}, pose, gate).has_value());
  gate.pose_age_s = 1.0;
  EXPECT_EQ(crossing_refusal(config, {2, 2}, pose, gate).value_or(""), "last pose too old");
}

// Air that has just left the line no room (a gust window) is not trusted on the next quiet
// window: centred, identified and still, with a calm forecast, the crossing is refused until
// the calm has lasted as long as the blind crossing from here; air that never left the line
// without room is not held back at all (beyond_gusts run 48, seed 1: crossed 2.0 s after
// holding short for a wander of 11.7 cm, then pushed within 1.7 cm of a post).
TEST(CrossingGate, RefusesACalmShorterThanTheBlindCrossingAfterRoughAir) {
  FlightConfig config;
  const PoseEstimate pose = centred_pose();
  CrossingGateInput gate = calm_still_gate(CellIdentity::Confirmed, 0.0);
  const double blind_s = blind_crossing_s(config, 0.6);
  ASSERT_GT(blind_s, 2.5);  // 0.6 m + the shelf's depth + the vehicle, at 0.4 m/s
  EXPECT_FALSE(crossing_refusal(config, {2, 2}, pose, gate).has_value());
  gate.calm_for_s = 2.0;
  const std::string refusal = crossing_refusal(config, {2, 2}, pose, gate).value_or("");
  EXPECT_EQ(refusal.rfind(kLineCannotBeHeld, 0), 0u) << refusal;
  EXPECT_NE(refusal.find("calm for 2.00 s"), std::string::npos) << refusal;
  gate.calm_for_s = blind_s - 0.05;
  EXPECT_TRUE(crossing_refusal(config, {2, 2}, pose, gate).has_value());
  gate.calm_for_s = blind_s + 0.05;
  EXPECT_FALSE(crossing_refusal(config, {2, 2}, pose, gate).has_value());
}

// Centred, identified, a calm hover measured, the lateral law quiet: the heading alone refuses
// the crossing, turned since the pose's picture (its still stretch shorter than settle_s at
// the pose's time) or turning on under the heading law's command in effect.
TEST(CrossingGate, RefusesWhileTheHeadingTurns) {
  FlightConfig config;
  const PoseEstimate pose = centred_pose();
  CrossingGateInput gate = calm_still_gate(CellIdentity::Confirmed, 0.0);
  gate.heading_still_for_s = config.mission.approach.settle_s;
  EXPECT_FALSE(crossing_refusal(config, {2, 2}, pose, gate).has_value());
  for (double still_s : {config.mission.approach.settle_s - 0.1, 0.0, -0.2}) {
    gate.heading_still_for_s = still_s;
    EXPECT_EQ(crossing_refusal(config, {2, 2}, pose, gate).value_or(""), "heading still turning") << still_s;
  }
  gate.heading_still_for_s = 10.0;
  const double turning_radps = config.control.kp_psi * config.mission.approach.settle_psi_rad;  // 0.048
  for (double w : {0.0, 0.03, -0.045}) {
    gate.yaw_rate_cmd_radps = w;
    EXPECT_FALSE(crossing_refusal(config, {2, 2}, pose, gate).has_value()) << w;
  }
  for (double w : {turning_radps + 0.005, -0.15}) {
    gate.yaw_rate_cmd_radps = w;
    EXPECT_EQ(crossing_refusal(config, {2, 2}, pose, gate).value_or(""), "heading still turning") << w;
  }
}

// Run 19 of grid_2x2 seed 2 (ideal link), at its commit: the last pose (0.3 s old
// with the video latency) showed the vehicle about 13 cm above the centre of L2 C1 (34 cm row,
// 32 cm opening) at 0.83 m; the crossing line from it through the cell centre at mid-depth
// passes the faces 2.3 cm off the centre, inside the 11 cm the opening leaves (0.5 (0.32 -
// 0.041) - 0.03). The gate let it through; the vehicle, by then 7.7 cm above and sinking at
// 0.1 m/s, sank 21 cm in the crossing. The state record
// tells where the vehicle is now: the gate refuses while the state height, or where the
// vertical speed carries it (vz * vertical_lag_s), leaves the opening, and when the cell's
// height was never measured against the state height.
TEST(CrossingGate, JudgesTheHeightByTheStateRecordNotOnlyByTheStalePose) {
  FlightConfig config;
  config.shelf.column_pitch_m = {0.48, 0.36};
  config.shelf.row_pitch_m = {0.40, 0.34};
  const CellIndex target{2, 1};
  PoseEstimate pose;  // camera 4.5 cm ahead of the body (mount), level, facing the cell
  pose.X_FB.translation() = Eigen::Vector3d(-0.83, 0.0, 0.13);
  pose.X_FC.translation() = Eigen::Vector3d(-0.785, 0.0, 0.13);
  CrossingGateInput gate = calm_still_gate(CellIdentity::Confirmed, std::nullopt);
  const double tol_z = 0.5 * (0.34 - 0.02 - config.mission.vehicle_size_m.z()) - config.mission.crossing_margin_m;
  // No height measured against the state: never crossed.
  EXPECT_EQ(crossing_refusal(config, target, pose, gate).value_or(""), "cell height not measured against the state height");
  // The state puts the vehicle at the centre's height, still: crossed (the line passes too).
  gate.height_above_cell_m = 0.0;
  EXPECT_FALSE(crossing_refusal(config, target, pose, gate).has_value());
  // Run 19 by the state: 7.7 cm above, sinking at 0.1 m/s, carried to 2.7 cm: inside, crossed
  // (the crossing then holds the centre's height).
  gate.height_above_cell_m = 0.077;
  gate.vz_mps = -0.1;
  EXPECT_FALSE(crossing_refusal(config, target, pose, gate).has_value());
  // Already low by the state and still sinking: carried below the opening's margin. Refused,
  // though the stale pose alone would have passed.
  gate.height_above_cell_m = -(tol_z - 0.03);
  gate.vz_mps = -0.1;
  EXPECT_EQ(crossing_refusal(config, target, pose, gate).value_or(""), "off the cell's height by the state height");
  // Low and still, or just outside the margin: refused; just inside and still: crossed.
  gate.vz_mps = 0.0;
  gate.height_above_cell_m = -(tol_z + 0.005);
  EXPECT_TRUE(crossing_refusal(config, target, pose, gate).has_value());
  gate.height_above_cell_m = tol_z + 0.005;
  EXPECT_TRUE(crossing_refusal(config, target, pose, gate).has_value());
  gate.height_above_cell_m = -(tol_z - 0.005);
  EXPECT_FALSE(crossing_refusal(config, target, pose, gate).has_value());
}

}  // namespace
}  // namespace shelfcross::flight_sw

namespace shelfcross::flight_sw {
namespace {

// The camera's pixels of the cell's corner tags for a body at p_KB, heading yaw (K frame).
std::array<cv::Point2d, 4> corners_seen(const FlightConfig& config, CellIndex cell, const Eigen::Vector3d& p_KB,
                                        double yaw_rad) {
  Eigen::Isometry3d X_KB = Eigen::Isometry3d::Identity();
  X_KB.linear() = Eigen::AngleAxisd(yaw_rad, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  X_KB.translation() = p_KB;
  Eigen::Isometry3d X_BC = Eigen::Isometry3d::Identity();
  X_BC.linear() = rotation_body_from_camera(config.mount.pitch_rad);
  X_BC.translation() = config.mount.p_BC_B_m;
  const Eigen::Isometry3d X_CK = (X_KB * X_BC).inverse();
  std::vector<cv::Point3d> p_C;
  for (const cv::Point3d& o : cell_corner_tags_K(config.shelf, cell)) {
    const Eigen::Vector3d c = X_CK * Eigen::Vector3d(o.x, o.y, o.z);
    p_C.emplace_back(c.x(), c.y(), c.z());
  }
  const CameraIntrinsics& k = config.camera;
  std::vector<cv::Point2d> px;
  cv::projectPoints(p_C, cv::Vec3d(0, 0, 0), cv::Vec3d(0, 0, 0), cv::Matx33d(k.fx_px, 0, k.cx_px, 0, k.fy_px, k.cy_px, 0, 0, 1),
                    cv::Vec<double, 5>(k.k1, k.k2, k.p1, k.p2, k.k3), px);
  return {px[0], px[1], px[2], px[3]};
}

// Between poses (damaged pictures, a tag missed) the tracker carries the last pose by the
// vehicle's own motion from its state odometry (frame O, whose axes are turned from K's by the
// heading): the carried pose is the moved body's to a millimetre, and its corner tags are where
// the moved camera sees them, to a tenth of a pixel, for motions of every axis and a turn, with
// O turned 1 rad from K.
TEST(MotionPrediction, CornerTagsMovedByTheOdometryAreWhereTheMovedCameraSeesThem) {
  const FlightConfig config;
  const CellIndex cell{2, 3};
  const Eigen::Vector3d p0_KB(-1.6, 0.08, 0.12);
  const double yaw0 = 0.05;
  const auto seen0 = corners_seen(config, cell, p0_KB, yaw0);
  const auto obj = cell_corner_tags_K(config.shelf, cell);
  const auto pose = estimate_pose({obj.begin(), obj.end()}, {seen0.begin(), seen0.end()}, config.camera, config.mount);
  ASSERT_TRUE(pose.has_value());
  const double yaw_K_in_O = 1.0;  // the odometry frame's heading is arbitrary
  const double yaw_O_at_pose = yaw_K_in_O + yaw0;
  for (const auto& [dp_KB, dyaw] : std::vector<std::pair<Eigen::Vector3d, double>>{
           {{0.3, 0.0, 0.0}, 0.0}, {{0.0, 0.1, 0.0}, 0.0}, {{0.0, 0.0, -0.15}, 0.0}, {{0.2, -0.05, 0.1}, -0.08}}) {
    const Eigen::Vector3d dp_O(std::cos(yaw_K_in_O) * dp_KB.x() - std::sin(yaw_K_in_O) * dp_KB.y(),
                               std::sin(yaw_K_in_O) * dp_KB.x() + std::cos(yaw_K_in_O) * dp_KB.y(), dp_KB.z());
    const PoseEstimate moved = pose_after_motion(*pose, yaw_O_at_pose, dp_O, dyaw);
    EXPECT_LT((moved.p_FB_m() - (p0_KB + dp_KB)).norm(), 1e-3) << "motion " << dp_KB.transpose();
    EXPECT_NEAR(moved.yaw_rad, yaw0 + dyaw, 1e-3);
    const auto predicted = corners_seen_from(config, cell, moved);
    ASSERT_TRUE(predicted.has_value());
    const auto truth = corners_seen(config, cell, p0_KB + dp_KB, yaw0 + dyaw);
    for (size_t k = 0; k < 4; ++k) {
      EXPECT_LT(cv::norm((*predicted)[k] - truth[k]), 0.1) << "corner " << k << " motion " << dp_KB.transpose();
    }
    // And the motion moves them: a prediction that ignored it would be far off.
    double moved_px = 0.0;
    for (size_t k = 0; k < 4; ++k) moved_px = std::max(moved_px, cv::norm(truth[k] - seen0[k]));
    EXPECT_GT(moved_px, 10.0);
  }
}

}  // namespace
}  // namespace shelfcross::flight_sw

namespace shelfcross::flight_sw {
namespace {

// The level check (judge_pose) seen from 2.15 m, the approach's start: a pose whose pitch
// disagrees with the state records' (far out, planar PnP's tilt is ambiguous) is judged by its
// image row under the records' pitch. The picture was taken a video latency before the newest
// record; as the approach starts from a hover, the Tello tips 4 deg within that latency.
struct LevelScene {
  FlightConfig config;
  double range_m = 2.15;
  double vehicle_height_m = 0.95;
  double target_height_m = 1.10;
  // The image row of a point at `height_m` on the shelf's front seen under pitch `pitch_rad`.
  double row_px(double height_m, double pitch_rad) const {
    const CameraIntrinsics& k = config.camera;
    const double elevation = std::atan((height_m - vehicle_height_m) / range_m) + pitch_rad;
    return k.cy_px - k.fy_px * std::tan(elevation + config.mount.pitch_rad);
  }
  // The verdict on a pose whose corner tags' centre is at that row, under `states`.
  PoseVerdict judge(double row, const RecentStates& states, TimeNs now_ns) const {
    PoseEstimate pose;
    pose.X_FC.translation() = Eigen::Vector3d(-range_m, 0.0, 0.0);
    pose.X_FB.translation() = Eigen::Vector3d(-range_m - 0.045, 0.0, 0.0);
    pose.pitch_rad = 0.3;  // far from every record's: the image row decides
    const TargetPoses no_history;
    return judge_pose(config, {pose, now_ns, false, cv::Point2d(config.camera.cx_px, row)}, no_history,
                      states.span(now_ns), target_height_m);
  }
};

StateRecord record_at(double t_s, double pitch_rad, double height_m) {
  StateRecord s;
  s.t_ns = seconds_to_ns(t_s);
  s.pitch_rad = pitch_rad;
  s.height_m = height_m;
  return s;
}

TEST(LevelCheck, TheWindowOfStateRecordsSpansTheVideoLatency) {
  RecentStates states;
  EXPECT_FALSE(states.span(seconds_to_ns(1.0)).has_value());
  for (int i = 0; i <= 10; ++i) states.on_state(record_at(0.1 * i, 0.01 * i, 1.0 + 0.01 * i));
  // At 1.0 s: the records of 0.6-1.0 s (kLevelWindow_s = 0.45 s).
  const std::optional<StateSpan> now = states.span(seconds_to_ns(1.0));
  ASSERT_TRUE(now.has_value());
  EXPECT_NEAR(now->pitch_min_rad, 0.06, 1e-12);
  EXPECT_NEAR(now->pitch_max_rad, 0.10, 1e-12);
  EXPECT_NEAR(now->height_min_m, 1.06, 1e-12);
  EXPECT_NEAR(now->height_max_m, 1.10, 1e-12);
  // Records gone stale: the newest alone, as a single record would be judged.
  const std::optional<StateSpan> stale = states.span(seconds_to_ns(3.0));
  ASSERT_TRUE(stale.has_value());
  EXPECT_NEAR(stale->pitch_min_rad, 0.10, 1e-12);
  EXPECT_NEAR(stale->pitch_max_rad, 0.10, 1e-12);
}

TEST(LevelCheck, ATippingStartNeitherLosesTheTargetNorTakesTheLevelAbove) {
  const LevelScene scene;
  const auto& rows = scene.config.shelf.row_pitch_m;
  const double pitch_m = *std::min_element(rows.begin(), rows.end());
  const double tip_rad = 0.07;  // 4 deg, the SDK's whole degrees
  ASSERT_GT(scene.range_m * std::tan(tip_rad), 0.4 * pitch_m) << "the tip must move the row past the tolerance";
  // The target's tags and the level above's, in a picture taken level (pitch 0).
  const double target_row = scene.row_px(scene.target_height_m, 0.0);
  const double above_row = scene.row_px(scene.target_height_m + pitch_m, 0.0);
  const TimeNs now_ns = seconds_to_ns(10.0);
  // Hovering level, every record level: the target is the target, the level above is not.
  RecentStates level;
  for (int i = 4; i >= 0; --i) level.on_state(record_at(10.0 - 0.1 * i, 0.0, scene.vehicle_height_m));
  EXPECT_EQ(scene.judge(target_row, level, now_ns), PoseVerdict::Plausible);
  EXPECT_EQ(scene.judge(above_row, level, now_ns), PoseVerdict::WrongLevel);
  // Tipping 4 deg within the latency: under the newest record alone the target's own pose reads
  // a level off (the approach lost its target at every start); under the window it cannot be
  // told, which holds the pose without losing the target. The level above stays refused.
  RecentStates newest_only;
  newest_only.on_state(record_at(10.0, tip_rad, scene.vehicle_height_m));
  EXPECT_EQ(scene.judge(target_row, newest_only, now_ns), PoseVerdict::WrongLevel);
  RecentStates tipping;
  const double pitch_rad[] = {0.0, 0.0, 0.035, 0.052, tip_rad};
  for (int i = 0; i < 5; ++i) tipping.on_state(record_at(9.6 + 0.1 * i, pitch_rad[i], scene.vehicle_height_m));
  EXPECT_EQ(scene.judge(target_row, tipping, now_ns), PoseVerdict::LevelUnsure);
  EXPECT_EQ(scene.judge(above_row, tipping, now_ns), PoseVerdict::WrongLevel);
  // Climbing toward the cell within the latency (0.2 m/s, 8 cm): the same.
  RecentStates climbing;
  for (int i = 0; i < 5; ++i) climbing.on_state(record_at(9.6 + 0.1 * i, 0.0, scene.vehicle_height_m + 0.02 * i));
  EXPECT_NE(scene.judge(target_row, climbing, now_ns), PoseVerdict::WrongLevel);
  EXPECT_EQ(scene.judge(above_row, climbing, now_ns), PoseVerdict::WrongLevel);
}

}  // namespace
}  // namespace shelfcross::flight_sw
