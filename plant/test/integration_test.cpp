// CVODE integration against a fine fixed-step RK4 reference, determinism, the floor, failures,
// the top speed the drag defaults were fitted to, and the wind stream.

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <random>
#include <vector>

#include <Eigen/LU>

#include "plant/dynamics.hpp"
#include "plant/quadrotor.hpp"
#include "plant/simulated_tello.hpp"
#include "plant/wind.hpp"

namespace shelfcross::plant {
namespace {

// An open-loop manoeuvre around hover that stays bounded for 10 s: collective, roll, pitch
// and yaw sinusoids, held constant over each 2 ms tick like the autopilot's commands.
Eigen::Vector4d manoeuvre_command(const VehicleParams& v, std::int64_t k) {
  const double t = k / 500.0, h = v.hover_rotor_speed_radps();
  const double coll = 0.03 * std::sin(2.0 * 3.14159 * 0.3 * t);
  const double roll = 0.002 * std::cos(2.0 * 3.14159 * 0.7 * t);
  const double pitch = 0.002 * std::cos(2.0 * 3.14159 * 0.5 * t + 0.3);
  const double yaw = 0.05 * std::sin(2.0 * 3.14159 * 0.2 * t);
  Eigen::Vector4d c;
  for (int i = 0; i < 4; ++i)
    c[i] = h * (1.0 + coll + roll * kRotorSy[i] - pitch * kRotorSx[i] - yaw * kRotorSpin[i]);
  return c;
}

// Classic RK4 on the flat state with a fixed step, written here only as the reference.
void rk4_step(const VehicleParams& v, double* y, const Eigen::Vector4d& cmd, double h) {
  double k1[kStateSize], k2[kStateSize], k3[kStateSize], k4[kStateSize], tmp[kStateSize];
  const Eigen::Vector3d wind = Eigen::Vector3d::Zero();
  rigid_body_rhs(v, y, cmd, wind, k1);
  for (int i = 0; i < kStateSize; ++i) tmp[i] = y[i] + 0.5 * h * k1[i];
  rigid_body_rhs(v, tmp, cmd, wind, k2);
  for (int i = 0; i < kStateSize; ++i) tmp[i] = y[i] + 0.5 * h * k2[i];
  rigid_body_rhs(v, tmp, cmd, wind, k3);
  for (int i = 0; i < kStateSize; ++i) tmp[i] = y[i] + h * k3[i];
  rigid_body_rhs(v, tmp, cmd, wind, k4);
  for (int i = 0; i < kStateSize; ++i) y[i] += h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]);
}

RigidBodyState start_at_1m(const VehicleParams& v) {
  RigidBodyState s;
  s.p_WB_m = Eigen::Vector3d(0.0, 0.0, 1.0);
  s.rotor_speed_radps.setConstant(v.hover_rotor_speed_radps());
  return s;
}

// A 10 s manoeuvre flown by the autopilot from a hover at 1 m: forward, sideways, climbing,
// yawing, and a stop, with the stick changes of a pilot. Returns the final state of a plant
// advanced by `advance(cmd, t_next)`.
template <class Advance>
RigidBodyState fly_manoeuvre(Autopilot autopilot, RigidBodyState state, TimeNs t0, Advance advance) {
  const struct { double t_s; const char* rc; } sticks[] = {
      {0.0, "rc 0 80 0 0"}, {2.0, "rc 60 40 30 0"}, {4.0, "rc -50 0 -20 70"}, {6.5, "rc 0 -100 0 -40"}, {8.5, "rc 0 0 0 0"}};
  std::size_t next = 0;
  for (std::int64_t k = 0; k < 5000; ++k) {
    const TimeNs t = t0 + tick_time_ns(k, 500);
    while (next < std::size(sticks) && seconds_to_ns(sticks[next].t_s) <= t - t0) autopilot.on_command(t, sticks[next++].rc);
    state = advance(autopilot.update(t, state), t0 + tick_time_ns(k + 1, 500));
  }
  return state;
}

