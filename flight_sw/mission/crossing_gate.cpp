// The crossing gate's side of the approach (crossing_gate.hpp): what the approach feeds the
// line-hold monitor, the cell height and the forward gain, when it holds short or declines, and
// the gate on the last deciding pose. The pure parts (the wander, the forecast, the gate, the
// watch) are in guidance/line_hold.cpp and guidance/crossing_law.cpp.

#include "flight_sw/mission/crossing_gate.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "flight_sw/guidance/guidance.hpp"
#include "flight_sw/text.hpp"
#include "shelfcross/rotation.hpp"

namespace shelfcross::flight_sw {

namespace {
// A quiet stretch this fraction of line_hold_window_s or longer is a whole window (the
// records' and pictures' spacing leaves the stretch a little short of the window).
constexpr double kWholeWindow = 0.9;
}  // namespace

void CrossingGate::new_target() {
  rough_seen_ns_.reset();
  cell_height_.clear();
  line_hold_.clear();
  forward_gain_.restart();
}

// Quiet: no lateral command has acted and the heading has held still for settle_s (more than
// the video latency plus the autopilot's velocity lag), so what moves the vehicle sideways now
// nobody commanded.
bool CrossingGate::quiet_at(TimeNs t_ns) const {
  return ns_to_seconds(t_ns - still_since_ns()) >= config_.mission.approach.settle_s;
}

void CrossingGate::on_state(const StateRecord& s, bool approaching) {
  heading_.on_state(s.t_ns, s.yaw_rad);
  cell_height_.on_state(s);
  if (approaching) line_hold_.on_state(s, quiet_at(s.t_ns));
}

LineHoldForecast CrossingGate::forecast(MissionFacts& facts, const PoseEstimate& pose_K) {
  const LineWander w = line_hold_.wander(facts.now_ns, config_.mission.line_hold.line_hold_window_s);
  facts.telemetry.control.line_hold =
      forecast_line_hold(config_.mission, w, blind_crossing_s(config_, -pose_K.p_FB_m().x()));
  return facts.telemetry.control.line_hold;
}

void CrossingGate::on_picture(const MissionFacts& facts, const TargetTracker& tracker, bool found,
                              const std::optional<OdometryFix>& odometry) {
  const PoseEstimate* clean = found && tracker.poses().pose_decides() ? &*tracker.poses().pose_K() : nullptr;
  line_hold_.on_picture(facts.now_ns, clean, odometry, quiet_at(facts.now_ns), config_.mission.approach.coast_s);
}

// The forward speed gain (odometry.hpp, ForwardGainEstimator), then a sample of the target cell
// centre's height in the state height's frame (CellHeightEstimator): with a fresh state, inside
// commit_range_m, and once the state has shown the vehicle vertically still for vertical_lag_s.
void CrossingGate::on_deciding_pose(MissionFacts& facts, const PoseEstimate& pose) {
  forward_gain_.on_pose(facts.now_ns, pose.p_FB_m().x());
  facts.telemetry.control.forward_gain = forward_gain_.gain();
  if (!facts.state_fresh() || -pose.p_FB_m().x() > config_.control.commit_range_m) return;
  if (!cell_height_.vertically_still_for(facts.now_ns, config_.mission.crossing.vertical_lag_s)) return;
  cell_height_.sample(facts.state->height_m, pose.p_FB_m().z());
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
PoseEstimate CrossingGate::gate_pose(MissionFacts& facts, const TargetTracker& tracker, CrossingGateInput& gate) {
  const TimeNs pose_t_ns = tracker.poses().decision_pose_t_ns();
  PoseEstimate pose = *tracker.poses().decision_pose_K();
  gate.pose_age_s = ns_to_seconds(facts.now_ns - pose_t_ns);
  gate.still_for_s = ns_to_seconds(pose_t_ns - lateral_active_ns_);
  gate.heading_still_for_s = ns_to_seconds(pose_t_ns - heading_.since_ns());
  double carried_s = 0.0;
  if (gate.pose_age_s > config_.mission.crossing.pose_fresh_s && facts.state_fresh()) {
    const auto c = line_hold_.carried(facts.now_ns, OdometryFix{facts.odometry.p_O_m(), facts.state->yaw_rad},
                                      config_.mission.approach.coast_s);
    if (c && c->second == pose_t_ns) {
      pose = c->first;
      carried_s = gate.pose_age_s;
      gate.pose_age_s = 0.0;  // where the odometry puts the vehicle now
    }
  }
  gate.line_hold = forecast(facts, pose);
  gate.line_hold.y_m += kOdometryDrift_mps * carried_s;
  facts.telemetry.control.line_hold = gate.line_hold;
  return pose;
}

RoughAir CrossingGate::too_rough(MissionFacts& facts, const TargetTracker& tracker, const PoseEstimate& pose_K) {
  const MissionParams& m = config_.mission;
  if (-pose_K.p_FB_m().x() > config_.control.commit_range_m ||
      tracker.identification().identity() != CellIdentity::Confirmed) {
    rough_since_ns_.reset();
    return {};
  }
  // The air alone: even a line through the cell's centre would not be held. (An off-centre
  // line is the approach's to correct, and the gate's to judge with the forecast.)
  const LineHoldForecast f = forecast(facts, pose_K);
  const LineRoom room = line_room(config_, *tracker.target(), pose_K);
  // Not measured yet (the quiet stretch shorter than line_hold_min_span_s): hold short until
  // it is, or the settling's hold is given up (settle_hold_s).
  if (!f.measured) return {true, std::nullopt};
  // A height hold that follows the range (as identified) would climb into the beam above even
  // from the cell's centre: no wait for calmer air helps, the crossing is declined now.
  if (const std::optional<double> cell_centre_h_m = cell_height_.measured_m()) {
    const double climb = range_hold_climb_m(config_, *tracker.target(), *cell_centre_h_m);
    const double room_z = room.room_z_m - line_hold_keep_m(m, f.error_z_m);
    if (climb > 0.0 && climb + f.z_m > room_z) {
      return {true, std::string(kCrossingDeclined) + kLineCannotBeHeld +
                        " vertically (the height hold follows the range: a climb of " + centimetres_text(climb) +
                        " forecast over the cell, " + centimetres_text(room_z) + " of room)"};
    }
  }
  // Rough: no room now, or calm for less than the blind crossing since a whole window left
  // none (crossing_refusal). A shorter quiet stretch (the hold just begun, the settling's
  // last motion in it) is scaled up by sqrt(T / s) and holds the vehicle short, but is too
  // short a sample of the air to be remembered.
  const bool no_room = f.y_m > room.room_y_m - line_hold_keep_m(m, f.error_y_m) ||
                       f.z_m > room.room_z_m - line_hold_keep_m(m, f.error_z_m);
  if (no_room && f.span_s >= kWholeWindow * m.line_hold.line_hold_window_s) rough_seen_ns_ = facts.now_ns;
  const bool rough = no_room || (rough_seen_ns_ && ns_to_seconds(facts.now_ns - *rough_seen_ns_) <
                                                       blind_crossing_s(config_, -pose_K.p_FB_m().x()));
  if (!rough) {
    rough_since_ns_.reset();
    return {};
  }
  if (!rough_since_ns_) {
    rough_since_ns_ = facts.now_ns;
    facts.telemetry.event = "holding short: the hover's wander (" + centimetres_text(f.y_m) + " across, " +
                            centimetres_text(f.z_m) + " up) leaves the line no room" + air_text(f);
  }
  if (ns_to_seconds(facts.now_ns - *rough_since_ns_) > m.line_hold.calm_wait_s) {
    return {true, std::string(kCrossingDeclined) + kLineCannotBeHeld + " (wander " + centimetres_text(f.y_m) +
                      " across, " + centimetres_text(f.z_m) + " up, for " +
                      std::to_string(static_cast<int>(m.line_hold.calm_wait_s)) + " s)" + air_text(f)};
  }
  return {true, std::nullopt};
}

// The crossing gate (crossing_refusal) judged on the last pose from a nearly whole picture; if
// it is clear, the crossing (or, with no room behind the shelf to stop, the landing), else the
// refusal.
GateVerdict CrossingGate::judge(MissionFacts& facts, const TargetTracker& tracker, const VelocityCommand& sticks,
                                const std::string& why_now) {
  const ControlGains& g = config_.control;
  CrossingGateInput gate;
  const PoseEstimate pose = gate_pose(facts, tracker, gate);
  gate.yaw_rate_cmd_radps = sticks.yaw_rate_radps;
  gate.identity = tracker.identification().identity();
  const std::optional<double> cell_centre_h_m = cell_height_.measured_m();
  if (cell_centre_h_m && facts.state_fresh()) {
    gate.height_above_cell_m = facts.state->height_m - *cell_centre_h_m;
    gate.cell_centre_h_m = cell_centre_h_m;
    gate.vz_mps = facts.state->vz_H_mps;
  }
  if (rough_seen_ns_) gate.calm_for_s = ns_to_seconds(facts.now_ns - *rough_seen_ns_);
  const std::optional<std::string> refusal = crossing_refusal(config_, *tracker.target(), pose, gate);
  if (refusal) return {refusal, std::nullopt, std::nullopt};
  // Past the back face by beyond_distance_m, or less where a shelf stands behind
  // (guidance.hpp, crossing_beyond_m).
  const std::optional<double>& behind_m = tracker.record().behind_m;
  const double beyond_m = crossing_beyond_m(config_, behind_m);
  if (beyond_m < config_.mission.crossing.min_beyond_distance_m) {
    return {std::nullopt, "no room behind the shelf to stop after crossing (tags " + format_m(*behind_m) + " m behind)",
            std::nullopt};
  }
  // Along the line from the pose through the cell centre at mid-depth, heading held, on the
  // heading the vehicle settles on once the yaw stick is released; ended by the distance the
  // state odometry has flown (guidance.hpp, plan_crossing).
  const double yaw_O = facts.state ? facts.state->yaw_rad : 0.0;
  const double speed_gain = forward_gain_.speed_gain();
  CrossingPlan plan = plan_crossing(config_, pose, sticks.yaw_rate_radps, beyond_m, speed_gain,
                                    facts.odometry.p_O_m().head<2>(), yaw_O);
  trim_crossing(plan, g, gate.line_hold.drift_trim_y_mps);
  CrossingStart start;
  start.end = plan.end;
  start.watch = plan_crossing_watch(config_, line_room(config_, *tracker.target(), pose), pose.p_FB_m(),
                                    crossing_direction_K(config_.shelf, pose));
  start.event = why_now + ": crossing " + cell_text(*tracker.target()) + " (" + format_m(beyond_m) +
                " m past the back face; speed gain " + format_m(speed_gain) + "; " +
                format_m(*gate.height_above_cell_m) + " m above the cell centre by the state height; " +
                "line-hold forecast " + format_m(gate.line_hold.y_m) + " m across, " + format_m(gate.line_hold.z_m) +
                " m up" + air_text(gate.line_hold) +
                (plan.trim_B_mps.y() != 0.0 ? "; a drift of " + format_m(-plan.trim_B_mps.y()) + " m/s across flown out" : "") +
                (behind_m ? "; tags " + format_m(*behind_m) + " m behind)" : ")");
  // Horizontally along the line; vertically the cell centre's height held by the state
  // height (CellCrossing), not the line's slope: that slope came from a pose a video latency
  // old, and open loop it flew a vehicle still settling vertically into the beam below.
  start.height_m = *cell_centre_h_m;
  start.velocity = crossing_velocity(g, plan, crossing_vz_mps(g, *cell_centre_h_m, facts.state->height_m));
  return {std::nullopt, std::nullopt, start};
}

}  // namespace shelfcross::flight_sw
