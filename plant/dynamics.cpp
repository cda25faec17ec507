#include "plant/dynamics.hpp"

#include <algorithm>
#include <cmath>

#include "shelfcross/rotation.hpp"

namespace shelfcross::plant {

Eigen::Matrix4d mixer_matrix(const VehicleParams& vehicle) {
  const double b = vehicle.thrust_coeff_N_per_radps2;
  const double d = vehicle.torque_coeff_Nm_per_radps2;
  Eigen::Matrix4d m;
  for (int i = 0; i < 4; ++i) {
    // Thrust b O^2 along +z_B at r_i = (x_i, y_i, 0): torque r_i x (0, 0, f) = (y_i f, -x_i f, 0).
    m(0, i) = b;
    m(1, i) = b * kRotorSy[i] * vehicle.arm_y_m;
    m(2, i) = -b * kRotorSx[i] * vehicle.arm_x_m;
    // A rotor spinning along spin_i z_B drags the air; the air's reaction on the body is
    // -spin_i d O^2 about z_B.
    m(3, i) = -d * kRotorSpin[i];
  }
  return m;
}

double net_rotor_speed_radps(const Eigen::Vector4d& w) {
  return kRotorSpin[0] * w[0] + kRotorSpin[1] * w[1] + kRotorSpin[2] * w[2] + kRotorSpin[3] * w[3];
}

RotorWrench rotor_wrench(const VehicleParams& vehicle, const Eigen::Vector4d& rotor_speed_radps) {
  const Eigen::Vector4d u = mixer_matrix(vehicle) * rotor_speed_radps.cwiseAbs2();
  return {u[0], u.tail<3>()};
}

void rigid_body_rhs(const VehicleParams& vh, const double* y, const Eigen::Vector4d& cmd,
                    const Eigen::Vector3d& wind_W_mps, double* ydot, const Eigen::Vector4d& thrust_factor) {
  const ModelSwitches& sw = vh.switches;
  const Eigen::Map<const Eigen::Vector3d> v(y + kIdxV);
  const Eigen::Quaterniond q_raw(y[kIdxQ], y[kIdxQ + 1], y[kIdxQ + 2], y[kIdxQ + 3]);
  const Eigen::Map<const Eigen::Vector3d> w(y + kIdxW);
  const Eigen::Map<const Eigen::Vector4d> om(y + kIdxRotor);

  const Eigen::Quaterniond q = q_raw.normalized();
  const Eigen::Matrix3d R = q.toRotationMatrix();

  // Rotor speeds: first-order lag toward the held command.
  Eigen::Vector4d om_dot = Eigen::Vector4d::Zero();
  if (sw.motor_dynamics) om_dot = (cmd - om) / vh.motor_time_constant_s;

  // Thrust and torques of the mixer, expanded (no matrix build in the hot loop).
  const double b = vh.thrust_coeff_N_per_radps2, d = vh.torque_coeff_Nm_per_radps2;
  const Eigen::Vector4d o2 = om.cwiseAbs2();
  // Each rotor's thrust with its surface-effect factor (x 1.0 leaves every bit as it was); the
  // reaction torque is the open-air one.
  const Eigen::Vector4d t2 = o2.cwiseProduct(thrust_factor);
  const double thrust = b * t2.sum();
  Eigen::Vector3d tau(b * vh.arm_y_m * (t2[0] - t2[1] - t2[2] + t2[3]),
                      b * vh.arm_x_m * (-t2[0] - t2[1] + t2[2] + t2[3]),
                      d * (-o2[0] + o2[1] - o2[2] + o2[3]));

  if (sw.gyroscopic) {
    // Rotor angular momentum h = Jr Om e3 (fixed in B): torque on the body -w x h, and the
    // reaction to spinning the rotors up, -Jr Om' e3.
    const double jr = vh.rotor_inertia_kgm2;
    const double om_net = net_rotor_speed_radps(om);
    tau.x() += -jr * w.y() * om_net;
    tau.y() += jr * w.x() * om_net;
    tau.z() += -jr * net_rotor_speed_radps(om_dot);
  }

  // Drag on the air-relative velocity, per body axis.
  Eigen::Vector3d f_drag_B = Eigen::Vector3d::Zero();
  if (sw.linear_drag || sw.quadratic_drag) {
    const Eigen::Vector3d v_air_W = sw.wind ? Eigen::Vector3d(v - wind_W_mps) : Eigen::Vector3d(v);
    const Eigen::Vector3d v_air_B = R.transpose() * v_air_W;
    if (sw.linear_drag) f_drag_B -= vh.linear_drag_Ns_per_m.cwiseProduct(v_air_B);
    if (sw.quadratic_drag)
      f_drag_B -= vh.quadratic_drag_Ns2_per_m2.cwiseProduct(v_air_B.cwiseAbs().cwiseProduct(v_air_B));
  }

  const Eigen::Vector3d a_W = R * (Eigen::Vector3d(0.0, 0.0, thrust) + f_drag_B) / vh.mass_kg -
                              Eigen::Vector3d(0.0, 0.0, vh.gravity_mps2);

  const Eigen::Vector3d& I = vh.inertia_kgm2;
  const Eigen::Vector3d Iw = I.cwiseProduct(w);
  const Eigen::Vector3d w_dot = (tau - w.cross(Iw)).cwiseQuotient(I);

  // q' = 1/2 q (x) (0, w), on the raw (integrated) quaternion.
  const double qw = q_raw.w(), qx = q_raw.x(), qy = q_raw.y(), qz = q_raw.z();
  ydot[kIdxQ + 0] = 0.5 * (-qx * w.x() - qy * w.y() - qz * w.z());
  ydot[kIdxQ + 1] = 0.5 * (qw * w.x() + qy * w.z() - qz * w.y());
  ydot[kIdxQ + 2] = 0.5 * (qw * w.y() + qz * w.x() - qx * w.z());
  ydot[kIdxQ + 3] = 0.5 * (qw * w.z() + qx * w.y() - qy * w.x());
  for (int i = 0; i < 3; ++i) {
    ydot[kIdxP + i] = v[i];
    ydot[kIdxV + i] = a_W[i];
    ydot[kIdxW + i] = w_dot[i];
  }
  for (int i = 0; i < 4; ++i) ydot[kIdxRotor + i] = om_dot[i];
}

void pack_state(const RigidBodyState& x, double* y) {
  for (int i = 0; i < 3; ++i) {
    y[kIdxP + i] = x.p_WB_m[i];
    y[kIdxV + i] = x.v_WB_W_mps[i];
    y[kIdxW + i] = x.w_WB_B_radps[i];
  }
  y[kIdxQ + 0] = x.q_WB.w();
  y[kIdxQ + 1] = x.q_WB.x();
  y[kIdxQ + 2] = x.q_WB.y();
  y[kIdxQ + 3] = x.q_WB.z();
  for (int i = 0; i < 4; ++i) y[kIdxRotor + i] = x.rotor_speed_radps[i];
}

RigidBodyState unpack_state(const double* y) {
  RigidBodyState x;
  x.p_WB_m = Eigen::Vector3d(y[kIdxP], y[kIdxP + 1], y[kIdxP + 2]);
  x.v_WB_W_mps = Eigen::Vector3d(y[kIdxV], y[kIdxV + 1], y[kIdxV + 2]);
  x.q_WB = Eigen::Quaterniond(y[kIdxQ], y[kIdxQ + 1], y[kIdxQ + 2], y[kIdxQ + 3]);
  x.w_WB_B_radps = Eigen::Vector3d(y[kIdxW], y[kIdxW + 1], y[kIdxW + 2]);
  x.rotor_speed_radps = Eigen::Vector4d(y[kIdxRotor], y[kIdxRotor + 1], y[kIdxRotor + 2], y[kIdxRotor + 3]);
  return x;
}

std::array<double, kStateSize> rigid_body_rhs(const VehicleParams& vehicle, const RigidBodyState& x,
                                              const Eigen::Vector4d& rotor_cmd_radps,
                                              const Eigen::Vector3d& wind_W_mps, const Eigen::Vector4d& thrust_factor) {
  std::array<double, kStateSize> y{}, ydot{};
  pack_state(x, y.data());
  rigid_body_rhs(vehicle, y.data(), rotor_cmd_radps, wind_W_mps, ydot.data(), thrust_factor);
  return ydot;
}

Eigen::Vector3d euler_zyx_from_quaternion(const Eigen::Quaterniond& q_WB) {
  return euler_zyx(q_WB.normalized().toRotationMatrix());
}

Eigen::Quaterniond quaternion_from_euler_zyx(double roll_rad, double pitch_rad, double yaw_rad) {
  return Eigen::Quaterniond(Eigen::AngleAxisd(yaw_rad, Eigen::Vector3d::UnitZ()) *
                            Eigen::AngleAxisd(pitch_rad, Eigen::Vector3d::UnitY()) *
                            Eigen::AngleAxisd(roll_rad, Eigen::Vector3d::UnitX()));
}

double tilt_rad(const Eigen::Quaterniond& q_WB) {
  const Eigen::Matrix3d R = q_WB.normalized().toRotationMatrix();
  return std::acos(std::clamp(R(2, 2), -1.0, 1.0));
}

}  // namespace shelfcross::plant
