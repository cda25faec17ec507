// Control laws: PI step response and anti-windup, bang-off-bang and the approach's lateral law,
// rc conversion and saturation, the crossing's carried rounding and the heading its line is
// planned on.

#include <cmath>

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include "flight_sw/control/control.hpp"
#include "flight_sw/control/sticks.hpp"
#include "flight_sw/guidance/guidance.hpp"
#include "flight_sw/navigation/navigation.hpp"

namespace shelfcross::flight_sw {
namespace {

TEST(PiController, StepResponseOfTheOutputIsProportionalPlusRamp) {
  PiController pi({2.0, 0.5, 100.0, 100.0});
  // Constant error 1: u_k = kp + ki * k dt.
  for (int k = 1; k <= 10; ++k) EXPECT_NEAR(pi.update(1.0, 0.1), 2.0 + 0.5 * 0.1 * k, 1e-12);
}

TEST(PiController, ClosedLoopRejectsAConstantDisturbanceWithoutOffset) {
  // Integrator plant x' = u + d, set point 1: the I term cancels d, the error goes to zero.
  PiController pi({1.5, 0.8, 10.0, 5.0});
  double x = 0.0;
  const double d = -0.3, dt = 0.02;
  for (int k = 0; k < 2000; ++k) x += (pi.update(1.0 - x, dt) + d) * dt;
  EXPECT_NEAR(x, 1.0, 1e-3);
  EXPECT_NEAR(pi.integral() * 0.8, 0.3, 1e-3);  // ki * integral = -d
}

TEST(PiController, AntiWindupHoldsTheIntegralWhileSaturatedAndLeavesAtOnce) {
  PiController pi({1.0, 1.0, 100.0, 0.5});
  for (int k = 0; k < 100; ++k) EXPECT_DOUBLE_EQ(pi.update(2.0, 0.1), 0.5);  // saturated
  // kp*e alone saturates from the first step: the integral never advanced.
  EXPECT_DOUBLE_EQ(pi.integral(), 0.0);
  // The error reverses: the output follows at once (no stored windup to unwind).
  EXPECT_DOUBLE_EQ(pi.update(-0.2, 0.1), -0.2 + 1.0 * (-0.02));
  // The integral limit bounds it in the unsaturated region.
  PiController lim({0.0, 1.0, 0.3, 10.0});
  for (int k = 0; k < 100; ++k) lim.update(1.0, 0.1);
  EXPECT_DOUBLE_EQ(lim.integral(), 0.3);
  EXPECT_DOUBLE_EQ(lim.update(0.0, 0.1), 0.3);
}

TEST(BangOffBang, ThresholdsAndSigns) {
  const double psi_l = 0.05, v = 0.12;
  EXPECT_DOUBLE_EQ(bang_off_bang(0.0, psi_l, v), 0.0);
  EXPECT_DOUBLE_EQ(bang_off_bang(0.05, psi_l, v), 0.0);  // at the threshold: off
  EXPECT_DOUBLE_EQ(bang_off_bang(-0.05, psi_l, v), 0.0);
  EXPECT_DOUBLE_EQ(bang_off_bang(0.0501, psi_l, v), v);  // turned left of the normal: it is
  EXPECT_DOUBLE_EQ(bang_off_bang(-0.0501, psi_l, v), -v);  // right of it, and vice versa
  EXPECT_DOUBLE_EQ(bang_off_bang(1.0, psi_l, v), v);
  // Sign check in the cell frame: a vehicle left of the normal (y_K = +0.2 at x_K = -1)
  // looking at the cell centre has psi = atan2(-y, -x) < 0, and must move right (vy_B < 0).
  const double psi = std::atan2(-0.2, 1.0);
  EXPECT_LT(bang_off_bang(psi, psi_l, v), 0.0);
}

// The approach's lateral law: psi_L far out; closer than lateral_threshold_m / tan(psi_L) (1 m
// for the defaults), the bearing of lateral_threshold_m across the line of sight, so that the
// band is never narrower than 4 cm either side.
TEST(LateralLaw, BandNeverNarrowerThanItsOffset) {
  const ControlGains g;
  const auto lateral = [&](double range_m, double offset_m) {
    ApproachErrors e;
    e.range_m = range_m;
    e.psi_cell_rad = std::atan2(-offset_m, range_m);  // left of the normal by offset_m
    return approach_lateral_mps(g, e);
  };
  EXPECT_DOUBLE_EQ(lateral(2.0, 0.07), 0.0);                   // 0.035 rad: inside psi_L
  EXPECT_DOUBLE_EQ(lateral(2.0, 0.09), -g.lateral_speed_mps);  // 0.045 rad: moved right
  EXPECT_DOUBLE_EQ(lateral(2.0, -0.09), g.lateral_speed_mps);
  EXPECT_DOUBLE_EQ(lateral(0.6, 0.035), 0.0);  // 0.058 rad, beyond psi_L, but 3.5 cm across
  EXPECT_DOUBLE_EQ(lateral(0.6, -0.035), 0.0);
  EXPECT_DOUBLE_EQ(lateral(0.6, 0.045), -g.lateral_speed_mps);
  EXPECT_DOUBLE_EQ(lateral(0.6, -0.045), g.lateral_speed_mps);
}

// The crossing's height hold: climbs when below the target height, descends when above,
// proportionally, saturated both ways; zero on the target.
TEST(HeightHold, ProportionalTowardTheTargetAndSaturated) {
  EXPECT_DOUBLE_EQ(height_hold_vz_mps(0.87, 0.87, 1.0, 0.1), 0.0);
  EXPECT_NEAR(height_hold_vz_mps(0.87, 0.82, 1.0, 0.1), 0.05, 1e-12);
  EXPECT_NEAR(height_hold_vz_mps(0.87, 0.92, 1.0, 0.1), -0.05, 1e-12);
  EXPECT_DOUBLE_EQ(height_hold_vz_mps(0.87, 0.60, 1.0, 0.1), 0.1);
  EXPECT_DOUBLE_EQ(height_hold_vz_mps(0.87, 1.20, 1.0, 0.1), -0.1);
  EXPECT_DOUBLE_EQ(height_hold_vz_mps(0.87, 0.60, 0.0, 0.1), 0.0);
}

TEST(RcConversion, SignsGainsRoundingAndSaturation) {
  RcConversion k;  // 100 rc per m/s, 66.7 rc per rad/s
  // Forward 0.25, left 0.1, up 0.05, turning left 0.3 rad/s:
  const RcSticks r = to_rc({0.25, 0.1, 0.05, 0.3}, k);
  EXPECT_EQ(r, (RcSticks{-10, 25, 5, -20}));  // a right, b forward, c up, d clockwise
  EXPECT_EQ(r.text(), "rc -10 25 5 -20");
  EXPECT_EQ(to_rc({2.0, -3.0, -1.5, -4.0}, k), (RcSticks{100, 100, -100, 100}));
  EXPECT_EQ(to_rc({0.005, -0.005, 0.0049, 0.0}, k), (RcSticks{1, 1, 0, 0}));  // half away from 0
}

// The crossing's line at 0.4 m/s with a 1.9 cm/m aim asks for 0.76 of a stick sideways: plain
// rounding sends 1 every time (32 % too much); carried, the sticks average the command.
TEST(RcConversion, CarriedRoundingAveragesTheExactCommand) {
  RcConversion k;
  const VelocityCommand line{0.4 * 1.1, -0.4 * 0.019, 0.02, 0.0};  // forward 44, right 0.76
  EXPECT_EQ(to_rc(line, k).a, 1);
  StickCarry carry;
  int sum_a = 0, sum_b = 0;
  for (int i = 0; i < 100; ++i) {
    const RcSticks r = to_rc_carried(line, k, carry);
    EXPECT_TRUE(r.a == 0 || r.a == 1) << r.a;
    EXPECT_EQ(r.c, 2);  // vertical and yaw round as to_rc
    EXPECT_EQ(r.d, 0);
    sum_a += r.a;
    sum_b += r.b;
    EXPECT_LE(std::abs(carry.a), 0.5 + 1e-12);
  }
  EXPECT_NEAR(sum_a / 100.0, 0.76, 0.01);
  EXPECT_NEAR(sum_b / 100.0, 44.0, 0.01);
  // Saturated: nothing owed later (the carry stays within a stick).
  StickCarry sat;
  for (int i = 0; i < 10; ++i) EXPECT_EQ(to_rc_carried({2.0, 0.0, 0.0, 0.0}, k, sat).b, 100);
  EXPECT_LE(std::abs(sat.b), 1.0);
  EXPECT_LE(std::abs(to_rc_carried({0.25, 0.0, 0.0, 0.0}, k, sat).b - 25), 1);
}

// Sticks carry the rounding only while they fly a line: set, hover or a zeroing hold ends it.
TEST(Sticks, FlyLineCarriesTheRoundingUntilTheNextCommand) {
  FlightConfig config;
  Sticks sticks(config);
  const VelocityCommand line{0.3, -0.003, 0.0, 0.0};  // 0.3 of a stick to the right
  sticks.fly_line(line, 0);
  int sum_a = 0;
  for (int i = 1; i <= 10; ++i) sum_a += sticks.due(seconds_to_ns(0.1 * i), false)->a;
  EXPECT_EQ(sum_a, 3);
  sticks.set(line, seconds_to_ns(1.0));
  for (int i = 11; i <= 20; ++i) EXPECT_EQ(sticks.due(seconds_to_ns(0.1 * i), false)->a, 0);
  sticks.fly_line(line, seconds_to_ns(2.0));
  sticks.hover();
  for (int i = 21; i <= 25; ++i) EXPECT_EQ(*sticks.due(seconds_to_ns(0.1 * i), false), RcSticks{});
}

// The heading law still commanding a turn at the gate turns the vehicle on after the pose
// (kHeadingCarry_s); the crossing holds the heading it settles on, so the body-frame line is
// planned on that heading: turned by it, it lies along the line through the cell centre.
TEST(CrossingPlan, FliesTheLineOnTheHeadingTheCommandedTurnSettlesOn) {
  const FlightConfig config;
  PoseEstimate pose;
  pose.X_FB.translation() = Eigen::Vector3d(-0.6, 0.03, 0.01);
  pose.yaw_rad = 0.02;
  const Eigen::Vector2d d_K = crossing_direction_K(config.shelf, pose).head<2>();
  const double rate = 0.03;  // two yaw sticks counter-clockwise
  const CrossingPlan still = plan_crossing(config, pose, 0.0, 0.5, 1.0, Eigen::Vector2d::Zero(), 0.2);
  const CrossingPlan turning = plan_crossing(config, pose, rate, 0.5, 1.0, Eigen::Vector2d::Zero(), 0.2);
  const double settled = pose.yaw_rad + rate * kHeadingCarry_s;
  EXPECT_LT((Eigen::Rotation2Dd(pose.yaw_rad) * still.dir_B - d_K).norm(), 1e-12);
  EXPECT_LT((Eigen::Rotation2Dd(settled) * turning.dir_B - d_K).norm(), 1e-12);
  // The turning plan aims 0.9 deg clockwise of the still one in the body: right of it.
  EXPECT_NEAR(std::atan2(turning.dir_B.y(), turning.dir_B.x()) - std::atan2(still.dir_B.y(), still.dir_B.x()),
              -rate * kHeadingCarry_s, 1e-12);
  // The odometry's axis turns alike: the same line in O.
  EXPECT_LT((turning.end.axis_O - still.end.axis_O).norm(), 1e-12);
  EXPECT_DOUBLE_EQ(turning.end.line_m, still.end.line_m);
}

}  // namespace
}  // namespace shelfcross::flight_sw
