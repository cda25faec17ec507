// The crossing's own readings (crossing_readings.hpp) on synthetic state records at 10 Hz: a
// height hold that follows the range climbs over the cell's bottom beam while h stays put, and
// the climb is read from the vertical speed once the range has stepped; a fused hold, or a
// climb the vertical speed and h both show, reads none; vgx = vgy = 0 exactly while flying
// says the VPS is lost, and what is flown meanwhile is counted at the speed last read.

#include <cmath>
#include <optional>

#include <gtest/gtest.h>

#include "flight_sw/guidance/crossing_readings.hpp"

namespace shelfcross::flight_sw {
namespace {

// A record at t_s: the state height h, the range tof, the vertical speed and the horizontal
// ones, each in the SDK's steps (1 cm, 1 cm, 0.1 m/s).
StateRecord record(double t_s, double h_m, std::optional<double> tof_m, double vz_mps, double vx_mps = 0.4,
                   double vy_mps = 0.0) {
  StateRecord s;
  s.t_ns = seconds_to_ns(t_s);
  s.height_m = std::round(h_m * 100.0) / 100.0;
  if (tof_m) s.tof_m = std::round(*tof_m * 100.0) / 100.0;
  s.vz_H_mps = std::round(vz_mps * 10.0) / 10.0;
  s.vx_H_mps = std::round(vx_mps * 10.0) / 10.0;
  s.vy_H_mps = std::round(vy_mps * 10.0) / 10.0;
  return s;
}

// The crossing of L2 at 0.81 m: the range reads the floor (0.81 m) for 0.5 s, then the box of
// the cell below, 0.53 m up (0.28 m). A hold following the range fully with a 0.5 s time
// constant climbs toward 0.53 m; h stays at 0.81 m, the vertical speed shows the climb. By 0.4 s
// over the box the offset read is the climb, within the 0.1 m/s steps' error, and the vehicle's
// height is h less it.
TEST(CrossingReadings, AClimbTheHoldHidesFromHIsReadFromTheVerticalSpeed) {
  CrossingReadings r;
  double z = 0.81;
  for (int k = 0; k <= 9; ++k) {
    const double t = 0.1 * k, over_s = t - 0.5;
    const double climb = over_s > 0.0 ? 0.53 * (1.0 - std::exp(-over_s / 0.5)) : 0.0;
    const double vz = over_s > 0.0 ? 0.53 / 0.5 * std::exp(-over_s / 0.5) : 0.0;
    z = 0.81 + climb;
    r.on_state(record(t, 0.81, over_s >= 0.0 ? z - 0.53 : z, vz), true);
    if (over_s < 0.0) {
      EXPECT_EQ(r.hold_offset_m(), 0.0) << t;
    }
  }
  EXPECT_TRUE(r.range_stepped());
  EXPECT_NEAR(-r.hold_offset_m(), z - 0.81, 0.03);
  EXPECT_FALSE(r.vps_lost());
}

// A fused hold over the same step: the range steps, h and the vertical speed show nothing: no
// offset. A climb commanded over the floor, which h and the vertical speed both show: none.
TEST(CrossingReadings, AFusedHoldOrACommandedClimbReadsNoOffset) {
  CrossingReadings fused, commanded;
  for (int k = 0; k <= 10; ++k) {
    const double t = 0.1 * k;
    fused.on_state(record(t, 0.81, t >= 0.5 ? 0.28 : 0.81, 0.0), true);
    commanded.on_state(record(t, 0.81 + 0.1 * t, 0.81 + 0.1 * t, 0.1), true);
  }
  EXPECT_TRUE(fused.range_stepped());
  EXPECT_EQ(fused.hold_offset_m(), 0.0);
  EXPECT_FALSE(commanded.range_stepped());
  EXPECT_EQ(commanded.hold_offset_m(), 0.0);
}

// The VPS lost (below its range over the box): vgx = vgy = 0 exactly on two records in a row
// while flying. One such record is a flicker; while not flying (the crossing's first half
// second, the autopilot still accelerating) none counts.
TEST(CrossingReadings, ZeroSpeedsWhileFlyingSayTheVpsIsLost) {
  CrossingReadings r;
  r.on_state(record(0.0, 0.81, 0.81, 0.0, 0.0), false);
  r.on_state(record(0.1, 0.81, 0.81, 0.0, 0.0), false);
  EXPECT_FALSE(r.vps_lost());
  r.on_state(record(0.6, 0.81, 0.81, 0.0, 0.4), true);
  r.on_state(record(0.7, 0.81, 0.28, 0.0, 0.0), true);
  EXPECT_FALSE(r.vps_lost());
  r.on_state(record(0.8, 0.81, 0.28, 0.0, 0.4), true);
  r.on_state(record(0.9, 0.81, 0.28, 0.0, 0.0), true);
  r.on_state(record(1.0, 0.81, 0.28, 0.0, 0.0, 0.0), true);
  EXPECT_TRUE(r.vps_lost());
}

// The VPS lost over the cell's bottom beam after 0.6 s of flight at 0.4 m/s (read 0.3-0.5 in
// its steps): each record reading nothing adds its 0.1 s at the mean of the last five speeds
// read, not at a speed gain from elsewhere; the records before the crossing flies (the
// autopilot's lag) and a record that reads again add nothing blind.
TEST(CrossingReadings, WhatTheVpsMissesIsFlownAtTheSpeedItLastRead) {
  CrossingReadings r;
  r.on_state(record(0.0, 0.81, 0.81, 0.0, 0.0), false);
  r.on_state(record(0.1, 0.81, 0.81, 0.0, 0.0), false);  // not yet flying: nothing read, nothing blind
  EXPECT_FALSE(r.speed_mps());
  const double read[] = {0.3, 0.4, 0.5, 0.4, 0.4, 0.5};
  for (int k = 0; k < 6; ++k) r.on_state(record(0.2 + 0.1 * k, 0.81, 0.81, 0.0, read[k]), true);
  ASSERT_TRUE(r.speed_mps());
  EXPECT_NEAR(*r.speed_mps(), 0.44, 1e-9);  // the last five: 0.4 0.5 0.4 0.4 0.5
  EXPECT_EQ(r.blind_m(), 0.0);
  for (int k = 0; k < 4; ++k) r.on_state(record(0.8 + 0.1 * k, 0.81, 0.16, 0.0, 0.0), true);
  EXPECT_TRUE(r.vps_lost());
  EXPECT_NEAR(r.blind_m(), 4 * 0.1 * 0.44, 1e-9);
  r.on_state(record(1.2, 0.81, 0.81, 0.0, 0.4), true);  // the floor behind: read again
  EXPECT_NEAR(r.blind_m(), 4 * 0.1 * 0.44, 1e-9);
  EXPECT_NEAR(*r.speed_mps(), 0.44, 1e-9);  // the speeds read before the loss, and this one
}

}  // namespace
}  // namespace shelfcross::flight_sw
