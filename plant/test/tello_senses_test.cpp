// The Tello's own senses: the default senses the truth; below the VPS's range or over a plain
// surface the hold gives way and a hover drifts with the air; a VPS bias makes a hover drift at
// minus the bias; a height hold set to follow the range climbs by the step it sees over a box,
// set to fused it does not; tof reads the box top.

#include <gtest/gtest.h>

#include <cmath>

#include "plant/collision.hpp"
#include "plant/simulated_tello.hpp"
#include "shelfcross/rotation.hpp"

namespace shelfcross::plant {
namespace {

// A Tello in SDK mode taken off at (x, y), flying on the given senses.
struct SensedFlight {
  SensedFlight(const SensesSetup& senses, WindParams wind = {}, double x_m = 0.0, double y_m = 0.0)
      : tello(VehicleParams{}, AutopilotParams{}, wind, 11, {}, x_m, y_m, 0.0, senses) {
    EXPECT_EQ(tello.submit(0, "command"), std::optional<std::string>("ok"));
    EXPECT_EQ(tello.submit(seconds_to_ns(0.5), "takeoff"), std::nullopt);
    for (int k = 1; k <= 800 && replies.empty(); ++k) step(seconds_to_ns(0.5) + k * 10'000'000LL);
    EXPECT_EQ(replies.size(), 1u);
    replies.clear();
  }
  void step(TimeNs t) {
    tello.step_to(t);
    for (auto& r : tello.take_replies()) replies.push_back(r);
  }
  // Flies on for duration_s, sending `rc 0 0 0 0` every 2 s (the watchdog's keep-alive).
  void hover(double duration_s) {
    const TimeNs end = tello.time_ns() + seconds_to_ns(duration_s);
    while (tello.time_ns() < end) {
      step(std::min(end, tello.time_ns() + seconds_to_ns(2.0)));
      tello.submit(tello.time_ns(), "rc 0 0 0 0");
    }
  }
  SimulatedTello tello;
  std::vector<SdkReply> replies;
};

TEST(TelloSenses, DefaultSensesTheTruthExactly) {
  SensedFlight f(SensesSetup{});
  f.hover(3.0);
  const RigidBodyState& s = f.tello.state();
  const TelloSenses& senses = f.tello.autopilot().senses();
  const SensedReadings r = senses.readings(s);
  EXPECT_TRUE(senses.vps_valid());
  EXPECT_EQ(r.v_W_mps, s.v_WB_W_mps);
  EXPECT_EQ(r.height_W_m, s.p_WB_m.z());
  EXPECT_EQ(r.baro_m, s.p_WB_m.z());
  ASSERT_TRUE(r.tof_m);
  // The belly's range to the floor plus the reading on the ground.
  const Eigen::Vector3d z_B = s.q_WB * Eigen::Vector3d::UnitZ();
  const double belly_z = s.p_WB_m.z() - VehicleParams{}.rest_height_m() * z_B.z();
  EXPECT_NEAR(*r.tof_m, 0.1 + belly_z / z_B.z(), 1e-12);
}

// In a steady wind, a hover whose VPS is invalid flies level with no position feedback: the
// drag carries it to the wind's speed (time constant about m / k_lin = 6 s, less with the
// quadratic drag). Valid, the same hover holds within centimetres.
void check_drift_with_the_air(const SensesParams& invalid) {
  WindParams wind;
  wind.steady_W_mps = Eigen::Vector3d(0.3, 0.0, 0.0);
  SensedFlight held(SensesSetup{}, wind);
  const Eigen::Vector3d p_held = held.tello.state().p_WB_m;
  held.hover(30.0);
  EXPECT_LT((held.tello.state().p_WB_m - p_held).head<2>().norm(), 0.05);

  SensedFlight f(SensesSetup{invalid, nullptr, 1.0, 3}, wind);
  EXPECT_FALSE(f.tello.autopilot().senses().vps_valid());
  f.hover(30.0);
  const Eigen::Vector3d v = f.tello.state().v_WB_W_mps;
  EXPECT_GT(v.x(), 0.9 * wind.steady_W_mps.x());
  EXPECT_LT(v.x(), 1.01 * wind.steady_W_mps.x());
  EXPECT_NEAR(v.y(), 0.0, 0.01);
  EXPECT_NEAR(f.tello.state().p_WB_m.z(), 1.0, 0.05);  // the height hold is the barometer's
  // The state record has no horizontal velocity while the VPS is invalid.
  const SensedReadings r = f.tello.autopilot().senses().readings(f.tello.state());
  EXPECT_EQ(r.v_W_mps.head<2>(), Eigen::Vector2d::Zero());
}

TEST(TelloSenses, BelowTheVpsRangeAHoverDriftsWithTheAir) {
  SensesParams p;
  p.vps.min_range_m = 2.0;  // the hover at 1 m is below it
  check_drift_with_the_air(p);
}

TEST(TelloSenses, OverAPlainSurfaceAHoverDriftsWithTheAir) {
  SensesParams p;
  p.vps.texture.floor = 0.1;
  p.vps.min_contrast = 0.3;
  check_drift_with_the_air(p);
}

TEST(TelloSenses, TooLittleLightIsAPlainSurface) {
  SensesParams p;
  p.vps.min_contrast = 0.3;
  SensedFlight dim(SensesSetup{p, nullptr, 0.2, 3});
  EXPECT_FALSE(dim.tello.autopilot().senses().vps_valid());
  SensedFlight lit(SensesSetup{p, nullptr, 0.8, 3});
  EXPECT_TRUE(lit.tello.autopilot().senses().vps_valid());
}

// A VPS bias b (held nearly constant: a time constant of an hour) makes the hold believe the
// drone moves at v + b: it holds the estimate still, so the drone moves at -b, by the
// configured rate.
TEST(TelloSenses, AVpsBiasMakesAHoverDriftAtMinusTheBias) {
  SensesParams p;
  p.vps.bias_stddev_mps = 0.05;
  p.vps.bias_time_constant_s = 3600.0;
  SensedFlight f(SensesSetup{p, nullptr, 1.0, 5});
  f.hover(5.0);  // the hold settles on the biased estimate
  ASSERT_GT(f.tello.autopilot().senses().vps_bias_H_mps().norm(), 0.005);
  // The bias still wanders a little (about 10 % of its deviation in 20 s): compare the drift
  // with its mean over the span.
  const Eigen::Vector2d p0 = f.tello.state().p_WB_m.head<2>();
  Eigen::Vector2d bias_integral_W = Eigen::Vector2d::Zero();
  constexpr double kSpan_s = 20.0, kStep_s = 0.02;
  for (int k = 1; k <= static_cast<int>(kSpan_s / kStep_s); ++k) {
    f.step(f.tello.time_ns() + seconds_to_ns(kStep_s));
    if (k % 100 == 0) f.tello.submit(f.tello.time_ns(), "rc 0 0 0 0");
    const double yaw = euler_zyx_from_quaternion(f.tello.state().q_WB).z();
    bias_integral_W += Eigen::Rotation2Dd(yaw) * f.tello.autopilot().senses().vps_bias_H_mps() * kStep_s;
  }
  const Eigen::Vector2d drift_mps = (f.tello.state().p_WB_m.head<2>() - p0) / kSpan_s;
  const Eigen::Vector2d mean_bias_W = bias_integral_W / kSpan_s;
  EXPECT_NEAR(drift_mps.x(), -mean_bias_W.x(), 0.03 * mean_bias_W.norm() + 1e-3);
  EXPECT_NEAR(drift_mps.y(), -mean_bias_W.y(), 0.03 * mean_bias_W.norm() + 1e-3);
}

// One shelf level 0.3 m up with a 0.22 m box in its first cell (top at z = 0.53) at x 3.0 to
// 3.34; the drone flies forward at 1 m over the box's cell.
Warehouse box_shelf() {
  Warehouse w;
  ShelfSpec s;
  s.origin_W_m = {3.0, 0.0, 0.0};
  s.column_pitch_m = {0.34, 0.48};
  s.row_pitch_m = {0.34};
  s.base_height_m = 0.30;
  s.depth_m = 0.34;
  s.boxes = {{1, 1, 3}};
  w.shelves.push_back(s);
  w.box_size_m = {0.22, 0.22, 0.22};
  return w;
}

// Flies from x = 1 to over the box (x = 3.17) and hovers; returns the climb of the true height.
double climb_over_the_box(const HeightHoldParams& hold, const CollisionWorld& world, double y_m,
                          std::optional<double>& tof_m) {
  SensesParams p;
  p.height_hold = hold;
  SensedFlight f(SensesSetup{p, &world, 1.0, 7}, {}, 1.0, y_m);
  const double z0 = f.tello.state().p_WB_m.z();
  EXPECT_EQ(f.tello.submit(f.tello.time_ns(), "forward 217"), std::nullopt);
  f.hover(8.0);
  EXPECT_NEAR(f.tello.state().p_WB_m.x(), 3.17, 0.1);
  tof_m = f.tello.autopilot().senses().readings(f.tello.state()).tof_m;
  return f.tello.state().p_WB_m.z() - z0;
}

TEST(TelloSenses, AHeightHoldThatFollowsTheRangeClimbsByTheStepAndAFusedOneDoesNot) {
  const Warehouse w = box_shelf();
  const CollisionWorld world(w, VehicleParams{}.size_m, 0.0);
  const double y_m = cell_centre_S_m(w.shelves.front(), 1, 1).y();  // over the box's cell
  const double box_top_m = 0.30 + 0.01 + 0.22;
  const double rest_m = VehicleParams{}.rest_height_m();
  std::optional<double> tof_m;
  HeightHoldParams fused;  // range_blend 0
  const double fused_climb = climb_over_the_box(fused, world, y_m, tof_m);
  EXPECT_NEAR(fused_climb, 0.0, 0.02);
  // tof reads the box top, not the floor: the belly is 1 m - rest up, the box top 0.53 m.
  ASSERT_TRUE(tof_m);
  EXPECT_NEAR(*tof_m, 0.1 + (1.0 + fused_climb - rest_m) - box_top_m, 0.02);
  HeightHoldParams follow;
  follow.range_blend = 1.0;
  follow.range_below_m = 2.0;
  follow.time_constant_s = 0.3;
  const double climb = climb_over_the_box(follow, world, y_m, tof_m);
  EXPECT_NEAR(climb, box_top_m, 0.03);
  ASSERT_TRUE(tof_m);
  EXPECT_NEAR(*tof_m, 0.1 + 1.0 - rest_m, 0.03);  // it holds its range above the box
  HeightHoldParams half = follow;
  half.range_blend = 0.5;
  EXPECT_NEAR(climb_over_the_box(half, world, y_m, tof_m), 0.5 * box_top_m, 0.03);
}

TEST(TelloSenses, RefusesANonPositiveRateOrTimeConstant) {
  SensesParams p;
  p.sample_rate_hz = 0.0;
  EXPECT_THROW(TelloSenses(p, VehicleParams{}, nullptr, 1.0, 1), std::invalid_argument);
  p = {};
  p.height_hold.time_constant_s = 0.0;
  EXPECT_THROW(TelloSenses(p, VehicleParams{}, nullptr, 1.0, 1), std::invalid_argument);
}

}  // namespace
}  // namespace shelfcross::plant
