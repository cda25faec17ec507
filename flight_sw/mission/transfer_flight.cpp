#include "flight_sw/mission/transfer_flight.hpp"

#include <Eigen/Geometry>

#include "flight_sw/guidance/guidance.hpp"

namespace shelfcross::flight_sw {

void TransferFlight::plan(const FlightConfig& config, const PoseEstimate& pose_G, double state_yaw_rad,
                          const Eigen::Vector3d& p_O_m, const Eigen::Vector3d& viewpoint_G_m, bool last_shelf,
                          TimeNs now_ns) {
  const Eigen::Vector3d p = pose_G.p_FB_m();
  const std::vector<Eigen::Vector3d> w_G = transfer_waypoints_G(config, p, viewpoint_G_m, last_shelf);
  const double yaw_G_in_O = state_yaw_rad - pose_G.yaw_rad;
  const Eigen::Rotation2Dd R(yaw_G_in_O);
  waypoints_O_m_.clear();
  for (const Eigen::Vector3d& w : w_G) {
    const Eigen::Vector2d d = R * (w - p).head<2>();
    waypoints_O_m_.push_back({p_O_m.x() + d.x(), p_O_m.y() + d.y(), p_O_m.z() + (w.z() - p.z())});
  }
  hold_yaw_O_rad_ = yaw_G_in_O;
  waypoint_ = 0;
  leg_start_ns_ = now_ns;
}

TransferFlight::Progress TransferFlight::on_state(const Eigen::Vector3d& p_O_m, double tolerance_m, TimeNs now_ns) {
  Progress out;
  out.e_O_m = waypoints_O_m_[waypoint_] - p_O_m;
  if (out.e_O_m.norm() < tolerance_m) {
    ++waypoint_;
    leg_start_ns_ = now_ns;
    if (waypoint_ == waypoints_O_m_.size()) {
      out.arrived = true;
      return out;
    }
    out.next_leg = true;
    out.e_O_m = waypoints_O_m_[waypoint_] - p_O_m;
  }
  return out;
}

}  // namespace shelfcross::flight_sw
