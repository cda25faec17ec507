// The guidance room's pure laws (guidance.hpp), each alone: inputs in, the command out.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <optional>
#include <vector>

#include "flight_sw/config.hpp"
#include "flight_sw/guidance/guidance.hpp"
#include "shelfcross/rotation.hpp"

namespace shelfcross::flight_sw {
namespace {

constexpr double kTight = 1e-12;

TEST(GuidanceFrames, ToBodyTurnsAFrameVelocityByMinusTheHeading) {
  // A vehicle turned 90 deg left (CCW) in F sees F's x to its right: body -y.
  const Eigen::Vector2d v_B = to_body_xy({1.0, 0.0}, std::numbers::pi / 2);
  EXPECT_NEAR(v_B.x(), 0.0, kTight);
  EXPECT_NEAR(v_B.y(), -1.0, kTight);
  EXPECT_NEAR(to_body_xy({0.3, -0.4}, 0.7).norm(), 0.5, kTight);
}

TEST(GuidanceFrames, CappedShortensOnlyWhatIsTooLong) {
  EXPECT_EQ(capped({0.1, 0.0, 0.0}, 0.4), Eigen::Vector3d(0.1, 0.0, 0.0));
  const Eigen::Vector3d c = capped({3.0, 4.0, 0.0}, 0.5);
  EXPECT_NEAR(c.norm(), 0.5, kTight);
  EXPECT_NEAR(c.x() / c.y(), 0.75, kTight);  // direction kept
}

TEST(FragmentLaw, CentresTheTagsAndBacksAwayOnlyWhileTheShelfIsTooClose) {
  const FlightConfig config;
  const CameraIntrinsics& k = config.camera;
  // One tag left of and above the principal point.
  const std::vector<TagBlob> tags{{cv::Point2d(k.cx_px - 100.0, k.cy_px - 50.0), 400.0, {}}};
  const double far_side_px = k.fx_px * config.shelf.tag_size_m / (1.2 * 1.5);
  const VelocityCommand near = fragment_velocity(config, tags, std::pow(far_side_px + 1.0, 2), 1.5);
  EXPECT_EQ(near.vx_B_mps, -config.control.back_off_speed_mps);
  EXPECT_GT(near.yaw_rate_radps, 0.0);  // turn left, toward the tags
  EXPECT_GT(near.vz_mps, 0.0);          // climb toward them
  const VelocityCommand far = fragment_velocity(config, tags, std::pow(far_side_px - 1.0, 2), 1.5);
  EXPECT_EQ(far.vx_B_mps, 0.0);
  EXPECT_EQ(far.yaw_rate_radps, near.yaw_rate_radps);
}

TEST(ViewpointLaw, FliesTowardTheViewpointCappedAndTurnsToTheNormal) {
  const ControlGains g;
  const VelocityCommand v = viewpoint_velocity(g, {10.0, 0.0, 0.0}, 0.0);
  EXPECT_NEAR(std::hypot(v.vx_B_mps, std::hypot(v.vy_B_mps, v.vz_mps)), g.viewpoint_speed_max_mps, kTight);
  EXPECT_GT(v.vx_B_mps, 0.0);
  EXPECT_EQ(v.yaw_rate_radps, 0.0);
  // Turned left of the normal: turn right (negative rate), saturated.
  EXPECT_EQ(viewpoint_velocity(g, Eigen::Vector3d::Zero(), 3.0).yaw_rate_radps, -g.yaw_rate_max_radps);
}

TEST(ApproachErrors, FromTheBoxInTheImageAndThePose) {
  const FlightConfig config;
  const CameraIntrinsics& k = config.camera;
  PoseEstimate pose;
  pose.X_FC.translation() = Eigen::Vector3d(-1.0, 0.0, 0.0);
  pose.yaw_rad = 0.1;
  const ApproachErrors e = approach_errors(k, {k.cx_px - k.fx_px * 0.05, k.cy_px - 20.0}, pose);
  EXPECT_NEAR(e.range_m, 1.0, kTight);
  EXPECT_NEAR(e.e_z_m, 20.0 / k.fy_px, kTight);       // above: climb (eq. 11)
  EXPECT_NEAR(e.e_psi_rad, std::atan(0.05), kTight);  // left: turn left (eq. 13-14)
  EXPECT_NEAR(e.psi_cell_rad, 0.1 + std::atan(0.05), kTight);
}

TEST(LateralLaw, BangOffBangOnTheCellsBearingWithABandNeverNarrowerThanItsOffset) {
  const ControlGains g;
  ApproachErrors e;
  e.range_m = 0.5;  // close: the band is atan(lateral_threshold_m / range)
  const double band = std::atan(g.lateral_threshold_m / e.range_m);
  ASSERT_GT(band, g.psi_lateral_threshold_rad);
  e.psi_cell_rad = 0.99 * band;
  EXPECT_EQ(approach_lateral_mps(g, e), 0.0);
  e.psi_cell_rad = 1.01 * band;
  EXPECT_EQ(approach_lateral_mps(g, e), g.lateral_speed_mps);
  e.psi_cell_rad = -1.01 * band;
  EXPECT_EQ(approach_lateral_mps(g, e), -g.lateral_speed_mps);
}

TEST(ApproachHold, SettledNeedsStillnessAndBothErrorsWithinTheirBands) {
  const FlightConfig config;
  const auto& a = config.mission.approach;
  ApproachErrors e;
  EXPECT_TRUE(approach_hold(config, e, a.settle_s, 0.5).settled);
  EXPECT_FALSE(approach_hold(config, e, 0.9 * a.settle_s, 0.5).settled);
  e.e_z_m = 1.1 * a.settle_z_m;
  const ApproachHold h = approach_hold(config, e, a.settle_s, config.control.commit_range_m);
  EXPECT_FALSE(h.settled);
  EXPECT_TRUE(h.settling);
  EXPECT_FALSE(approach_hold(config, e, a.settle_s, 1.1 * config.control.commit_range_m).settling);
  e.psi_cell_rad = 1.1 * config.control.approach_cone_rad;
  EXPECT_FALSE(approach_hold(config, e, a.settle_s, 1.0).in_cone);
}

TEST(ForwardLaw, ConstantSpeedUnlessHeldAndBackOffWhileUnidentified) {
  const ControlGains g;
  EXPECT_EQ(approach_forward_mps(g, false, true, 1.0, 1.5), g.forward_speed_mps);  // eq. 10
  EXPECT_EQ(approach_forward_mps(g, true, true, 1.0, 1.5), 0.0);
  EXPECT_EQ(approach_forward_mps(g, false, false, 1.0, 1.5), -g.back_off_speed_mps);
  EXPECT_EQ(approach_forward_mps(g, false, false, 1.6, 1.5), 0.0);  // no farther than the viewpoint
  EXPECT_EQ(back_off_velocity(g), (VelocityCommand{-g.back_off_speed_mps, 0.0, 0.0, 0.0}));
}

TEST(CrossingLaws, ABehindShelfShortensTheCrossingsEnd) {
  const FlightConfig config;
  const auto& c = config.mission.crossing;
  EXPECT_EQ(crossing_beyond_m(config, std::nullopt), c.beyond_distance_m);
  const double behind_m = 1.5;
  EXPECT_NEAR(crossing_beyond_m(config, behind_m),
              std::min(c.beyond_distance_m, behind_m - config.shelf.depth_m - config.mission.vehicle_size_m.x() -
                                                c.stop_distance_m),
              kTight);
  EXPECT_LT(crossing_beyond_m(config, 0.8), c.beyond_distance_m);
}

TEST(CrossingLaws, TheLineIsFlownAtCrossingSpeedAndEndsByDistance) {
  const FlightConfig config;
  PoseEstimate pose;  // straight in front of the cell centre, 0.6 m out, on the normal
  pose.X_FC.translation() = Eigen::Vector3d(-0.6, 0.0, 0.0);
  pose.X_FB.translation() = Eigen::Vector3d(-0.6, 0.0, 0.0);
  const CrossingPlan plan = plan_crossing(config, pose, 0.0, 0.5, 1.0, {1.0, 2.0}, 0.0);
  EXPECT_NEAR(plan.dir_B.y(), 0.0, 1e-9);
  EXPECT_GT(plan.dir_B.x(), 0.99);
  EXPECT_NEAR(plan.end.line_m,
              (0.6 + config.shelf.depth_m + 0.5 * config.mission.vehicle_size_m.x() + 0.5) / plan.dir_B.x() *
                  plan.dir_B.norm(),
              1e-9);
  EXPECT_EQ(plan.end.start_O_m, Eigen::Vector2d(1.0, 2.0));
  const VelocityCommand v = crossing_velocity(config.control, plan, 0.02);
  EXPECT_NEAR(v.vx_B_mps, config.control.crossing_speed_mps * plan.dir_B.x(), kTight);
  EXPECT_EQ(v.vz_mps, 0.02);
  EXPECT_EQ(v.yaw_rate_radps, 0.0);  // heading held
  // A slower vehicle (gain below 1) is given longer before the timed fallback ends it.
  EXPECT_GT(plan_crossing(config, pose, 0.0, 0.5, 0.8, {1.0, 2.0}, 0.0).end.timed_ns, plan.end.timed_ns);
}

// A drift flown out: a vehicle drifting 2 cm/s to its left (+y) on a line straight ahead is
// asked 2 cm/s to its right; the Tello then flies the line, while its estimate, which the
// odometry integrates, moves along the commanded velocity: the watch's axis turns with it, by
// atan(-0.02 / 0.4) on a heading of 0.3 rad.
TEST(CrossingLaws, ADriftFlownOutTurnsTheCommandAndTheOdometrysAxis) {
  const FlightConfig config;
  PoseEstimate pose;
  pose.X_FC.translation() = Eigen::Vector3d(-0.6, 0.0, 0.0);
  pose.X_FB.translation() = Eigen::Vector3d(-0.6, 0.0, 0.0);
  const CrossingPlan line = plan_crossing(config, pose, 0.0, 0.5, 1.0, {0.0, 0.0}, 0.3);
  CrossingPlan trimmed = line;
  trim_crossing(trimmed, config.control, 0.02);
  const double speed = config.control.crossing_speed_mps;
  const VelocityCommand v = crossing_velocity(config.control, trimmed, 0.0);
  EXPECT_NEAR(v.vx_B_mps, speed, kTight);
  EXPECT_NEAR(v.vy_B_mps, -0.02, kTight);
  const double turned = std::atan2(trimmed.end.axis_O.y(), trimmed.end.axis_O.x()) -
                        std::atan2(line.end.axis_O.y(), line.end.axis_O.x());
  EXPECT_NEAR(turned, std::atan2(-0.02, speed), 1e-12);
  EXPECT_NEAR(trimmed.end.axis_O.norm(), 1.0, 1e-12);
  EXPECT_EQ(trimmed.end.line_m, line.end.line_m);
  // No drift: the plan is the line's.
  CrossingPlan none = line;
  trim_crossing(none, config.control, 0.0);
  EXPECT_EQ(none.end.axis_O, line.end.axis_O);
  EXPECT_EQ(crossing_velocity(config.control, none, 0.0).vy_B_mps, crossing_velocity(config.control, line, 0.0).vy_B_mps);
}

TEST(CrossingLaws, TheHeightHoldIsSaturated) {
  const ControlGains g;
  EXPECT_EQ(crossing_vz_mps(g, 1.0, 0.0), g.crossing_z_speed_max_mps);
  EXPECT_EQ(crossing_vz_mps(g, 0.0, 1.0), -g.crossing_z_speed_max_mps);
  EXPECT_NEAR(crossing_vz_mps(g, 1.0, 0.999), g.crossing_kp_z * 0.001, kTight);
}

TEST(TransferLaws, OverTheTopsClimbsCrossesAndComesDownAtTheNextViewpoint) {
  FlightConfig config;
  config.strategy.mode = Strategy::over_tops;
  config.layout.shelf_count = 2;
  config.layout.shelf_spacing_m = 4.0;
  const Eigen::Vector3d p(-1.5, 0.1, 0.2), viewpoint(-1.5, 0.0, 0.3);
  const std::vector<Eigen::Vector3d> w = transfer_waypoints_G(config, p, viewpoint, false);
  ASSERT_EQ(w.size(), 3u);
  EXPECT_EQ(w[0].head<2>(), p.head<2>());  // straight up first
  EXPECT_GT(w[0].z(), p.z());
  EXPECT_EQ(w[1].z(), w[0].z());  // across at that height
  EXPECT_NEAR(w[2].x(), config.layout.shelf_spacing_m + viewpoint.x(), kTight);
  EXPECT_EQ(w[2].z(), viewpoint.z());
  config.strategy.mode = Strategy::around_ends;
  const std::vector<Eigen::Vector3d> a = transfer_waypoints_G(config, p, viewpoint, false);
  EXPECT_GT(a[0].y(), p.y());  // the nearer end: p is left of the centre line
  EXPECT_EQ(a[0].z(), p.z());
}

TEST(TransferLaws, ThePLawIsCappedAndHoldsTheHeading) {
  const FlightConfig config;
  const VelocityCommand v = transfer_velocity(config, {5.0, 0.0, 0.0}, 0.0, 0.0);
  EXPECT_NEAR(v.vx_B_mps, config.strategy.transfer_speed_mps, kTight);
  EXPECT_EQ(v.yaw_rate_radps, 0.0);
  EXPECT_GT(transfer_velocity(config, Eigen::Vector3d::Zero(), -0.1, 0.0).yaw_rate_radps, 0.0);
  // Across the +-pi seam the shorter turn.
  EXPECT_LT(transfer_velocity(config, Eigen::Vector3d::Zero(), deg_to_rad(-179.0), deg_to_rad(179.0)).yaw_rate_radps,
            0.0);
}

}  // namespace
}  // namespace shelfcross::flight_sw
