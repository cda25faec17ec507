// Control laws: PI step response and anti-windup, bang-off-bang and the approach's lateral law,
// rc conversion and saturation.

#include <cmath>

#include <gtest/gtest.h>

#include "flight_sw/control.hpp"
#include "flight_sw/guidance.hpp"

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

}  // namespace
}  // namespace shelfcross::flight_sw
