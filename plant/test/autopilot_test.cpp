// The simulated Tello firmware as an SDK user sees it: takeoff, rc responses with their
// configured time constants, tilt limits, landing, emergency, the watchdog, moves, replies.

#include <gtest/gtest.h>

#include <cmath>

#include "plant/simulated_tello.hpp"

namespace shelfcross::plant {
namespace {

constexpr double kDeg = 3.14159265358979323846 / 180.0;

// A Tello in SDK mode, hovering after `takeoff` (whose reply it checks).
struct Flight {
  explicit Flight(AutopilotParams ap = {}, WindParams wind = {}) : tello(VehicleParams{}, ap, wind, 11) {
    EXPECT_EQ(tello.submit(0, "command"), std::optional<std::string>("ok"));
    EXPECT_EQ(tello.submit(seconds_to_ns(0.5), "takeoff"), std::nullopt);
  }
  void take_off() {
    for (int k = 1; k <= 800 && replies.empty(); ++k) step(seconds_to_ns(0.5) + k * 10'000'000LL);
    ASSERT_EQ(replies.size(), 1u);
    takeoff_reply_s = ns_to_seconds(replies[0].t_ns) - 0.5;
    replies.clear();
  }
  void step(TimeNs t) {
    tello.step_to(t);
    for (auto& r : tello.take_replies()) replies.push_back(r);
  }
  // Steps in 2 ms ticks to t, calling f after each.
  template <class F>
  void run_until(TimeNs t_end, F f) {
    for (TimeNs t = tello.time_ns() + 2'000'000; t <= t_end; t += 2'000'000) {
      step(t);
      f();
    }
  }
  std::optional<std::string> send(const std::string& text) { return tello.submit(tello.time_ns(), text); }
  double t_s() const { return ns_to_seconds(tello.time_ns()); }
  SimulatedTello tello;
  std::vector<SdkReply> replies;
  double takeoff_reply_s = 0.0;
};

TEST(Autopilot, TakeoffClimbsToAboutOneMetreHoldsAndRepliesOkAfterAboutFourSeconds) {
  Flight f;
  EXPECT_EQ(f.tello.mode(), FlightMode::taking_off);
  f.take_off();
  EXPECT_EQ(f.tello.mode(), FlightMode::flying);
  EXPECT_GT(f.takeoff_reply_s, 3.0);
  EXPECT_LT(f.takeoff_reply_s, 5.5);
  EXPECT_NEAR(f.tello.state().p_WB_m.z(), 1.0, 0.05);
  // Holds: 10 s later (rc keep-alive) still there, not drifting.
  const Eigen::Vector3d p0 = f.tello.state().p_WB_m;
  double max_dev = 0.0;
  for (int i = 1; i <= 5; ++i) {
    f.run_until(f.tello.time_ns() + seconds_to_ns(2.0), [&] { max_dev = std::max(max_dev, (f.tello.state().p_WB_m - p0).norm()); });
    f.send("rc 0 0 0 0");
  }
  EXPECT_LT(max_dev, 0.03);
  EXPECT_NEAR(f.tello.state().p_WB_m.z(), 1.0, 0.03);
  EXPECT_EQ(f.send("height?"), std::optional<std::string>("10dm"));
  EXPECT_EQ(f.send("takeoff"), std::optional<std::string>("error"));  // already flying
}

// Time for a scalar response y(t) starting at y0 to cover 63.2 % of the way to y_final.
template <class Sample>
double time_to_63_percent(Flight& f, double duration_s, double y0, double y_final, Sample sample) {
  const double t0 = f.t_s();
  double t63 = -1.0;
  f.run_until(f.tello.time_ns() + seconds_to_ns(duration_s), [&] {
    if (t63 < 0.0 && (sample() - y0) / (y_final - y0) >= 1.0 - std::exp(-1.0)) t63 = f.t_s() - t0;
  });
  return t63;
}

void check_forward_response(AutopilotParams ap, double expected_speed_mps) {
  const double tau = ap.velocity_time_constant_s;
  Flight f(ap);
  f.take_off();
  f.send("rc 0 50 0 0");  // half stick forward, along the heading (x_W here)
  const double t63 = time_to_63_percent(f, 5.0, 0.0, expected_speed_mps, [&] { return f.tello.state().v_WB_W_mps.x(); });
  EXPECT_NEAR(t63, tau, 0.2 * tau + 0.03) << "tau " << tau;
  EXPECT_NEAR(f.tello.state().v_WB_W_mps.x(), expected_speed_mps, 0.02);
  EXPECT_NEAR(f.tello.state().v_WB_W_mps.y(), 0.0, 0.01);
  EXPECT_NEAR(f.tello.state().p_WB_m.z(), 1.0, 0.05);
}

TEST(Autopilot, RcForwardConvergesToConfiguredSpeedWithConfiguredTimeConstant) {
  check_forward_response(AutopilotParams{}, 0.5);  // defaults: slow mode, 1 m/s at full stick, 0.5 s
  // Dispersed time constants and gains (fast mode, so that the 9 deg tilt limit does not cap
  // the initial acceleration of the quickest ones).
  for (const double tau : {0.3, 0.5, 0.7}) {
    AutopilotParams ap;
    ap.fast_mode = true;
    ap.velocity_time_constant_s = tau;
    ap.rc_horizontal_mps_at_100 = 1.5;
    check_forward_response(ap, 0.5 * 1.5 * ap.fast_mode_speed_factor);
  }
}

TEST(Autopilot, SlowModeTiltLimitCapsTheAcceleration) {
  AutopilotParams ap;
  ap.velocity_time_constant_s = 0.3;
  ap.rc_horizontal_mps_at_100 = 2.0;
  Flight f(ap);
  f.take_off();
  f.send("rc 0 50 0 0");  // 1 m/s in 0.3 s would need 3.3 m/s^2 > g tan(9 deg) = 1.55 m/s^2
  const double t63 = time_to_63_percent(f, 5.0, 0.0, 1.0, [&] { return f.tello.state().v_WB_W_mps.x(); });
  EXPECT_GT(t63, 0.4);
  EXPECT_NEAR(f.tello.state().v_WB_W_mps.x(), 1.0, 0.02);
}

TEST(Autopilot, RcSticksFollowTheSdkSigns) {
  Flight f;
  f.take_off();
  f.send("rc 50 0 0 0");  // a > 0: right, i.e. -y here
  f.run_until(f.tello.time_ns() + seconds_to_ns(3.0), [] {});
  EXPECT_NEAR(f.tello.state().v_WB_W_mps.y(), -0.5, 0.03);
  f.send("rc 0 0 50 0");  // c > 0: up
  f.run_until(f.tello.time_ns() + seconds_to_ns(2.0), [] {});
  EXPECT_NEAR(f.tello.state().v_WB_W_mps.z(), 0.5, 0.03);
  EXPECT_NEAR(f.tello.state().v_WB_W_mps.y(), 0.0, 0.03);
}

TEST(Autopilot, YawRateStepHasConfiguredRateAndTimeConstant) {
  AutopilotParams ap;
  Flight f(ap);
  f.take_off();
  f.send("rc 0 0 0 100");  // full clockwise: yaw rate -1.5 rad/s in our (ccw-positive) frame
  const double r_final = -ap.rc_yaw_radps_at_100;
  const double t63 = time_to_63_percent(f, 1.5, 0.0, r_final, [&] {
    return (f.tello.state().q_WB * f.tello.state().w_WB_B_radps).z();  // yaw rate about z_W
  });
  EXPECT_NEAR(t63, ap.yaw_time_constant_s, 0.25 * ap.yaw_time_constant_s + 0.03);
  EXPECT_NEAR((f.tello.state().q_WB * f.tello.state().w_WB_B_radps).z(), r_final, 0.03);
  // Forward stick now flies along the new heading.
  f.send("rc 0 0 0 0");
  f.run_until(f.tello.time_ns() + seconds_to_ns(1.5), [] {});
  const double yaw = euler_zyx_from_quaternion(f.tello.state().q_WB).z();
  f.send("rc 0 60 0 0");
  f.run_until(f.tello.time_ns() + seconds_to_ns(4.0), [] {});
  const Eigen::Vector3d v = f.tello.state().v_WB_W_mps;
  EXPECT_NEAR(std::atan2(v.y(), v.x()), yaw, 0.03);
  EXPECT_EQ(f.send("attitude?")->substr(0, 6), "pitch:");
}

void check_tilt_limit(bool fast) {
  AutopilotParams ap;
  ap.fast_mode = fast;
  ap.rc_horizontal_mps_at_100 = 4.0;  // demand more than the tilt can give
  Flight f(ap);
  f.take_off();
  const double limit = fast ? 25.0 * kDeg : 9.0 * kDeg;
  double max_tilt = 0.0;
  const auto track = [&] { max_tilt = std::max(max_tilt, tilt_rad(f.tello.state().q_WB)); };
  for (const char* rc : {"rc 0 100 0 0", "rc 0 -100 0 0", "rc 100 100 0 100", "rc -100 -100 100 -100", "rc 0 0 -100 0", "rc 0 0 0 0"}) {
    f.send(rc);
    f.run_until(f.tello.time_ns() + seconds_to_ns(2.5), track);
  }
  EXPECT_LE(max_tilt, limit);
  EXPECT_GT(max_tilt, 0.8 * limit);  // it did lean on the limit
}

TEST(Autopilot, TiltNeverExceedsSlowModeLimit) { check_tilt_limit(false); }
TEST(Autopilot, TiltNeverExceedsFastModeLimit) { check_tilt_limit(true); }

TEST(Autopilot, RcIgnoredWhileLanded) {
  SimulatedTello tello(VehicleParams{}, AutopilotParams{}, WindParams{}, 1);
  EXPECT_EQ(tello.submit(0, "command"), std::optional<std::string>("ok"));
  EXPECT_EQ(tello.submit(seconds_to_ns(0.1), "rc 0 100 100 0"), std::nullopt);  // never a reply
  tello.step_to(seconds_to_ns(3.0));
  EXPECT_EQ(tello.mode(), FlightMode::landed);
  EXPECT_DOUBLE_EQ(tello.state().p_WB_m.z(), VehicleParams{}.rest_height_m());
  EXPECT_EQ(tello.state().rotor_speed_radps.norm(), 0.0);
  EXPECT_TRUE(tello.take_replies().empty());
  EXPECT_EQ(tello.submit(seconds_to_ns(3.0), "land"), std::optional<std::string>("error"));
  EXPECT_EQ(tello.submit(seconds_to_ns(3.1), "forward 50"), std::optional<std::string>("error"));
}

TEST(Autopilot, NothingIsAnsweredBeforeSdkMode) {
  SimulatedTello tello(VehicleParams{}, AutopilotParams{}, WindParams{}, 1);
  EXPECT_EQ(tello.submit(0, "takeoff"), std::nullopt);
  EXPECT_EQ(tello.submit(seconds_to_ns(0.1), "battery?"), std::nullopt);
  tello.step_to(seconds_to_ns(2.0));
  EXPECT_EQ(tello.mode(), FlightMode::landed);
}

TEST(Autopilot, WatchdogLandsAfterFifteenSecondsWithoutCommands) {
  Flight f;
  f.take_off();
  const double last_command_s = 0.5;  // the takeoff
  f.run_until(seconds_to_ns(last_command_s + 14.9), [] {});
  EXPECT_EQ(f.tello.mode(), FlightMode::flying);
  f.run_until(seconds_to_ns(last_command_s + 15.1), [] {});
  EXPECT_EQ(f.tello.mode(), FlightMode::landing);
  f.run_until(seconds_to_ns(last_command_s + 19.0), [] {});
  EXPECT_EQ(f.tello.mode(), FlightMode::landed);
  EXPECT_TRUE(f.replies.empty());  // nobody asked: no reply
  EXPECT_DOUBLE_EQ(f.tello.state().p_WB_m.z(), VehicleParams{}.rest_height_m());
}

TEST(Autopilot, KeepAliveRcPreventsTheWatchdog) {
  Flight f;
  f.take_off();
  for (int i = 0; i < 10; ++i) {
    f.run_until(f.tello.time_ns() + seconds_to_ns(3.0), [] {});
    f.send("rc 0 0 0 0");
  }
  EXPECT_EQ(f.tello.mode(), FlightMode::flying);
}

TEST(Autopilot, LandRepliesWhenDownAndStopsMotors) {
  Flight f;
  f.take_off();
  EXPECT_EQ(f.send("land"), std::nullopt);
  const double t_land = f.t_s();
  f.run_until(f.tello.time_ns() + seconds_to_ns(5.0), [] {});
  ASSERT_EQ(f.replies.size(), 1u);
  EXPECT_EQ(f.replies[0].text, "ok");
  const double took = ns_to_seconds(f.replies[0].t_ns) - t_land;
  EXPECT_GT(took, 1.5);  // ~1 m at 0.5 m/s
  EXPECT_LT(took, 3.0);
  EXPECT_EQ(f.tello.mode(), FlightMode::landed);
  EXPECT_EQ(f.tello.state().rotor_speed_radps.maxCoeff() < 1.0, true);
  EXPECT_EQ(f.send("tof?"), std::optional<std::string>("100mm"));  // the sensor reads 10 cm on the ground
}

TEST(Autopilot, EmergencyCutsMotorsAndTheVehicleFalls) {
  Flight f;
  f.take_off();
  EXPECT_EQ(f.send("emergency"), std::optional<std::string>("ok"));
  EXPECT_EQ(f.tello.mode(), FlightMode::emergency);
  f.run_until(f.tello.time_ns() + seconds_to_ns(0.3), [] {});
  EXPECT_LT(f.tello.state().v_WB_W_mps.z(), -1.5);  // falling freely (minus a little drag)
  f.run_until(f.tello.time_ns() + seconds_to_ns(1.5), [] {});
  EXPECT_EQ(f.tello.mode(), FlightMode::landed);
  EXPECT_DOUBLE_EQ(f.tello.state().p_WB_m.z(), VehicleParams{}.rest_height_m());
  EXPECT_TRUE(f.replies.empty());
}

TEST(Autopilot, PositionHoldAgainstSteadyWind) {
  WindParams wind;
  wind.steady_W_mps = Eigen::Vector3d(1.0, 0.5, 0.0);
  Flight f(AutopilotParams{}, wind);
  f.take_off();
  const Eigen::Vector3d p0 = f.tello.state().p_WB_m;
  f.run_until(f.tello.time_ns() + seconds_to_ns(10.0), [] {});
  EXPECT_LT((f.tello.state().p_WB_m - p0).norm(), 0.05);
}

TEST(Autopilot, MovesAndTurnsReplyWhenDone) {
  Flight f;
  f.take_off();
  const Eigen::Vector3d p0 = f.tello.state().p_WB_m;
  EXPECT_EQ(f.send("speed 50"), std::optional<std::string>("ok"));
  EXPECT_EQ(f.send("speed?"), std::optional<std::string>("50.0"));
  EXPECT_EQ(f.send("forward 100"), std::nullopt);
  EXPECT_EQ(f.send("cw 90"), std::optional<std::string>("error"));  // one manoeuvre at a time
  f.run_until(f.tello.time_ns() + seconds_to_ns(5.0), [] {});
  ASSERT_EQ(f.replies.size(), 1u);
  EXPECT_EQ(f.replies[0].text, "ok");
  EXPECT_NEAR((f.tello.state().p_WB_m - p0).x(), 1.0, 0.1);
  f.replies.clear();
  EXPECT_EQ(f.send("cw 90"), std::nullopt);
  f.run_until(f.tello.time_ns() + seconds_to_ns(3.0), [] {});
  ASSERT_EQ(f.replies.size(), 1u);
  EXPECT_NEAR(euler_zyx_from_quaternion(f.tello.state().q_WB).z(), -90.0 * kDeg, 0.06);
  f.replies.clear();
  EXPECT_EQ(f.send("forward 50"), std::nullopt);  // now along -y_W
  f.run_until(f.tello.time_ns() + seconds_to_ns(3.0), [] {});
  ASSERT_EQ(f.replies.size(), 1u);
  EXPECT_NEAR((f.tello.state().p_WB_m - p0).y(), -0.5, 0.1);
  EXPECT_EQ(f.send("flip l"), std::optional<std::string>("error"));
}

TEST(Autopilot, RepliesUseTheRealFormats) {
  Flight f;
  EXPECT_EQ(f.send("sdk?"), std::optional<std::string>("20"));
  EXPECT_EQ(f.send("battery?"), std::optional<std::string>("100"));
  EXPECT_EQ(f.send("height?"), std::optional<std::string>("0dm"));
  EXPECT_EQ(f.send("sn?")->size(), 14u);
  EXPECT_EQ(f.send("hover"), std::optional<std::string>("unknown command: hover"));
  EXPECT_EQ(f.send("speed 5"), std::optional<std::string>("out of range"));
  EXPECT_EQ(f.send("rc 0 0 0 500"), std::nullopt);  // rc never gets a reply, not even a bad one
  EXPECT_EQ(f.send("streamon"), std::optional<std::string>("ok"));
  EXPECT_TRUE(f.tello.autopilot().stream_on());
  f.take_off();
  f.run_until(f.tello.time_ns() + seconds_to_ns(60.0), [&] {
    if (f.tello.time_ns() % seconds_to_ns(5.0) == 0) f.send("rc 0 0 0 0");
  });
  // Battery drains with motor-on time (13 min from full): about 8 % after ~65 s.
  const int battery = std::stoi(*f.send("battery?"));
  EXPECT_GE(battery, 90);
  EXPECT_LE(battery, 93);
  EXPECT_EQ(f.send("time?"), std::optional<std::string>(std::to_string(static_cast<int>(f.tello.autopilot().motor_on_time_s())) + "s"));
}

}  // namespace
}  // namespace shelfcross::plant