// A hover after a real take-off (the floor is CVODE's), handed to the manoeuvre's flights.
struct Hover {
  Autopilot autopilot;
  RigidBodyState state;
  TimeNs t0_ns;
};
Hover hover_after_takeoff(const VehicleParams& v) {
  SimulatedTello tello(v, AutopilotParams{}, WindParams{}, 1);
  tello.submit(0, "command");
  tello.submit(seconds_to_ns(0.1), "takeoff");
  tello.step_to(seconds_to_ns(6.0));
  EXPECT_EQ(tello.mode(), FlightMode::flying);
  return {tello.autopilot(), tello.state(), tello.time_ns()};
}

// The manoeuvre from `hover` with each tick's rotor commands moved by seeded draws of
// `jitter` times hover speed (0: as the autopilot sends them), flown by a plant advanced by
// `advance(cmd, t_next)`.
template <class Advance>
RigidBodyState fly_jittered(const VehicleParams& v, const Hover& hover, double jitter, Advance advance) {
  std::mt19937_64 rng(7);
  std::normal_distribution<double> draw(0.0, jitter * v.hover_rotor_speed_radps());
  return fly_manoeuvre(hover.autopilot, hover.state, hover.t0_ns, [&](Eigen::Vector4d cmd, TimeNs t_next) {
    if (jitter > 0.0)
      for (int i = 0; i < 4; ++i) cmd[i] += draw(rng);
    return advance(cmd, t_next);
  });
}

// The reference: RK4 at 50 us.
RigidBodyState rk4_flight(const VehicleParams& v, const Hover& hover, double jitter) {
  double y[kStateSize];
  pack_state(hover.state, y);
  return fly_jittered(v, hover, jitter, [&](const Eigen::Vector4d& cmd, TimeNs) {
    constexpr int kSub = 40;
    for (int j = 0; j < kSub; ++j) rk4_step(v, y, cmd, 0.002 / kSub);
    const double qn = std::sqrt(y[kIdxQ] * y[kIdxQ] + y[kIdxQ + 1] * y[kIdxQ + 1] + y[kIdxQ + 2] * y[kIdxQ + 2] +
                                y[kIdxQ + 3] * y[kIdxQ + 3]);
    for (int i = 0; i < 4; ++i) y[kIdxQ + i] /= qn;
    return unpack_state(y);
  });
}

RigidBodyState cvode_flight(const VehicleParams& v, const Hover& hover, double jitter, IntegratorSettings settings,
                            long* evaluations = nullptr) {
  Quadrotor quad(v, WindParams{}, 1, settings);
  quad.reset(hover.state, hover.t0_ns);
  const RigidBodyState end = fly_jittered(v, hover, jitter, [&](const Eigen::Vector4d& cmd, TimeNs t_next) {
    quad.set_rotor_commands(cmd);
    quad.advance_to(t_next);
    return quad.state();
  });
  if (evaluations) *evaluations = quad.rhs_evaluations();
  return end;
}

