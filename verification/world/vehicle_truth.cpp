#include "verification/world/vehicle_truth.hpp"

#include <algorithm>
#include <cmath>

#include "sdk/state_record.hpp"
#include "shelfcross/rotation.hpp"

namespace shelfcross::verification {

plant::AutopilotParams autopilot_params_for(const Scenario& scenario) {
  plant::AutopilotParams p = scenario.autopilot;
  p.battery_start_pct = scenario.cosim.battery_start_pct;
  p.battery_endurance_s = scenario.cosim.endurance_s;
  return p;
}


Eigen::Isometry3d body_pose(const plant::RigidBodyState& s) {
  Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
  X.linear() = s.q_WB.toRotationMatrix();
  X.translation() = s.p_WB_m;
  return X;
}

std::optional<CellIndex> cell_at(const ShelfSpec& s, double y_S, double z_S) {
  const int columns = static_cast<int>(s.column_pitch_m.size());
  const int levels = static_cast<int>(s.row_pitch_m.size());
  for (int c = 1; c <= columns; ++c) {
    if (!(y_S <= post_y_S_m(s, c - 1) && y_S > post_y_S_m(s, c))) continue;
    for (int l = 1; l <= levels; ++l) {
      if (z_S >= beam_z_S_m(s, l - 1) && z_S < beam_z_S_m(s, l)) return CellIndex{l, c};
    }
  }
  return std::nullopt;
}

StateRecord state_from_senses(const plant::RigidBodyState& s, const plant::SensedReadings& sensed,
                              const Eigen::Vector3d& a_W_mps2, double ground_z_m, double battery_pct,
                              double motor_time_s, TimeNs t_ns) {
  StateRecord r;
  r.t_ns = t_ns;
  const Eigen::Matrix3d R = s.q_WB.toRotationMatrix();
  const Eigen::Vector3d rpy = euler_zyx(R);
  r.roll_rad = rpy.x();
  r.pitch_rad = rpy.y();
  r.yaw_rad = rpy.z();
  const Eigen::Vector3d v_H = Eigen::AngleAxisd(rpy.z(), Eigen::Vector3d::UnitZ()).inverse() * sensed.v_W_mps;
  r.vx_H_mps = v_H.x();
  r.vy_H_mps = v_H.y();
  r.vz_H_mps = v_H.z();
  // Specific force: f_B = R^T (a_W - g_W), g_W = (0, 0, -g).
  const Eigen::Vector3d f_B = R.transpose() * (a_W_mps2 + Eigen::Vector3d(0, 0, sdk::kStandardGravity_mps2));
  r.ax_B_mps2 = f_B.x();
  r.ay_B_mps2 = f_B.y();
  r.az_B_mps2 = f_B.z();
  r.height_m = sensed.height_W_m - ground_z_m;
  r.tof_m = sensed.tof_m;
  r.baro_m = 100.0 + sensed.baro_m;
  r.battery_pct = static_cast<int>(std::clamp(std::floor(battery_pct), 0.0, 100.0));
  r.motor_time_s = motor_time_s;
  r.temp_low_c = 55;
  r.temp_high_c = 57;
  return r;
}

double light_level(const Lighting& lighting) { return std::min(1.0, lighting.ambient + lighting.directional); }

ShelfCrossingMonitor::ShelfCrossingMonitor(const ShelfSpec& shelf, const Eigen::Vector3d& p_WB_m)
    : shelf_(shelf), X_SW_(shelf_pose_W(shelf).inverse()), p_S_m_(X_SW_ * p_WB_m) {}

ShelfCrossingMonitor::Faces ShelfCrossingMonitor::update(const Eigen::Vector3d& p_WB_m) {
  Faces faces;
  const double prev_x_S = p_S_m_.x();
  p_S_m_ = X_SW_ * p_WB_m;
  const Eigen::Vector3d& p_S = p_S_m_;
  if (prev_x_S < 0.0 && p_S.x() >= 0.0) {
    entry_cell_ = cell_at(shelf_, p_S.y(), p_S.z());
    if (entry_cell_) {
      const Eigen::Vector3d c = cell_centre_S_m(shelf_, entry_cell_->level, entry_cell_->column);
      entry_offset_y_m_ = p_S.y() - c.y();
      entry_offset_z_m_ = p_S.z() - c.z();
    }
    faces.front = true;
  }
  if (prev_x_S < shelf_.depth_m && p_S.x() >= shelf_.depth_m) {
    const auto exit_cell = cell_at(shelf_, p_S.y(), p_S.z());
    if (entry_cell_ && exit_cell && *entry_cell_ == *exit_cell) crossed_ = exit_cell;
    faces.back = true;
  }
  return faces;
}

}  // namespace shelfcross::verification
