// The right-hand side against paper eq. 9 (docs/method.md section 5) written independently with
// Euler angles, term by term, and the physics that fixes the signs: hover equilibrium, free
// fall, the gyroscopic sign, conservation of energy and angular momentum.

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "plant/dynamics.hpp"
#include "plant/quadrotor.hpp"

namespace shelfcross::plant {
namespace {

constexpr double kPi = 3.14159265358979323846;

VehicleParams all_switches_off() {
  VehicleParams v;
  v.switches = ModelSwitches{false, false, false, false, false};
  return v;
}

struct Eq9Terms {
  Eigen::Vector3d accel;        // xdd, ydd, zdd
  Eigen::Vector3d coupling;     // ((Iy-Iz)/Ix) q r, ((Iz-Ix)/Iy) p r, ((Ix-Iy)/Iz) p q
  Eigen::Vector3d gyroscopic;   // -(Jr/Ix) q Om, (Jr/Iy) p Om, 0
  Eigen::Vector3d control;      // (l/Ix) U2, (l/Iy) U3, U4/Iz
};

// eq. 9 straight from the paper with ZYX Euler angles (phi roll, theta pitch, psi yaw). The
// paper's plus layout becomes the Tello's X layout (params.hpp): the roll lever is a_y with
// U2 = b (O1^2 - O2^2 - O3^2 + O4^2) (left rotors 1, 4 minus right 2, 3), the pitch lever a_x
// with U3 = b (O3^2 + O4^2 - O1^2 - O2^2) (rear minus front), U4 = d (O2^2 + O4^2 - O1^2 - O3^2)
// exactly as printed; Om is the net rotor speed along +z_B, O1 + O3 - O2 - O4 (eq. 9 prints
// its negative, inconsistent with its own U4: see plant/dynamics.hpp).
Eq9Terms eq9(const VehicleParams& v, double phi, double theta, double psi, const Eigen::Vector3d& pqr,
             const Eigen::Vector4d& O) {
  const double b = v.thrust_coeff_N_per_radps2, d = v.torque_coeff_Nm_per_radps2, m = v.mass_kg;
  const double Ix = v.inertia_kgm2.x(), Iy = v.inertia_kgm2.y(), Iz = v.inertia_kgm2.z(), Jr = v.rotor_inertia_kgm2;
  const double p = pqr.x(), q = pqr.y(), r = pqr.z();
  const double U1 = b * (O[0] * O[0] + O[1] * O[1] + O[2] * O[2] + O[3] * O[3]);
  const double U2 = b * (O[0] * O[0] - O[1] * O[1] - O[2] * O[2] + O[3] * O[3]);
  const double U3 = b * (O[2] * O[2] + O[3] * O[3] - O[0] * O[0] - O[1] * O[1]);
  const double U4 = d * (O[1] * O[1] + O[3] * O[3] - O[0] * O[0] - O[2] * O[2]);
  const double Om = O[0] + O[2] - O[1] - O[3];
  Eq9Terms t;
  t.accel = Eigen::Vector3d(
      (std::cos(phi) * std::sin(theta) * std::cos(psi) + std::sin(phi) * std::sin(psi)) * U1 / m,
      (std::cos(phi) * std::sin(theta) * std::sin(psi) - std::sin(phi) * std::cos(psi)) * U1 / m,
      -v.gravity_mps2 + std::cos(phi) * std::cos(theta) * U1 / m);
  t.coupling = Eigen::Vector3d((Iy - Iz) / Ix * q * r, (Iz - Ix) / Iy * p * r, (Ix - Iy) / Iz * p * q);
  t.gyroscopic = Eigen::Vector3d(-Jr / Ix * q * Om, Jr / Iy * p * Om, 0.0);
  t.control = Eigen::Vector3d(v.arm_y_m / Ix * U2, v.arm_x_m / Iy * U3, U4 / Iz);
  return t;
}

struct RandomState {
  double phi, theta, psi;
  Eigen::Vector3d pqr;
  Eigen::Vector4d O;
  RigidBodyState state;
};

RandomState random_state(std::mt19937_64& rng) {
  std::uniform_real_distribution<double> angle(-kPi, kPi), pitch(-1.4, 1.4), rate(-8.0, 8.0), rotor(0.0, 5491.0),
      pos(-5.0, 5.0);
  RandomState s;
  s.phi = angle(rng);
  s.theta = pitch(rng);
  s.psi = angle(rng);
  s.pqr = Eigen::Vector3d(rate(rng), rate(rng), rate(rng));
  s.O = Eigen::Vector4d(rotor(rng), rotor(rng), rotor(rng), rotor(rng));
  s.state.p_WB_m = Eigen::Vector3d(pos(rng), pos(rng), pos(rng) + 6.0);
  s.state.v_WB_W_mps = Eigen::Vector3d(pos(rng), pos(rng), pos(rng));
  s.state.q_WB = quaternion_from_euler_zyx(s.phi, s.theta, s.psi);
  s.state.w_WB_B_radps = s.pqr;
  s.state.rotor_speed_radps = s.O;
  return s;
}

Eigen::Vector3d accel_of(const std::array<double, kStateSize>& yd) { return {yd[kIdxV], yd[kIdxV + 1], yd[kIdxV + 2]}; }
Eigen::Vector3d wdot_of(const std::array<double, kStateSize>& yd) { return {yd[kIdxW], yd[kIdxW + 1], yd[kIdxW + 2]}; }

TEST(PlantEq9, AllSwitchesOffEqualsEq9TermByTermAtRandomStates) {
  std::mt19937_64 rng(20240917);
  const VehicleParams off = all_switches_off();
  VehicleParams gyro = off;
  gyro.switches.gyroscopic = true;
  for (int i = 0; i < 500; ++i) {
    const RandomState s = random_state(rng);
    const Eq9Terms e = eq9(gyro, s.phi, s.theta, s.psi, s.pqr, s.O);
    const auto yd_off = rigid_body_rhs(off, s.state, s.O, Eigen::Vector3d::Zero());
    const auto yd_gyro = rigid_body_rhs(gyro, s.state, s.O, Eigen::Vector3d::Zero());
    // Translational rows.
    EXPECT_LT((accel_of(yd_off) - e.accel).norm(), 1e-9 * (1.0 + e.accel.norm())) << "state " << i;
    EXPECT_LT((accel_of(yd_gyro) - e.accel).norm(), 1e-9 * (1.0 + e.accel.norm()));
    // Rotational rows, term by term: with the rotors stopped only the coupling term remains...
    RigidBodyState stopped = s.state;
    stopped.rotor_speed_radps.setZero();
    const Eigen::Vector3d coupling = wdot_of(rigid_body_rhs(gyro, stopped, Eigen::Vector4d::Zero(), Eigen::Vector3d::Zero()));
    EXPECT_LT((coupling - e.coupling).norm(), 1e-9 * (1.0 + e.coupling.norm()));
    // ...the gyroscopic term is what switching it on adds...
    const Eigen::Vector3d gyroscopic = wdot_of(yd_gyro) - wdot_of(yd_off);
    EXPECT_LT((gyroscopic - e.gyroscopic).norm(), 1e-9 * (1.0 + e.gyroscopic.norm()));
    // ...and the control term is what remains of the switched-off right-hand side.
    const Eigen::Vector3d control = wdot_of(yd_off) - coupling;
    EXPECT_LT((control - e.control).norm(), 1e-9 * (1.0 + e.control.norm()));
    // Whole rows.
    EXPECT_LT((wdot_of(yd_gyro) - (e.coupling + e.gyroscopic + e.control)).norm(), 1e-9 * (1.0 + e.control.norm()));
    // Rotor speeds are inputs in eq. 9: no dynamics with motor_dynamics off.
    for (int k = 0; k < 4; ++k) EXPECT_EQ(yd_off[kIdxRotor + k], 0.0);
  }
}

TEST(PlantEq9, AttitudeKinematicsMatchEulerRates) {
  // The quaternion derivative maps to eq. 9's Euler-angle kinematics:
  //   phi' = p + (q sin(phi) + r cos(phi)) tan(theta), theta' = q cos(phi) - r sin(phi),
  //   psi' = (q sin(phi) + r cos(phi)) / cos(theta).
  std::mt19937_64 rng(7);
  const VehicleParams v = all_switches_off();
  for (int i = 0; i < 200; ++i) {
    const RandomState s = random_state(rng);
    const auto yd = rigid_body_rhs(v, s.state, s.O, Eigen::Vector3d::Zero());
    const double h = 1e-7;
    Eigen::Quaterniond qp = s.state.q_WB, qm = s.state.q_WB;
    qp.coeffs() += h * Eigen::Vector4d(yd[kIdxQ + 1], yd[kIdxQ + 2], yd[kIdxQ + 3], yd[kIdxQ]);
    qm.coeffs() -= h * Eigen::Vector4d(yd[kIdxQ + 1], yd[kIdxQ + 2], yd[kIdxQ + 3], yd[kIdxQ]);
    Eigen::Vector3d rates = (euler_zyx_from_quaternion(qp) - euler_zyx_from_quaternion(qm)) / (2.0 * h);
    for (int k = 0; k < 3; ++k) rates[k] = std::remainder(rates[k] * 2.0 * h, 2.0 * kPi) / (2.0 * h);
    const double p = s.pqr.x(), q = s.pqr.y(), r = s.pqr.z(), ph = s.phi, th = s.theta;
    const Eigen::Vector3d expected(p + (q * std::sin(ph) + r * std::cos(ph)) * std::tan(th),
                                   q * std::cos(ph) - r * std::sin(ph),
                                   (q * std::sin(ph) + r * std::cos(ph)) / std::cos(th));
    EXPECT_LT((rates - expected).norm(), 1e-5 * (1.0 + expected.norm())) << "state " << i;
  }
}

TEST(PlantEq9, MixerMatchesLayout) {
  const VehicleParams v;
  const Eigen::Matrix4d m = mixer_matrix(v);
  const double b = v.thrust_coeff_N_per_radps2;
  // Rotor 1 (front-left, ccw) alone: lifts, rolls right-side-down (tau_x > 0), pitches nose up
  // (tau_y < 0) and yaws clockwise (tau_z < 0: the reaction to its ccw spin).
  EXPECT_DOUBLE_EQ(m(0, 0), b);
  EXPECT_GT(m(1, 0), 0.0);
  EXPECT_LT(m(2, 0), 0.0);
  EXPECT_LT(m(3, 0), 0.0);
  // Rotor 3 (rear-right, ccw) is its mirror image through the centre.
  EXPECT_DOUBLE_EQ(m(1, 2), -m(1, 0));
  EXPECT_DOUBLE_EQ(m(2, 2), -m(2, 0));
  EXPECT_DOUBLE_EQ(m(3, 2), m(3, 0));
  // Equal speeds: no torque.
  const RotorWrench w = rotor_wrench(v, Eigen::Vector4d::Constant(3000.0));
  EXPECT_NEAR(w.torque_B_Nm.norm(), 0.0, 1e-15);
  EXPECT_NEAR(w.thrust_N, 4.0 * b * 9e6, 1e-12);
}

TEST(PlantEq9, HoverEquilibrium) {
  const VehicleParams v;
  const double om_h = v.hover_rotor_speed_radps();
  EXPECT_GT(om_h, 3000.0);  // 8520 coreless motors on ~45 mm props: ~30,000-40,000 rpm
  EXPECT_LT(om_h, 4500.0);
  RigidBodyState s;
  s.p_WB_m = Eigen::Vector3d(0.0, 0.0, 1.0);
  s.q_WB = quaternion_from_euler_zyx(0.0, 0.0, 0.7);
  s.rotor_speed_radps.setConstant(om_h);
  const auto yd = rigid_body_rhs(v, s, s.rotor_speed_radps, Eigen::Vector3d::Zero());
  for (double x : yd) EXPECT_NEAR(x, 0.0, 1e-12);

  Quadrotor quad(v, WindParams{}, 1);
  quad.reset(s, 0);
  quad.set_rotor_commands(s.rotor_speed_radps);
  for (int k = 1; k <= 2500; ++k) quad.advance_to(tick_time_ns(k, 500));  // 5 s
  EXPECT_NEAR((quad.state().p_WB_m - s.p_WB_m).norm(), 0.0, 1e-9);
  EXPECT_NEAR(quad.state().v_WB_W_mps.norm(), 0.0, 1e-9);
  EXPECT_FALSE(quad.on_floor());
}

TEST(PlantEq9, FreeFall) {
  VehicleParams v;
  v.switches.linear_drag = v.switches.quadratic_drag = false;
  IntegratorSettings tight;
  tight.rel_tol = 1e-10;
  tight.abs_tol = 1e-12;
  tight.abs_tol_rate_radps = 1e-12;
  Quadrotor quad(v, WindParams{}, 1, tight);
  RigidBodyState s;
  s.p_WB_m = Eigen::Vector3d(1.0, 2.0, 10.0);
  s.v_WB_W_mps = Eigen::Vector3d(0.5, 0.0, 0.0);
  quad.reset(s, 0);
  quad.advance_to(seconds_to_ns(1.0));
  const double g = v.gravity_mps2;
  EXPECT_NEAR(quad.state().p_WB_m.z(), 10.0 - 0.5 * g, 1e-8);
  EXPECT_NEAR(quad.state().p_WB_m.x(), 1.5, 1e-8);
  EXPECT_NEAR(quad.state().v_WB_W_mps.z(), -g, 1e-8);
  // It reaches the floor and rests on it: z = half the height, never below, nothing NaN.
  for (int k = 1; k <= 3000; ++k) {
    quad.advance_to(seconds_to_ns(1.0) + k * 1'000'000LL);
    ASSERT_GE(quad.state().p_WB_m.z(), v.rest_height_m() - 1e-12);
    ASSERT_TRUE(quad.state().p_WB_m.allFinite());
  }
  EXPECT_TRUE(quad.on_floor());
  EXPECT_DOUBLE_EQ(quad.state().p_WB_m.z(), v.rest_height_m());
  EXPECT_EQ(quad.state().v_WB_W_mps.norm(), 0.0);
}

TEST(PlantEq9, GyroscopicTermSign) {
  // Rotors 1 and 3 spin counter-clockwise seen from above: angular momentum h = Jr Om e3 along
  // +z_B. Rolling at p > 0 turns h with the body; the body must supply dh/dt = w x h, so the
  // rotors push back on it with -w x h = (0, Jr Om p, 0): a positive pitch acceleration.
  VehicleParams v = all_switches_off();
  v.switches.gyroscopic = true;
  v.thrust_coeff_N_per_radps2 = 0.0;  // isolate the gyroscopic torque
  v.torque_coeff_Nm_per_radps2 = 0.0;
  RigidBodyState s;
  s.w_WB_B_radps = Eigen::Vector3d(2.0, 0.0, 0.0);
  s.rotor_speed_radps = Eigen::Vector4d(3000.0, 0.0, 3000.0, 0.0);
  EXPECT_GT(net_rotor_speed_radps(s.rotor_speed_radps), 0.0);
  const auto yd = rigid_body_rhs(v, s, s.rotor_speed_radps, Eigen::Vector3d::Zero());
  EXPECT_NEAR(yd[kIdxW + 1], v.rotor_inertia_kgm2 * 6000.0 * 2.0 / v.inertia_kgm2.y(), 1e-12);
  EXPECT_GT(yd[kIdxW + 1], 0.0);
  EXPECT_EQ(yd[kIdxW], 0.0);
  // And a pitch rate q > 0 gives a negative roll acceleration.
  s.w_WB_B_radps = Eigen::Vector3d(0.0, 2.0, 0.0);
  EXPECT_LT(rigid_body_rhs(v, s, s.rotor_speed_radps, Eigen::Vector3d::Zero())[kIdxW], 0.0);
}

double energy(const VehicleParams& v, const RigidBodyState& s) {
  return 0.5 * v.mass_kg * s.v_WB_W_mps.squaredNorm() +
         0.5 * s.w_WB_B_radps.dot(v.inertia_kgm2.cwiseProduct(s.w_WB_B_radps)) +
         v.mass_kg * v.gravity_mps2 * s.p_WB_m.z();
}

// Total angular momentum about the centre of mass in W: body plus rotors (sign of h chosen by
// `rotor_sign`, +1 the physical one).
Eigen::Vector3d angular_momentum_W(const VehicleParams& v, const RigidBodyState& s, double rotor_sign = 1.0) {
  const Eigen::Vector3d h(0.0, 0.0, rotor_sign * v.rotor_inertia_kgm2 * net_rotor_speed_radps(s.rotor_speed_radps));
  return s.q_WB * (v.inertia_kgm2.cwiseProduct(s.w_WB_B_radps) + h);
}

TEST(PlantEq9, TumblingBodyConservesEnergyAndAngularMomentum) {
  VehicleParams v;
  v.switches.linear_drag = v.switches.quadratic_drag = v.switches.wind = false;
  IntegratorSettings tight;
  tight.rel_tol = 1e-10;
  tight.abs_tol = 1e-12;
  tight.abs_tol_rate_radps = 1e-12;
  Quadrotor quad(v, WindParams{}, 1, tight);
  RigidBodyState s;  // rotors stopped, gravity on, high above the floor
  s.p_WB_m = Eigen::Vector3d(0.0, 0.0, 100.0);
  s.v_WB_W_mps = Eigen::Vector3d(1.0, -2.0, 3.0);
  s.q_WB = quaternion_from_euler_zyx(0.3, -0.5, 1.0);
  s.w_WB_B_radps = Eigen::Vector3d(3.0, -2.0, 5.0);  // near the unstable intermediate axis too
  quad.reset(s, 0);
  const double e0 = energy(v, s);
  const Eigen::Vector3d l0 = angular_momentum_W(v, s);
  for (int k = 1; k <= 1500; ++k) {  // 3 s at 500 Hz, with a re-initialisation every tick
    quad.set_rotor_commands(Eigen::Vector4d::Zero());
    quad.advance_to(tick_time_ns(k, 500));
  }
  EXPECT_NEAR(energy(v, quad.state()) / e0, 1.0, 1e-8);
  EXPECT_LT((angular_momentum_W(v, quad.state()) - l0).norm(), 1e-6 * l0.norm());
  // It did tumble: the body rates changed a lot.
  EXPECT_GT((quad.state().w_WB_B_radps - s.w_WB_B_radps).norm(), 0.5);
}

TEST(PlantEq9, SpinningRotorsConserveTotalAngularMomentum) {
  // Torque-free (no thrust or reaction torque, no drag) body carrying spinning rotors: the
  // total angular momentum R (I w + Jr Om e3) is conserved only with the gyroscopic term's
  // physical sign; with h taken the other way round it is not.
  VehicleParams v;
  v.switches.linear_drag = v.switches.quadratic_drag = v.switches.wind = false;
  v.thrust_coeff_N_per_radps2 = 1e-30;
  v.torque_coeff_Nm_per_radps2 = 1e-30;
  v.rotor_inertia_kgm2 = 2e-6;  // large, to make the effect plain
  IntegratorSettings tight;
  tight.rel_tol = 1e-10;
  tight.abs_tol = 1e-12;
  tight.abs_tol_rate_radps = 1e-12;
  Quadrotor quad(v, WindParams{}, 1, tight);
  RigidBodyState s;
  s.p_WB_m = Eigen::Vector3d(0.0, 0.0, 100.0);
  s.w_WB_B_radps = Eigen::Vector3d(2.0, 1.0, -0.5);
  s.rotor_speed_radps = Eigen::Vector4d(4000.0, 1000.0, 4000.0, 1000.0);
  quad.reset(s, 0);
  const Eigen::Vector3d l0 = angular_momentum_W(v, s), l0_wrong = angular_momentum_W(v, s, -1.0);
  for (int k = 1; k <= 1000; ++k) {
    quad.set_rotor_commands(s.rotor_speed_radps);
    quad.advance_to(tick_time_ns(k, 500));
  }
  EXPECT_LT((angular_momentum_W(v, quad.state()) - l0).norm(), 1e-8 * l0.norm());
  EXPECT_GT((angular_momentum_W(v, quad.state(), -1.0) - l0_wrong).norm(), 1e-3 * l0.norm());

  // Spinning the rotors up: the body counter-rotates about z_B so that the total stays put.
  RigidBodyState rest = s;
  rest.w_WB_B_radps.setZero();
  rest.q_WB.setIdentity();
  rest.rotor_speed_radps.setZero();
  quad.reset(rest, 0);
  for (int k = 1; k <= 500; ++k) {
    quad.set_rotor_commands(Eigen::Vector4d(3000.0, 0.0, 3000.0, 0.0));
    quad.advance_to(tick_time_ns(k, 500));
  }
  EXPECT_LT(quad.state().w_WB_B_radps.z(), -1e-3);
  EXPECT_LT(angular_momentum_W(v, quad.state()).norm(), 1e-9);
}

}  // namespace
}  // namespace shelfcross::plant