TEST(PlantIntegration, CvodeMatchesFineRk4OverTenSecondManoeuvre) {
  const VehicleParams v;  // every term on (motors, gyroscopic, drag); calm air
  const Hover hover = hover_after_takeoff(v);
  const RigidBodyState ref = rk4_flight(v, hover, 0.0);
  // The manoeuvre did go somewhere, airborne all the time.
  EXPECT_GT((ref.p_WB_m - hover.state.p_WB_m).norm(), 1.0);
  EXPECT_GT(ref.p_WB_m.z(), 0.5);

  const RigidBodyState s = cvode_flight(v, hover, 0.0, IntegratorSettings{});
  EXPECT_LT((s.p_WB_m - ref.p_WB_m).norm(), 1e-4) << "CVODE " << s.p_WB_m.transpose() << " RK4 " << ref.p_WB_m.transpose();
  EXPECT_LT((s.v_WB_W_mps - ref.v_WB_W_mps).norm(), 1e-4);
  EXPECT_LT(s.q_WB.angularDistance(ref.q_WB), 1e-4);
  EXPECT_LT((s.w_WB_B_radps - ref.w_WB_B_radps).norm(), 1e-3);
  EXPECT_LT((s.rotor_speed_radps - ref.rotor_speed_radps).norm(), 1.0);

  // Tight tolerances converge onto the reference.
  IntegratorSettings tight;
  tight.rel_tol = 1e-10;
  tight.abs_tol = 1e-12;
  tight.abs_tol_rate_radps = 1e-12;
  tight.abs_tol_rotor_radps = 1e-8;
  const RigidBodyState p = cvode_flight(v, hover, 0.0, tight);
  EXPECT_LT((p.p_WB_m - ref.p_WB_m).norm(), 1e-7);
  EXPECT_LT((p.v_WB_W_mps - ref.v_WB_W_mps).norm(), 1e-7);
  EXPECT_LT((p.rotor_speed_radps - ref.rotor_speed_radps).norm(), 1e-4);
}

// Commands that jump from tick to tick, as a position hold on noisy velocity readings sends
// them: the manoeuvre's, each rotor's command moved by a seeded draw of 1 % of hover speed.
// The defaults keep the flight on the reference; the body rates' tolerance relaxed to 1e-6
// rad/s keeps it there too, with fewer evaluations.
TEST(PlantIntegration, JumpyCommandsStayOnTheReferenceAndARelaxedRateToleranceSavesEvaluations) {
  const VehicleParams v;
  const Hover hover = hover_after_takeoff(v);
  constexpr double kJitter = 0.01;
  const RigidBodyState ref = rk4_flight(v, hover, kJitter);
  EXPECT_GT((ref.p_WB_m - hover.state.p_WB_m).norm(), 1.0);

  long n_default = 0, n_relaxed = 0;
  IntegratorSettings relaxed;
  relaxed.abs_tol_rate_radps = 1e-6;
  for (auto [settings, evaluations] : {std::pair{IntegratorSettings{}, &n_default}, std::pair{relaxed, &n_relaxed}}) {
    const RigidBodyState s = cvode_flight(v, hover, kJitter, settings, evaluations);
    EXPECT_LT((s.p_WB_m - ref.p_WB_m).norm(), 1e-4);
    EXPECT_LT((s.v_WB_W_mps - ref.v_WB_W_mps).norm(), 1e-4);
    EXPECT_LT(s.q_WB.angularDistance(ref.q_WB), 1e-4);
    EXPECT_LT((s.w_WB_B_radps - ref.w_WB_B_radps).norm(), 1e-3);
  }
  EXPECT_LT(static_cast<double>(n_relaxed), 0.9 * static_cast<double>(n_default))
      << n_relaxed << " evaluations against " << n_default;
}

TEST(PlantIntegration, BdfNewtonAlternativeAgrees) {
  const VehicleParams v;
  IntegratorSettings bdf;
  bdf.method = IntegratorSettings::Method::bdf_newton_dense;
  Quadrotor a(v, WindParams{}, 1), b(v, WindParams{}, 1, bdf);
  a.reset(start_at_1m(v), 0);
  b.reset(start_at_1m(v), 0);
  for (std::int64_t k = 0; k < 1000; ++k) {
    a.set_rotor_commands(manoeuvre_command(v, k));
    b.set_rotor_commands(manoeuvre_command(v, k));
    a.advance_to(tick_time_ns(k + 1, 500));
    b.advance_to(tick_time_ns(k + 1, 500));
  }
  EXPECT_LT((a.state().p_WB_m - b.state().p_WB_m).norm(), 2e-3);  // open loop, 2 s, drifting
}

