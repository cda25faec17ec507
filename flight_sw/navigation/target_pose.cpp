#include "flight_sw/navigation/target_pose.hpp"

#include <algorithm>
#include <cmath>

#include "shelfcross/rotation.hpp"

namespace shelfcross::flight_sw {

std::optional<double> cell_height_m(const std::optional<StateRecord>& state, double z_K_m) {
  if (!state) return std::nullopt;
  return cell_centre_height_m(state->height_m, z_K_m);
}

double row_height_m(const FlightConfig& config, double height_m, double pitch_rad, double v_px, double range_m) {
  const CameraIntrinsics& k = config.camera;
  const double elevation = std::atan((k.cy_px - v_px) / k.fy_px) - (pitch_rad + config.mount.pitch_rad);
  return height_m + range_m * std::tan(elevation);
}

double pose_jump_limit_m(const MissionParams& mission, double range_m) {
  const double r = std::max(1.0, range_m / kPoseJumpRange_m);
  return mission.target.pose_jump_m * r * r;
}

// ---- RecentStates ----

void RecentStates::on_state(const StateRecord& s) {
  records_.push_back(s);
  while (ns_to_seconds(s.t_ns - records_.front().t_ns) > 1.0) records_.pop_front();
}

std::optional<StateSpan> RecentStates::span(TimeNs t_ns) const {
  if (records_.empty()) return std::nullopt;
  const auto one = [](const StateRecord& r) { return StateSpan{r.pitch_rad, r.pitch_rad, r.height_m, r.height_m}; };
  const TimeNs from_ns = t_ns - seconds_to_ns(kLevelWindow_s);
  std::optional<StateSpan> span;
  for (const StateRecord& r : records_) {
    if (r.t_ns < from_ns || r.t_ns > t_ns) continue;
    if (!span) span = one(r);
    span->pitch_min_rad = std::min(span->pitch_min_rad, r.pitch_rad);
    span->pitch_max_rad = std::max(span->pitch_max_rad, r.pitch_rad);
    span->height_min_m = std::min(span->height_min_m, r.height_m);
    span->height_max_m = std::max(span->height_max_m, r.height_m);
  }
  return span ? *span : one(records_.back());
}

// ---- TargetPoses ----

std::optional<PoseEstimate> TargetPoses::carried_pose() const {
  if (!pose_K_ || !odometry_now_ || !odometry_at_pose_) return std::nullopt;
  return pose_after_motion(*pose_K_, odometry_at_pose_->yaw_O_rad, odometry_now_->p_O_m - odometry_at_pose_->p_O_m,
                           wrap_pi(odometry_now_->yaw_O_rad - odometry_at_pose_->yaw_O_rad));
}

void TargetPoses::accept(const PoseEstimate& pose, TimeNs t_ns, bool decides) {
  pose_K_ = pose;
  pose_t_ns_ = t_ns;
  odometry_at_pose_ = odometry_now_;
  pose_decides_ = decides;
  if (pose_decides_) {  // the crossing is judged on poses from nearly whole pictures only
    decision_pose_K_ = pose;
    decision_pose_t_ns_ = t_ns;
  }
}

void TargetPoses::forget_poses() {
  pose_K_.reset();
  decision_pose_K_.reset();
}

// ---- The plausibility filter ----

namespace {

enum class LevelVerdict { Same, Another, Unsure };

// Between frames the vehicle moves centimetres, so a pose that jumps further than
// pose_jump_limit_m (+ 1 m/s of the time since the last one) or turns more than pose_jump_rad
// (+ 1 rad/s) comes from a wrong corner tag (a neighbour's, as a true corner leaves the view
// close to the shelf): not a measurement. Once the last pose is older than pose_jump_window_s
// there is nothing to compare with.
bool jumped(const MissionParams& mp, const PoseEstimate& pose, const PoseEstimate& last, double dt) {
  const double jump_m = (pose.p_FB_m() - last.p_FB_m()).norm();
  const double turn = std::abs(wrap_pi(pose.yaw_rad - last.yaw_rad));
  const double range_m = -last.p_FB_m().x();
  return dt <= mp.target.pose_jump_window_s &&
         (jump_m > pose_jump_limit_m(mp, range_m) + 1.0 * dt || turn > mp.target.pose_jump_rad + 1.0 * dt);
}

// A pose from touched tags must agree with the last pose carried to now by the state
// odometry: within the jump limit plus the odometry's drift since, within pose_jump_rad, and
// for at most mission.coast_s after the last pose.
bool agrees_with_carried(const MissionParams& mp, const PoseEstimate& pose, const std::optional<PoseEstimate>& carried,
                         double age_s) {
  return carried && age_s <= mp.approach.coast_s &&
         (pose.p_FB_m() - carried->p_FB_m()).norm() <=
             pose_jump_limit_m(mp, -carried->p_FB_m().x()) + kOdometryDrift_mps * age_s &&
         std::abs(wrap_pi(pose.yaw_rad - carried->yaw_rad)) <= mp.target.pose_jump_rad;
}

// The target cell's centre stays at one height above the take-off point. After the target was
// lost, the tracked box can settle on the cell above or below (and the jump test no longer
// applies once the last pose is old); a level's corner tags make as good a pose as the
// target's, but one a row pitch off in height. The height check tells them apart: the cell
// centre's height must stay within 0.4 of the smallest row pitch of the height found, from the
// grid's pose, when the target was chosen. The height is the pose's (cell_height_m) when the
// pose's pitch agrees with a state record's: the pose solves the camera's attitude, which the
// record gives only in whole degrees and a video latency late (a Tello tipping 3 deg as it
// starts, stops or meets a gust moves the cell's image row by 12 cm at 2.3 m). Far out, four
// tags leave the pose's tilt ambiguous (planar PnP's two solutions: the other one tilted
// several degrees more, its height decimetres off); a pose whose pitch disagrees falls back on
// the image row under the state's pitch (row_height_m).
//
// Which record describes the picture is not known (the latency is not), so the height is taken
// under every record of the window (StateSpan): an interval, the pose's height h - z_K over the
// window's heights, or the image row's, lowest under the largest pitch and the lowest height.
// Wholly within the tolerance: the target's level; wholly outside: another's; across its edge:
// not told on this picture. Starting the approach from a hover, the Tello tips 3 deg within the
// latency and climbs at 0.2 m/s toward the cell's height: judged under the newest record alone,
// the target's own poses read 14-19 cm off (flight_sw/README.md, "The target's level").
LevelVerdict judge_level(const FlightConfig& config, const PoseCandidate& candidate, const StateSpan& states,
                         double target_height_m) {
  const PoseEstimate& pose = candidate.pose;
  const bool pose_attitude_agrees =
      pose.pitch_rad >= states.pitch_min_rad - kLevelPitchAgreement_rad &&
      pose.pitch_rad <= states.pitch_max_rad + kLevelPitchAgreement_rad;
  double lo_m = 0.0, hi_m = 0.0;
  if (pose_attitude_agrees) {
    lo_m = cell_centre_height_m(states.height_min_m, pose.p_FB_m().z());
    hi_m = cell_centre_height_m(states.height_max_m, pose.p_FB_m().z());
  } else {
    const double v_px = candidate.corners_centre_px.y, range_m = -pose.X_FC.translation().x();
    lo_m = row_height_m(config, states.height_min_m, states.pitch_max_rad, v_px, range_m);
    hi_m = row_height_m(config, states.height_max_m, states.pitch_min_rad, v_px, range_m);
  }
  const auto& rows = config.shelf.row_pitch_m;
  const double tol_m = 0.4 * *std::min_element(rows.begin(), rows.end());
  const double nearest_m = std::max({0.0, lo_m - target_height_m, target_height_m - hi_m});
  const double farthest_m = std::max(std::abs(lo_m - target_height_m), std::abs(hi_m - target_height_m));
  if (farthest_m <= tol_m) return LevelVerdict::Same;
  if (nearest_m > tol_m) return LevelVerdict::Another;
  return LevelVerdict::Unsure;
}

}  // namespace

PoseVerdict judge_pose(const FlightConfig& config, const PoseCandidate& candidate, const TargetPoses& history,
                       const std::optional<StateSpan>& states, const std::optional<double>& target_height_m) {
  const MissionParams& mp = config.mission;
  const double since_last_s = ns_to_seconds(candidate.t_ns - history.pose_t_ns());
  if (history.pose_K() && jumped(mp, candidate.pose, *history.pose_K(), since_last_s)) return PoseVerdict::Jumped;
  if (candidate.touched && !agrees_with_carried(mp, candidate.pose, history.carried_pose(), since_last_s)) {
    return PoseVerdict::Hidden;
  }
  // (mission.level_check off: for verification studies only, to show what the check prevents.)
  if (mp.target.level_check && target_height_m && states) {
    switch (judge_level(config, candidate, *states, *target_height_m)) {
      case LevelVerdict::Same: break;
      case LevelVerdict::Another: return PoseVerdict::WrongLevel;
      case LevelVerdict::Unsure: return PoseVerdict::LevelUnsure;
    }
  }
  return PoseVerdict::Plausible;
}

}  // namespace shelfcross::flight_sw
