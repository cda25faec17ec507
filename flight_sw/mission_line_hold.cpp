// The mission's side of the line-hold gate and the in-crossing watch (line_hold.hpp): what the
// approach feeds the monitor, when it holds short or declines, and what the crossing does on
// each state record. The pure parts (the wander, the forecast, the gate, the watch) are in
// line_hold.cpp and target_tracker.cpp.

#include <cmath>
#include <cstdio>

#include <Eigen/Geometry>

#include "flight_sw/flight_software.hpp"
#include "flight_sw/guidance.hpp"

namespace shelfcross::flight_sw {


// Quiet: no lateral command has acted for settle_s (more than the video latency plus the
// autopilot's velocity lag), so what moves the vehicle sideways now nobody commanded.
bool FlightSoftware::quiet_at(TimeNs t_ns) const {
  return ns_to_seconds(t_ns - lateral_active_ns_) >= config_.mission.settle_s;
}

LineHoldForecast FlightSoftware::line_hold_forecast(const PoseEstimate& pose_K) {
  const LineWander w = line_hold_.wander(now_ns_, config_.mission.line_hold_window_s);
  telemetry_.control.line_hold = forecast_line_hold(config_.mission, w, blind_crossing_s(config_, -pose_K.p_FB_m().x()));
  return telemetry_.control.line_hold;
}

void FlightSoftware::feed_line_hold(bool found, const std::optional<OdometryFix>& odometry) {
  const PoseEstimate* clean = found && tracker_.poses().pose_decides() ? &*tracker_.poses().pose_K() : nullptr;
  line_hold_.on_picture(now_ns_, clean, odometry, quiet_at(now_ns_), config_.mission.coast_s);
}

// The crossing is judged on the last pose from a nearly whole picture with clean corner tags
// (TargetTracker::decision_pose_K). Over a lossy link the picture on which the tags leave the
// view often comes more than pose_fresh_s after the last such pose; then that pose, if it is
// the line-hold monitor's anchor (taken quiet, no lateral command since, at most coast_s old),
// is judged carried to now by the state odometry. The odometry may have missed up to
// kOdometryDrift_mps (half the state's 0.1 m/s step) of sideways motion per second since: the
// forecast across grows by that much, so the gate leaves the margin around the worst place the
// vehicle may be (at 0.4 s old, 2 cm of the 8.4 cm a 34 cm column leaves). The height is the
// state height's either way (crossing_refusal).
PoseEstimate FlightSoftware::crossing_gate_pose(CrossingGateInput& gate) {
  const TimeNs pose_t_ns = tracker_.poses().decision_pose_t_ns();
  PoseEstimate pose = *tracker_.poses().decision_pose_K();
  gate.pose_age_s = ns_to_seconds(now_ns_ - pose_t_ns);
  gate.still_for_s = ns_to_seconds(pose_t_ns - lateral_active_ns_);
  double carried_s = 0.0;
  if (gate.pose_age_s > config_.mission.pose_fresh_s && state_fresh()) {
    const auto c = line_hold_.carried(now_ns_, OdometryFix{odometry_.p_O_m(), state_->yaw_rad}, config_.mission.coast_s);
    if (c && c->second == pose_t_ns) {
      pose = c->first;
      carried_s = gate.pose_age_s;
      gate.pose_age_s = 0.0;  // where the odometry puts the vehicle now
    }
  }
  gate.line_hold = line_hold_forecast(pose);
  gate.line_hold.y_m += kOdometryDrift_mps * carried_s;
  telemetry_.control.line_hold = gate.line_hold;
  return pose;
}

bool FlightSoftware::too_rough_to_cross(const PoseEstimate& pose_K) {
  const MissionParams& m = config_.mission;
  if (-pose_K.p_FB_m().x() > config_.control.commit_range_m || tracker_.identification().identity() != CellIdentity::Confirmed) {
    rough_since_ns_.reset();
    return false;
  }
  // The air alone: even a line through the cell's centre would not be held. (An off-centre
  // line is the approach's to correct, and the gate's to judge with the forecast.)
  const LineHoldForecast f = line_hold_forecast(pose_K);
  const LineRoom room = line_room(config_, *tracker_.target(), pose_K);
  // Not measured yet (the quiet stretch shorter than line_hold_min_span_s): hold short until
  // it is, or the settling's hold is given up (settle_hold_s).
  if (!f.measured) return true;
  const bool rough = f.y_m > room.tol_y_m || f.z_m > room.tol_z_m;
  if (!rough) {
    rough_since_ns_.reset();
    return false;
  }
  if (!rough_since_ns_) {
    rough_since_ns_ = now_ns_;
    telemetry_.event = "holding short: the hover's wander (" + centimetres_text(f.y_m) + " across, " + centimetres_text(f.z_m) +
                       " up) leaves the line no room";
  }
  if (ns_to_seconds(now_ns_ - *rough_since_ns_) > m.calm_wait_s) {
    back_out_and_land(std::string(kCrossingDeclined) + kLineCannotBeHeld + " (wander " + centimetres_text(f.y_m) + " across, " + centimetres_text(f.z_m) + " up, for " +
                     std::to_string(static_cast<int>(m.calm_wait_s)) + " s)");
  }
  return true;
}

void FlightSoftware::back_out_and_land(const std::string& reason, double flown_in_m) {
  // Back straight out (the heading is on the cell normal) to give_up_clearance_m in front of
  // the shelf by the last pose (and what was flown in since), then land there (supervise): clear of the frame whatever a
  // gust does during the descent.
  double back_m = config_.mission.give_up_clearance_m + flown_in_m;
  if (const std::optional<PoseEstimate>& pose_K = tracker_.poses().pose_K()) back_m += pose_K->p_FB_m().x();
  retreat_until_ns_ = now_ns_ + seconds_to_ns(std::max(0.0, back_m) / config_.control.back_off_speed_mps);
  retreat_reason_ = reason;
  telemetry_.event = retreat_reason_ + ": backing out to land clear of the shelf";
  sticks_.restart_loops();
  sticks_.set(back_off_velocity(config_.control), now_ns_);
}

// On each state record of the crossing: the watch's verdict (line_hold.hpp); a drift seen while
// the vehicle can still stop short of the front face stops it and backs it out, a refusal of
// the crossing like the gate's (crossing_attempts of them decline it).
void FlightSoftware::watch_crossing(const StateRecord& s) {
  const Eigen::Vector2d v_O = Eigen::Rotation2Dd(s.yaw_rad) * Eigen::Vector2d(s.vx_H_mps, s.vy_H_mps);
  const CrossingWatchVerdict v = crossing_watch(crossing_end_, watch_, config_.mission, odometry_.p_O_m(), v_O,
                                                s.height_m - *crossing_height_m_, s.vz_H_mps);
  if (!v.back_out) return;
  ++telemetry_.control.crossings_backed_out;
  const std::string why = "drift seen before the cell (" + centimetres_text(v.across_m) + " across, " + centimetres_text(v.height_m) + " up)";
  enter(Phase::Approach, "crossing stopped: " + why + ": backing out");
  crossing_height_m_.reset();
  line_hold_.clear();
  lateral_active_ns_ = now_ns_;  // stillness to be shown anew
  sticks_.set(back_off_velocity(config_.control), now_ns_);
  if (++crossing_refusals_ >= config_.mission.crossing_attempts) {
    back_out_and_land(std::string(kCrossingDeclined) + kLineCannotBeHeld + ": " + why, (odometry_.p_O_m().head<2>() - crossing_end_.start_O_m).dot(crossing_end_.axis_O));
  } else {
    back_off_since_ns_ = now_ns_;
  }
  emit_rc(true);
}

}  // namespace shelfcross::flight_sw