bool bit_identical(const RigidBodyState& a, const RigidBodyState& b) {
  double ya[kStateSize], yb[kStateSize];
  pack_state(a, ya);
  pack_state(b, yb);
  return std::memcmp(ya, yb, sizeof ya) == 0;
}

TEST(PlantIntegration, IdenticalInputsGiveBitIdenticalStates) {
  WindParams gusty;
  gusty.steady_W_mps = Eigen::Vector3d(0.5, -0.3, 0.0);
  gusty.gust_stddev_mps = 0.4;
  const VehicleParams v;
  Quadrotor a(v, gusty, 99), b(v, gusty, 99), c(v, gusty, 100);
  a.reset(start_at_1m(v), 0);
  b.reset(start_at_1m(v), 0);
  c.reset(start_at_1m(v), 0);
  for (std::int64_t k = 0; k < 2000; ++k) {
    for (Quadrotor* q : {&a, &b, &c}) {
      q->set_rotor_commands(manoeuvre_command(v, k));
      q->advance_to(tick_time_ns(k + 1, 500));
    }
    ASSERT_TRUE(bit_identical(a.state(), b.state())) << "tick " << k;
  }
  EXPECT_FALSE(bit_identical(a.state(), c.state()));  // another wind seed, another flight

  // The whole simulated Tello too.
  SimulatedTello t1(v, AutopilotParams{}, gusty, 5), t2(v, AutopilotParams{}, gusty, 5);
  for (SimulatedTello* t : {&t1, &t2}) {
    t->submit(0, "command");
    t->submit(seconds_to_ns(0.2), "takeoff");
    t->submit(seconds_to_ns(6.0), "rc 30 60 -10 40");
    t->step_to(seconds_to_ns(9.0));
  }
  EXPECT_TRUE(bit_identical(t1.state(), t2.state()));
}

TEST(PlantFloor, StartsLandedAndRestsWithoutSinking) {
  const VehicleParams v;
  Quadrotor quad(v, WindParams{}, 1);
  EXPECT_TRUE(quad.on_floor());
  EXPECT_DOUBLE_EQ(quad.state().p_WB_m.z(), v.floor_z_m + 0.5 * v.size_m.z());
  // Idle rotors: thrust below weight, it stays put.
  for (int k = 1; k <= 500; ++k) {
    quad.set_rotor_commands(Eigen::Vector4d::Constant(v.rotor_speed_min_radps));
    quad.advance_to(tick_time_ns(k, 500));
    ASSERT_DOUBLE_EQ(quad.state().p_WB_m.z(), v.rest_height_m());
  }
  EXPECT_TRUE(quad.on_floor());
  // Full thrust: it lifts off and climbs.
  for (int k = 501; k <= 750; ++k) {
    quad.set_rotor_commands(Eigen::Vector4d::Constant(v.rotor_speed_max_radps));
    quad.advance_to(tick_time_ns(k, 500));
  }
  EXPECT_FALSE(quad.on_floor());
  EXPECT_GT(quad.state().p_WB_m.z(), v.rest_height_m() + 0.1);
  // Motors off: it falls back, tilted and spinning, and comes to rest level on the floor.
  quad.set_rotor_commands(Eigen::Vector4d(0.0, 0.0, 0.0, v.rotor_speed_max_radps));
  quad.advance_to(seconds_to_ns(1.6));
  for (int k = 1; k <= 3000; ++k) {
    quad.set_rotor_commands(Eigen::Vector4d::Zero());
    quad.advance_to(seconds_to_ns(1.6) + k * 1'000'000LL);
    ASSERT_GE(quad.state().p_WB_m.z(), v.rest_height_m() - 1e-12);
    ASSERT_TRUE(quad.state().w_WB_B_radps.allFinite());
  }
  EXPECT_TRUE(quad.on_floor());
  EXPECT_NEAR(tilt_rad(quad.state().q_WB), 0.0, 1e-12);
}

