// The Tello's answer to its sticks measured in flight: a first-order autopilot of known gain and
// lag, driven by rc datagrams at 20 Hz and reporting state records at 10 Hz in the SDK's
// resolution (0.1 m/s, 1 cm, 1 degree), is identified, and its sticks are scaled only when it
// answers more strongly than the certified envelope.

#include <algorithm>
#include <cmath>
#include <deque>
#include <functional>
#include <vector>

#include <gtest/gtest.h>

#include "flight_sw/control/stick_response.hpp"
#include "shelfcross/rotation.hpp"

namespace shelfcross::flight_sw {
namespace {

/// A Tello whose velocity (body x, y, z) and yaw rate follow k u with lag tau after a dead time
/// of `delay_steps` steps; u the sticks' nominal rates. The state record quantizes as the SDK
/// does.
struct FirstOrderTello {
  double gain = 1.0, tau_s = 0.5;
  int delay_steps = 0;
  std::vector<double> v = std::vector<double>(4, 0.0);  ///< vx, vy, vz, yaw rate
  double height_m = 1.0, yaw_rad = 0.0;
  std::deque<std::vector<double>> pending;  ///< sticks not yet acting

  void step(const std::vector<double>& u_sent, double dt) {
    pending.push_back(u_sent);
    if (static_cast<int>(pending.size()) <= delay_steps) return step_with({0.0, 0.0, 0.0, 0.0}, dt);
    const std::vector<double> u = pending.front();
    pending.pop_front();
    step_with(u, dt);
  }
  void step_with(const std::vector<double>& u, double dt) {
    const double a = std::exp(-dt / tau_s);
    for (int i = 0; i < 4; ++i) v[i] = gain * u[i] + (v[i] - gain * u[i]) * a;
    height_m += v[2] * dt;
    yaw_rad += v[3] * dt;
  }
  StateRecord record(TimeNs t_ns) const {
    StateRecord s;
    s.t_ns = t_ns;
    s.vx_H_mps = std::round(v[0] * 10.0) / 10.0;
    s.vy_H_mps = std::round(v[1] * 10.0) / 10.0;
    s.vz_H_mps = std::round(v[2] * 10.0) / 10.0;
    s.height_m = std::round(height_m * 100.0) / 100.0;
    s.yaw_rad = deg_to_rad(std::round(rad_to_deg(yaw_rad)));
    return s;
  }
};

/// The command of a short approach-like pattern at time t: forward at 0.25 m/s, a lateral
/// step, a climb and a descent, turns both ways.
VelocityCommand pattern(double t) {
  const double p = std::fmod(t, 8.0);
  VelocityCommand v;
  v.vx_B_mps = p < 4.0 ? 0.25 : 0.0;
  v.vy_B_mps = p >= 2.0 && p < 3.0 ? -0.08 : (p >= 5.0 && p < 6.0 ? 0.08 : 0.0);
  v.vz_mps = p < 1.5 ? 0.2 : (p >= 4.0 && p < 5.5 ? -0.2 : 0.0);
  v.yaw_rate_radps = p >= 1.0 && p < 2.5 ? -0.225 : (p >= 6.0 && p < 7.5 ? 0.225 : 0.0);
  return v;
}

/// The sticks at time t given the last state record.
using Law = std::function<VelocityCommand(double t, const StateRecord& last)>;

/// Flies `seconds` of the law (by default the open-loop pattern; sticks sent when `driven`),
/// the response fed as the flight software feeds it.
void fly(StickResponse& response, FirstOrderTello& tello, double seconds, bool driven = true,
         const Law& law = [](double t, const StateRecord&) { return pattern(t); }) {
  const RcConversion nominal;
  const double dt = 0.01;
  RcSticks held;
  StateRecord last = tello.record(0);
  for (int i = 1; i <= static_cast<int>(std::lround(seconds / dt)); ++i) {
    const double t = i * dt;
    const TimeNs t_ns = seconds_to_ns(t);
    if (driven && i % 5 == 0) {
      held = to_rc(law(t, last), response.conversion());  // as Sticks::due sends them
      response.on_sent(held, t_ns);
    }
    // What the Tello makes of the sticks: their nominal rates (a right, d clockwise).
    const std::vector<double> u = driven ? std::vector<double>{held.b / nominal.rc_per_mps_horizontal,
                                                              -held.a / nominal.rc_per_mps_horizontal,
                                                              held.c / nominal.rc_per_mps_vertical,
                                                              -held.d / nominal.rc_per_radps_yaw}
                                         : std::vector<double>{0.0, 0.0, 0.3, 0.0};  // a take-off climb
    tello.step(u, dt);
    if (i % 10 == 0) {
      last = tello.record(t_ns);
      response.on_state(last);
    }
  }
}

TEST(StickResponse, AStrongSlowAutopilotIsIdentifiedAndItsSticksScaled) {
  StickResponse response{RcConversion{}};
  FirstOrderTello tello{2.0, 1.1};
  fly(response, tello, 30.0);
  for (StickAxis axis : {StickAxis::Horizontal, StickAxis::Vertical, StickAxis::Yaw}) {
    const std::optional<AxisResponse> e = response.estimate(axis);
    ASSERT_TRUE(e.has_value());
    EXPECT_NEAR(e->gain, 2.0, 0.1) << static_cast<int>(axis);
    EXPECT_NEAR(e->tau_s, 1.1, 0.25) << static_cast<int>(axis);
    EXPECT_NEAR(response.scale(axis), 1.0 / e->gain, 1e-12) << static_cast<int>(axis);
  }
  const RcConversion k = response.conversion();
  EXPECT_NEAR(k.rc_per_mps_horizontal, 50.0, 3.0);
  EXPECT_NEAR(k.rc_per_mps_vertical, 50.0, 3.0);
  EXPECT_NEAR(k.rc_per_radps_yaw, 33.3, 2.0);
  EXPECT_NE(stick_scaling_event(StickAxis::Vertical, response).find("vertical sticks scaled by 0.5"),
            std::string::npos)
      << stick_scaling_event(StickAxis::Vertical, response);
}

TEST(StickResponse, AnAutopilotInsideTheCertifiedRangeKeepsItsSticks) {
  // Without any air to dither them, the 0.1 m/s steps are the horizontal estimate's worst case:
  // a steady 0.25 m/s approaching from below reads 0.2, 20 % low (and 0.27 reads 0.3, 11 %
  // high); the height's 1 cm and the yaw's degree leave the others within a few per cent.
  for (double gain : {0.6, 1.0, 1.25}) {
    StickResponse response{RcConversion{}};
    FirstOrderTello tello{gain, 0.5};
    fly(response, tello, 30.0);
    for (StickAxis axis : {StickAxis::Horizontal, StickAxis::Vertical, StickAxis::Yaw}) {
      const std::optional<AxisResponse> e = response.estimate(axis);
      ASSERT_TRUE(e.has_value());
      const double tolerance = axis == StickAxis::Horizontal ? 0.3 : 0.1;
      EXPECT_NEAR(e->gain, gain, tolerance * gain) << gain << " " << static_cast<int>(axis);
      EXPECT_EQ(response.scale(axis), 1.0) << gain << " " << static_cast<int>(axis);
    }
  }
}

TEST(StickResponse, ADeadTimeInAClosedLoopDoesNotReadAsAStrongerGain) {
  // The approach's loops close through the vehicle: the heading and height laws' sticks shrink
  // as the error closes, so a response to older, larger sticks would read as a stronger gain
  // if the command's dead time (the link, the autopilot's inner loops) were not fitted. A Tello
  // at 1.2, inside the certified range, with 0.1 s of dead time and a 0.3 s lag, flown by
  // proportional laws to targets that step every 4 s (the heading's kp 1.5/s, the height's
  // 1/s): each axis reads within 3 % and keeps its sticks.
  StickResponse response{RcConversion{}};
  FirstOrderTello tello{1.2, 0.3, 10};
  const Law closed = [](double t, const StateRecord& last) {
    const bool first_half = std::fmod(t, 8.0) < 4.0;
    VelocityCommand v = pattern(t);
    v.yaw_rate_radps = 1.5 * ((first_half ? 0.3 : -0.3) - last.yaw_rad);
    v.vz_mps = std::clamp(1.0 * ((first_half ? 1.3 : 1.0) - last.height_m), -0.4, 0.4);
    return v;
  };
  fly(response, tello, 40.0, true, closed);
  for (StickAxis axis : {StickAxis::Vertical, StickAxis::Yaw}) {
    const std::optional<AxisResponse> e = response.estimate(axis);
    ASSERT_TRUE(e.has_value());
    EXPECT_NEAR(e->gain, 1.2, 0.03 * 1.2) << stick_axis_name(axis);
    EXPECT_NEAR(e->delay_s, 0.1, 0.051) << stick_axis_name(axis);
    EXPECT_EQ(response.scale(axis), 1.0) << stick_axis_name(axis);
  }
}

TEST(StickResponse, TheSummaryNamesWhatWasMeasuredAndWhatWasNot) {
  StickEstimates sticks;
  sticks[1] = AxisResponse{2.125, 0.03125, 1.2, 0.05, 215, 0.5};
  EXPECT_EQ(stick_response_text(sticks),
            "horizontal not measured; vertical 2.12 (+-0.03, lag 1.20 s after 0.05 s, 215 windows) sent at 0.50; "
            "yaw not measured");
}

TEST(StickResponse, MotionWithoutSticksIsNotEvidence) {
  // A take-off: the Tello climbs on its own, no rc datagram goes out; nothing is measured.
  StickResponse response{RcConversion{}};
  FirstOrderTello tello{1.0, 0.5};
  fly(response, tello, 10.0, false);
  EXPECT_FALSE(response.estimate(StickAxis::Vertical).has_value());
  EXPECT_FALSE(response.estimate(StickAxis::Horizontal).has_value());
  EXPECT_EQ(response.conversion().rc_per_mps_vertical, RcConversion{}.rc_per_mps_vertical);
}

}  // namespace
}  // namespace shelfcross::flight_sw
