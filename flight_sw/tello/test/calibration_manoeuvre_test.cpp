// The calibration manoeuvre of tello_pilot --fly-calibration: short, inside the SDK's and the
// slow mode's limits, one axis at a time, hovering between, each axis back near where it began.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>

#include "flight_sw/tello/calibration_manoeuvre.hpp"
#include "shelfcross/gravity.hpp"
#include "shelfcross/rotation.hpp"

namespace shelfcross::tello {
namespace {

TEST(CalibrationManoeuvre, IsShortOneAxisAtATimeAndHoversBetween) {
  const CalibrationManoeuvre m;
  EXPECT_LT(m.duration_s(), 50.0);  // with takeoff and landing, under a minute of flight
  ASSERT_FALSE(m.steps().empty());
  const std::array<int, 4> centred{};
  EXPECT_EQ(m.steps().front().sticks, centred);
  EXPECT_EQ(m.steps().back().sticks, centred);
  std::array<int, 4> pulses{}, doublets{};
  for (size_t i = 0; i < m.steps().size(); ++i) {
    const ManoeuvreStep& s = m.steps()[i];
    int moving = 0;
    for (int v : s.sticks) {
      EXPECT_LE(std::abs(v), 100);
      moving += v != 0 ? 1 : 0;
    }
    EXPECT_LE(moving, 1) << s.what;
    if (moving == 0) continue;
    // Every pulse is followed by a hover, or by its doublet's other half and then a hover.
    size_t k = 0;
    while (s.sticks[k] == 0) ++k;
    ASSERT_LT(i + 1, m.steps().size());
    const ManoeuvreStep& next = m.steps()[i + 1];
    if (next.sticks[k] == -s.sticks[k] && std::count(next.sticks.begin(), next.sticks.end(), 0) == 3) {
      ASSERT_LT(i + 2, m.steps().size());
      EXPECT_EQ(m.steps()[i + 2].sticks, centred) << next.what;
      ++doublets[k];
      ++i;
    } else {
      EXPECT_EQ(next.sticks, centred) << s.what;
      ++pulses[k];
    }
  }
  // right, forward: four pulses each; up, clockwise: five doublets each.
  EXPECT_EQ(pulses, (std::array<int, 4>{4, 4, 0, 0}));
  EXPECT_EQ(doublets, (std::array<int, 4>{0, 0, 5, 5}));
}

TEST(CalibrationManoeuvre, EachAxisSettlesBeforeItsNextPulse) {
  // An axis's edges: a doublet's halves 1 s apart at least; a pulse or doublet starts at least
  // 2.5 s (3.5 time constants of the slowest plausible drone, 0.7 s) after the axis's last edge.
  const CalibrationManoeuvre m;
  std::array<int, 4> previous{}, edges{};
  std::array<double, 4> last_edge_s{-1e9, -1e9, -1e9, -1e9};
  double t = 0.0;
  for (const ManoeuvreStep& s : m.steps()) {
    for (size_t k = 0; k < 4; ++k) {
      if (s.sticks[k] == previous[k]) continue;
      const double since = t - last_edge_s[k];
      EXPECT_GE(since, previous[k] == 0 ? 2.5 - 1e-9 : 1.0 - 1e-9) << s.what << " at " << t << " s";
      last_edge_s[k] = t;
      ++edges[k];
    }
    previous = s.sticks;
    t += s.duration_s;
  }
  EXPECT_EQ(edges, (std::array<int, 4>{8, 8, 15, 15}));
}

TEST(CalibrationManoeuvre, HeightNeverGoesBelowTheTakeoffAndEachAxisEndsWhereItBegan) {
  // Integrated stick (the response's displacement at unit gain, lags aside): height never
  // below its start, heading and horizontal within one pulse of it, all back near the start.
  const CalibrationManoeuvre m;
  std::array<double, 4> position{}, lowest{}, highest{};
  for (const ManoeuvreStep& s : m.steps()) {
    for (size_t k = 0; k < 4; ++k) {
      position[k] += s.sticks[k] / 100.0 * s.duration_s;
      lowest[k] = std::min(lowest[k], position[k]);
      highest[k] = std::max(highest[k], position[k]);
    }
  }
  EXPECT_GE(lowest[2], -1e-9);
  EXPECT_NEAR(position[2], 0.0, 1e-9);
  EXPECT_NEAR(position[3], 0.0, 1e-9);
  // At 1.25 m/s and 1.875 rad/s at full stick: 0.6 m above the takeoff, 65 deg each way.
  EXPECT_LE(1.25 * highest[2], 0.61);
  EXPECT_LE(1.875 * std::max(highest[3], -lowest[3]) * 180.0 / 3.14159265358979323846, 65.0);
  for (size_t k : {0u, 1u}) EXPECT_LE(1.25 * std::max(highest[k], -lowest[k]), 0.9) << k;
}

TEST(CalibrationManoeuvre, StaysInsideTheSlowModesTiltForTheStrongestFastestDrone) {
  // A horizontal step of s / 100 asks for K s / (100 tau): K 1.25 m/s, tau 0.3 s at worst.
  const CalibrationManoeuvre m;
  const double tilt_limit_mps2 = kStandardGravity_mps2 * std::tan(deg_to_rad(9.0));
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

// The senses block: first, after the first hover: 15 s of still hover, back at stick 20 for the
// board's distance at 0.2 m/s, 8 s over the board, forward as long, 2.5 s of hover; then the
// manoeuvre as without it. Back where it began; refused for a board too near or too far.
TEST(CalibrationManoeuvre, TheSensesBlockHoversStillThenPassesOverTheBoardAndBack) {
  const CalibrationManoeuvre plain;
  const CalibrationManoeuvre m(CalibrationAmplitudes{}, CalibrationSenses{1.5});
  ASSERT_EQ(m.steps().size(), plain.steps().size() + 5);
  const std::array<int, 4> centred{};
  EXPECT_EQ(m.steps()[1].sticks, centred);
  EXPECT_DOUBLE_EQ(m.steps()[1].duration_s, CalibrationManoeuvre::kStillHover_s);
  EXPECT_EQ(m.steps()[2].sticks, (std::array<int, 4>{0, -20, 0, 0}));
  EXPECT_EQ(m.steps()[4].sticks, (std::array<int, 4>{0, 20, 0, 0}));
  EXPECT_DOUBLE_EQ(m.steps()[2].duration_s, 7.5);
  EXPECT_DOUBLE_EQ(m.steps()[4].duration_s, 7.5);
  EXPECT_GE(m.steps()[3].duration_s, 8.0);  // four of the slowest height hold's 2 s
  EXPECT_GE(m.steps()[5].duration_s, 2.5);  // the forward axis settles before its first pulse
  for (size_t i = 1; i < plain.steps().size(); ++i) EXPECT_EQ(m.steps()[i + 5].sticks, plain.steps()[i].sticks) << i;
  EXPECT_NEAR(m.duration_s(), plain.duration_s() + 40.5, 1e-9);
  double x = 0.0, farthest = 0.0;
  for (size_t i = 0; i < m.steps().size(); ++i) {
    x += m.steps()[i].sticks[1] / 100.0 * m.steps()[i].duration_s;  // at 1 m/s at full stick
    farthest = std::min(farthest, x);
    if (i == 5) {
      EXPECT_NEAR(x, 0.0, 1e-9);  // back over the take-off point
    }
  }
  EXPECT_NEAR(farthest, -1.5, 1e-9);  // the board's middle
  EXPECT_THROW(CalibrationManoeuvre(CalibrationAmplitudes{}, CalibrationSenses{0.9}), std::invalid_argument);
  EXPECT_THROW(CalibrationManoeuvre(CalibrationAmplitudes{}, CalibrationSenses{2.6}), std::invalid_argument);
}

}  // namespace
}  // namespace shelfcross::tello