TEST(PlantFailure, NonFiniteStateThrowsNumericalFailure) {
  const VehicleParams v;
  Quadrotor quad(v, WindParams{}, 1);
  RigidBodyState s = start_at_1m(v);
  s.v_WB_W_mps.x() = std::nan("");
  quad.reset(s, 0);
  EXPECT_THROW(quad.advance_to(seconds_to_ns(0.01)), NumericalFailure);
}

TEST(PlantFailure, CvodeErrorFlagThrowsNumericalFailure) {
  const VehicleParams v;
  IntegratorSettings starved;
  starved.max_steps_per_segment = 1;
  starved.initial_step_s = 1e-7;
  Quadrotor quad(v, WindParams{}, 1, starved);
  quad.reset(start_at_1m(v), 0);
  try {
    quad.advance_to(seconds_to_ns(0.5));
    FAIL() << "expected NumericalFailure";
  } catch (const NumericalFailure& e) {
    EXPECT_LT(e.cvode_flag(), 0);
    EXPECT_NE(std::string(e.what()).find("CVode"), std::string::npos);
  }
}

TEST(PlantFailure, BadParametersAreRefused) {
  VehicleParams v;
  v.mass_kg = 0.0;
  EXPECT_THROW(Quadrotor(v, WindParams{}, 1), std::invalid_argument);
  IntegratorSettings s;
  s.rel_tol = -1.0;
  EXPECT_THROW(Quadrotor(VehicleParams{}, WindParams{}, 1, s), std::invalid_argument);
  IntegratorSettings rate;
  rate.abs_tol_rate_radps = 0.0;
  EXPECT_THROW(Quadrotor(VehicleParams{}, WindParams{}, 1, rate), std::invalid_argument);
}

// Steady level flight at a given pitch: the speed where drag balances the thrust's horizontal
// part while its vertical part carries the weight (2-D Newton on the right-hand side).
double steady_speed_at_tilt(const VehicleParams& v, double pitch_rad) {
  double speed = 3.0, thrust = v.mass_kg * v.gravity_mps2;
  const auto residual = [&](double V, double T) {
    RigidBodyState s;
    s.q_WB = quaternion_from_euler_zyx(0.0, pitch_rad, 0.0);
    s.v_WB_W_mps = Eigen::Vector3d(V, 0.0, 0.0);
    s.rotor_speed_radps.setConstant(std::sqrt(T / (4.0 * v.thrust_coeff_N_per_radps2)));
    const auto yd = rigid_body_rhs(v, s, s.rotor_speed_radps, Eigen::Vector3d::Zero());
    return Eigen::Vector2d(yd[kIdxV], yd[kIdxV + 2]);
  };
  for (int it = 0; it < 50; ++it) {
    const Eigen::Vector2d r = residual(speed, thrust);
    Eigen::Matrix2d J;
    J.col(0) = (residual(speed + 1e-6, thrust) - r) / 1e-6;
    J.col(1) = (residual(speed, thrust + 1e-6) - r) / 1e-6;
    const Eigen::Vector2d d = J.inverse() * r;
    speed -= d[0];
    thrust -= d[1];
  }
  return speed;
}

TEST(PlantParams, TopSpeedAt25DegTiltIs8mps) {
  const VehicleParams v;
  EXPECT_NEAR(steady_speed_at_tilt(v, 25.0 * 3.14159265358979 / 180.0), 8.0, 0.05);  // fast mode, Table 4
  EXPECT_NEAR(steady_speed_at_tilt(v, 9.0 * 3.14159265358979 / 180.0), 4.0, 0.05);   // slow mode
  // And the maximum thrust can hold 25 deg level: 2 m g > m g / cos(25 deg).
  EXPECT_GT(4.0 * v.thrust_coeff_N_per_radps2 * v.rotor_speed_max_radps * v.rotor_speed_max_radps,
            1.5 * v.mass_kg * v.gravity_mps2);
}

