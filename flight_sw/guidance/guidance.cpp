#include "flight_sw/guidance/guidance.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

#include <Eigen/Geometry>

#include "shelfcross/rotation.hpp"

namespace shelfcross::flight_sw {

Eigen::Vector2d to_body_xy(const Eigen::Vector2d& v_F, double yaw_F_rad) {
  const double c = std::cos(yaw_F_rad), s = std::sin(yaw_F_rad);
  return {c * v_F.x() + s * v_F.y(), -s * v_F.x() + c * v_F.y()};  // R_z(-yaw) v_F
}

Eigen::Vector3d capped(Eigen::Vector3d v, double max_norm) {
  if (v.norm() > max_norm) v *= max_norm / v.norm();
  return v;
}

namespace {
// A velocity of a frame F (horizontal x, y; z up) flown by a vehicle at heading yaw_F in F:
// horizontally R_z(-yaw) v_F, vertically as it is, turning at yaw_rate_radps.
VelocityCommand velocity_in_body(const Eigen::Vector3d& v_F_mps, double yaw_F_rad, double yaw_rate_radps) {
  const Eigen::Vector2d v_B = to_body_xy(v_F_mps.head<2>(), yaw_F_rad);
  return {v_B.x(), v_B.y(), v_F_mps.z(), yaw_rate_radps};
}
}  // namespace

// ---- FindShelf and GoToViewpoint ----

VelocityCommand fragment_velocity(const FlightConfig& config, const std::vector<TagBlob>& tags,
                                  double largest_tag_area_px, double viewpoint_range_m) {
  const ControlGains& g = config.control;
  const CameraIntrinsics& k = config.camera;
  cv::Point2d c(0, 0);
  for (const TagBlob& t : tags) c += t.centre_px;
  c *= 1.0 / static_cast<double>(tags.size());
  const double far_side_px = k.fx_px * config.shelf.tag_size_m / (1.2 * viewpoint_range_m);
  VelocityCommand v;
  v.vx_B_mps = std::sqrt(largest_tag_area_px) > far_side_px ? -g.back_off_speed_mps : 0.0;
  v.yaw_rate_radps = std::clamp(g.viewpoint_yaw_kp * std::atan((k.cx_px - c.x) / k.fx_px),
                                -g.yaw_rate_max_radps, g.yaw_rate_max_radps);
  v.vz_mps = std::clamp(g.viewpoint_kp * (k.cy_px - c.y) / k.fy_px, -g.z_speed_max_mps,
                        g.z_speed_max_mps);
  return v;
}

VelocityCommand viewpoint_velocity(const ControlGains& g, const Eigen::Vector3d& e1_G_m, double yaw_G_rad) {
  return velocity_in_body(capped(g.viewpoint_kp * e1_G_m, g.viewpoint_speed_max_mps), yaw_G_rad,
                          std::clamp(-g.viewpoint_yaw_kp * yaw_G_rad, -g.yaw_rate_max_radps, g.yaw_rate_max_radps));
}

// ---- Approach ----

ApproachErrors approach_errors(const CameraIntrinsics& k, const cv::Point2d& box_centre_px,
                               const PoseEstimate& pose_K) {
  const cv::Point2d& c = box_centre_px;
  const double range_m = std::max(0.05, -pose_K.X_FC.translation().x());
  ApproachErrors e;
  e.e_z_m = (k.cy_px - c.y) * range_m / k.fy_px;     // eq. 11
  e.e_psi_rad = std::atan((k.cx_px - c.x) / k.fx_px);  // eq. 13, 14
  e.psi_cell_rad = pose_K.yaw_rad + e.e_psi_rad;
  e.range_m = range_m;
  return e;
}

// A fixed angle psi_L narrows the lateral law's band with the range (0.04 rad: 2.8 cm either
// side at 0.7 m) while a sideways step's coast does not shrink: V_y over the video latency plus
// the autopilot's lag, 0.08 m/s x (0.35 + 0.5) s = 6.8 cm, more than that band's 5.6 cm width,
// so the law stepped left and right in front of the cell, and each step restarted the
// stillness the crossing waits for. Held at lateral_threshold_m (4 cm: an 8 cm band) the step
// ends inside the band. The crossing does not need the vehicle closer to the normal: it flies
// the line from the last pose through the cell centre at mid-depth, on which an offset y0 at
// range r leaves y0 (D/2) / (r + D/2) at either face (4 cm at 0.6 m: 0.9 cm).
double approach_lateral_mps(const ControlGains& g, const ApproachErrors& e) {
  const double threshold_rad = std::max(g.psi_lateral_threshold_rad, std::atan(g.lateral_threshold_m / e.range_m));
  return bang_off_bang(e.psi_cell_rad, threshold_rad, g.lateral_speed_mps);  // Fig. 19
}

ApproachHold approach_hold(const FlightConfig& config, const ApproachErrors& e, double still_s,
                           double range_x_m) {
  const MissionParams& m = config.mission;
  const ControlGains& g = config.control;
  ApproachHold h;
  h.settled = still_s >= m.approach.settle_s && std::abs(e.e_z_m) <= m.approach.settle_z_m &&
              std::abs(e.e_psi_rad) <= m.approach.settle_psi_rad;
  h.in_cone = std::abs(e.psi_cell_rad) <= g.approach_cone_rad;
  h.settling = range_x_m <= g.commit_range_m && !h.settled;
  return h;
}

double approach_forward_mps(const ControlGains& g, bool hold, bool identified, double range_x_m,
                            double viewpoint_range_m) {
  if (!identified) return range_x_m < viewpoint_range_m ? -g.back_off_speed_mps : 0.0;
  return hold ? 0.0 : g.forward_speed_mps;  // eq. 10
}

VelocityCommand back_off_velocity(const ControlGains& g) { return {-g.back_off_speed_mps, 0.0, 0.0, 0.0}; }

// ---- Crossing ----

double crossing_beyond_m(const FlightConfig& config, const std::optional<double>& behind_m) {
  const MissionParams& mp = config.mission;
  double beyond_m = mp.crossing.beyond_distance_m;
  if (behind_m) {
    beyond_m = std::min(beyond_m, *behind_m - config.shelf.depth_m - mp.vehicle_size_m.x() - mp.crossing.stop_distance_m);
  }
  return beyond_m;
}

CrossingPlan plan_crossing(const FlightConfig& config, const PoseEstimate& pose_K, double yaw_rate_cmd_radps,
                           double beyond_m, double forward_gain, const Eigen::Vector2d& start_O_m, double yaw_O_rad) {
  const MissionParams& mp = config.mission;
  const double distance = -pose_K.p_FB_m().x() + config.shelf.depth_m + 0.5 * mp.vehicle_size_m.x() + beyond_m;
  const Eigen::Vector3d d = crossing_direction_K(config.shelf, pose_K);
  CrossingPlan plan;
  const double turn_rad = yaw_rate_cmd_radps * kHeadingCarry_s;
  plan.dir_B = to_body_xy(d.head<2>(), pose_K.yaw_rad + turn_rad);  // |dir_B| = |d_xy|
  plan.end.line_m = distance / d.x() * plan.dir_B.norm();
  plan.end.start_O_m = start_O_m;
  plan.end.axis_O = Eigen::Rotation2Dd(yaw_O_rad + turn_rad) * plan.dir_B.normalized();
  plan.end.timed_ns =
      seconds_to_ns(distance / (d.x() * config.control.crossing_speed_mps * forward_gain) + kVelocityLag_s);
  return plan;
}

double crossing_vz_mps(const ControlGains& g, double cell_height_m, double height_m) {
  return height_hold_vz_mps(cell_height_m, height_m, g.crossing_kp_z, g.crossing_z_speed_max_mps);
}

void trim_crossing(CrossingPlan& plan, const ControlGains& g, double drift_y_mps) {
  const Eigen::Vector2d line_B = g.crossing_speed_mps * plan.dir_B;
  plan.trim_B_mps = Eigen::Vector2d(0.0, -drift_y_mps);
  const Eigen::Vector2d commanded_B = line_B + plan.trim_B_mps;
  const double turn_rad = std::atan2(commanded_B.y(), commanded_B.x()) - std::atan2(line_B.y(), line_B.x());
  plan.end.axis_O = Eigen::Rotation2Dd(turn_rad) * plan.end.axis_O;
}

VelocityCommand crossing_velocity(const ControlGains& g, const CrossingPlan& plan, double vz_mps) {
  const Eigen::Vector2d v_B = g.crossing_speed_mps * plan.dir_B + plan.trim_B_mps;
  return {v_B.x(), v_B.y(), vz_mps, 0.0};
}

// ---- Transfer ----

std::vector<Eigen::Vector3d> transfer_waypoints_G(const FlightConfig& config, const Eigen::Vector3d& p,
                                                  const Eigen::Vector3d& viewpoint_G_m, bool last_shelf) {
  const KnownShelf& sh = config.shelf;
  const StrategyParams& st = config.strategy;
  const Eigen::Vector3d half = 0.5 * config.mission.vehicle_size_m;
  const double half_tag = 0.5 * sh.tag_size_m;
  const cv::Point3d top_left = grid_tag_G(sh, 0, sh.levels()), bottom_right = grid_tag_G(sh, sh.columns(), 0);
  // The last leg (down to the viewpoint height, or back to the centre line) is flown clear of
  // the shelf just passed: at least the clearance behind its back face, even when the next
  // shelf's viewpoint is closer (GoToViewpoint then brings the vehicle back to it visually).
  const double clearance = st.mode == Strategy::over_tops ? st.top_clearance_m : st.end_clearance_m;
  const double x_end = std::max(last_shelf ? sh.depth_m + half.x() + config.mission.crossing.beyond_distance_m
                                           : config.layout.shelf_spacing_m + viewpoint_G_m.x(),
                                sh.depth_m + half.x() + clearance);
  const Eigen::Vector3d end(x_end, viewpoint_G_m.y(), viewpoint_G_m.z());
  if (st.mode == Strategy::over_tops) {
    // Bottom of the vehicle top_clearance_m above the top tags' upper edge.
    const double z = std::max(top_left.z, bottom_right.z) + half_tag + half.z() + st.top_clearance_m;
    return {{p.x(), p.y(), z}, {x_end, p.y(), z}, end};
  }
  // Past the nearer end: the vehicle's widest half (any heading) beyond the grid's side
  // edge (tags included) by end_clearance_m.
  const double y_edge = std::max(std::abs(top_left.y), std::abs(bottom_right.y)) + half_tag;
  const double y = (p.y() >= 0.0 ? 1.0 : -1.0) * (y_edge + half.head<2>().norm() + st.end_clearance_m);
  return {{p.x(), y, p.z()}, {x_end, y, p.z()}, end};
}

VelocityCommand transfer_velocity(const FlightConfig& config, const Eigen::Vector3d& e_O_m, double yaw_O_rad,
                                  double hold_yaw_O_rad) {
  const StrategyParams& st = config.strategy;
  return velocity_in_body(
      capped(st.transfer_kp * e_O_m, st.transfer_speed_mps), yaw_O_rad,
      std::clamp(st.transfer_yaw_kp * wrap_pi(hold_yaw_O_rad - yaw_O_rad),
                 -config.control.yaw_rate_max_radps, config.control.yaw_rate_max_radps));
}

}  // namespace shelfcross::flight_sw
