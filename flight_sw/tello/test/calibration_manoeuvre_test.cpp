// The calibration manoeuvre of tello_pilot --fly-calibration: short, inside the SDK's and the
// slow mode's limits, one axis at a time, hovering between, each axis back where it began.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>

#include "flight_sw/tello/calibration_manoeuvre.hpp"

namespace shelfcross::tello {
namespace {

TEST(CalibrationManoeuvre, IsShortOneAxisAtATimeAndHoversBetween) {
  const CalibrationManoeuvre m;
  EXPECT_LT(m.duration_s(), 50.0);  // with takeoff and landing, under a minute of flight
  ASSERT_FALSE(m.steps().empty());
  EXPECT_EQ(m.steps().front().sticks, (std::array<int, 4>{0, 0, 0, 0}));
  EXPECT_EQ(m.steps().back().sticks, (std::array<int, 4>{0, 0, 0, 0}));
  std::array<int, 4> pulses{};
  for (size_t i = 0; i < m.steps().size(); ++i) {
    const ManoeuvreStep& s = m.steps()[i];
    int moving = 0;
    for (int v : s.sticks) {
      EXPECT_LE(std::abs(v), 100);
      moving += v != 0 ? 1 : 0;
    }
    EXPECT_LE(moving, 1) << s.what;
    if (moving == 1) {
      // Every pulse is followed by a hover.
      ASSERT_LT(i + 1, m.steps().size());
      EXPECT_EQ(m.steps()[i + 1].sticks, (std::array<int, 4>{0, 0, 0, 0})) << s.what;
      for (int k = 0; k < 4; ++k) pulses[static_cast<size_t>(k)] += s.sticks[static_cast<size_t>(k)] != 0 ? 1 : 0;
    }
  }
  EXPECT_EQ(pulses, (std::array<int, 4>{4, 4, 4, 2}));  // right, forward, up: two pairs; yaw one
}

TEST(CalibrationManoeuvre, StaysInsideTheSlowModesTiltForTheStrongestFastestDrone) {
  // A horizontal step of s / 100 asks for K s / (100 tau): K 1.25 m/s, tau 0.3 s at worst.
  const CalibrationManoeuvre m;
  const double tilt_limit_mps2 = 9.80665 * std::tan(9.0 * 3.14159265358979323846 / 180.0);
  for (const ManoeuvreStep& s : m.steps()) {
    const int horizontal = std::max(std::abs(s.sticks[0]), std::abs(s.sticks[1]));
    EXPECT_LT(1.25 * horizontal / 100.0 / 0.3, tilt_limit_mps2) << s.what;
  }
}

TEST(CalibrationManoeuvre, StepAtFollowsTheScheduleAndEnds) {
  const CalibrationManoeuvre m;
  EXPECT_EQ(m.step_at(-0.1), nullptr);
  EXPECT_EQ(m.step_at(0.0), &m.steps()[0]);
  EXPECT_EQ(m.step_at(m.steps()[0].duration_s), &m.steps()[1]);
  EXPECT_EQ(m.step_at(m.duration_s()), nullptr);
  EXPECT_THROW(CalibrationManoeuvre(CalibrationAmplitudes{.horizontal = 90}), std::invalid_argument);
}

}  // namespace
}  // namespace shelfcross::tello