TEST(PlantParams, InertiaFromGeometryIsPlausible) {
  const VehicleParams v;
  // Bounded by a point mass at the centre (0) and the whole mass spread as a uniform box of
  // the full outline (which overstates it: the battery sits in the middle).
  const double m = v.mass_kg, x = v.size_m.x(), y = v.size_m.y(), z = v.size_m.z();
  EXPECT_GT(v.inertia_kgm2.x(), 0.2 * m * (y * y + z * z) / 12.0);
  EXPECT_LT(v.inertia_kgm2.x(), m * (y * y + z * z) / 12.0);
  EXPECT_LT(v.inertia_kgm2.z(), m * (x * x + y * y) / 12.0);
  EXPECT_GT(v.inertia_kgm2.z(), v.inertia_kgm2.x());
  EXPECT_GT(v.inertia_kgm2.z(), v.inertia_kgm2.y());
  // Rotors inside the outline.
  EXPECT_LT(v.arm_x_m, 0.5 * x);
  EXPECT_LT(v.arm_y_m, 0.5 * y);
}

TEST(PlantWind, GustStreamIsSeededStationaryAndCorrelated) {
  WindParams p;
  p.steady_W_mps = Eigen::Vector3d(1.0, 0.0, -0.2);
  p.gust_stddev_mps = 0.5;
  p.gust_time_constant_s = 0.5;
  WindModel a(p, 3), b(p, 3), c(p, 4);
  const int n = 200000;
  Eigen::Vector3d sum = Eigen::Vector3d::Zero(), sq = Eigen::Vector3d::Zero();
  double lag_sum = 0.0;
  Eigen::Vector3d prev = Eigen::Vector3d::Zero();
  const int lag = 50;  // 0.5 s at 10 ms: correlation exp(-1)
  std::vector<double> xs(n);
  for (int k = 0; k < n; ++k) {
    const TimeNs t = k * 10'000'000LL;
    const Eigen::Vector3d w = a.wind_W_mps(t);
    ASSERT_EQ(w, b.wind_W_mps(t));
    const Eigen::Vector3d g = w - p.steady_W_mps;
    sum += g;
    sq += g.cwiseAbs2();
    xs[k] = g.x();
    if (k >= lag) lag_sum += xs[k] * xs[k - lag];
    prev = g;
  }
  const Eigen::Vector3d mean = sum / n;
  const Eigen::Vector3d sd = (sq / n - mean.cwiseAbs2()).cwiseSqrt();
  for (int i = 0; i < 3; ++i) {
    EXPECT_NEAR(mean[i], 0.0, 0.05);
    EXPECT_NEAR(sd[i], 0.5, 0.05);
  }
  EXPECT_NEAR(lag_sum / (n - lag) / (sd.x() * sd.x()), std::exp(-1.0), 0.05);
  EXPECT_NE(a.wind_W_mps(0), c.wind_W_mps(0));
  // Going back replays the same stream.
  EXPECT_EQ(a.wind_W_mps(12'340'000'000LL), b.wind_W_mps(12'340'000'000LL));
}

TEST(PlantWind, SteadyWindCarriesAnUnpoweredBodyAlongThroughDrag) {
  VehicleParams v;
  WindParams p;
  p.steady_W_mps = Eigen::Vector3d(2.0, 0.0, 0.0);
  Quadrotor quad(v, p, 1);
  RigidBodyState s = start_at_1m(v);
  s.p_WB_m.z() = 50.0;
  quad.reset(s, 0);
  quad.advance_to(seconds_to_ns(1.0));
  EXPECT_GT(quad.state().v_WB_W_mps.x(), 0.05);
  v.switches.wind = false;
  Quadrotor calm(v, p, 1);
  calm.reset(s, 0);
  calm.advance_to(seconds_to_ns(1.0));
  EXPECT_NEAR(calm.state().v_WB_W_mps.x(), 0.0, 1e-9);
}

}  // namespace
}  // namespace shelfcross::plant
