// The approach (flight_software.hpp): the target chosen on the full view, followed, measured,
// re-acquired and its identity judged; the laws of eq. 10-15 and Fig. 19 on its pose; when to
// hold short, back off, re-read the shelf or cross (the crossing gate, target_tracker.hpp).
// The line-hold gate and the in-crossing watch are in mission_line_hold.cpp.

#include <algorithm>
#include <cmath>

#include "flight_sw/flight_software.hpp"
#include "flight_sw/guidance.hpp"
#include "flight_sw/mission_text.hpp"

namespace shelfcross::flight_sw {

bool FlightSoftware::select_target(const cv::Mat& bgr) {
  const cv::Point2d centre(config_.camera.cx_px, config_.camera.cy_px);
  // With a shelf after this one: the cell nearest the next shelf's optimal viewpoint. The
  // shelves are parallel and aligned, so that viewpoint is this one moved shelf_spacing_m along
  // x_G; the crossing flies along x_G, so only the (y, z) distance in G counts.
  const Eigen::Vector3d next_viewpoint_G =
      survey_.viewpoint_G_m() + Eigen::Vector3d(config_.layout.shelf_spacing_m, 0.0, 0.0);
  std::optional<CellIndex> best;
  double best_d = 0.0;
  for (const CellIndex& cell : survey_.inventory().empty_cells()) {
    // Only cells the vehicle fits through, centred and level.
    const Eigen::Vector2d opening = cell_opening_m(config_.shelf, cell);
    const Eigen::Vector3d& size = config_.mission.vehicle_size_m;
    if (opening.x() - size.y() - 2.0 * config_.mission.crossing_margin_m <= 0.0 ||
        opening.y() - size.z() - 2.0 * config_.mission.crossing_margin_m <= 0.0) {
      continue;
    }
    double d = 0.0;
    if (last_shelf()) {  // the last (or only) shelf: nearest the image centre
      const auto q = cell_quad(survey_.view(), cell);
      const cv::Point2d c = 0.25 * (q[0] + q[1] + q[2] + q[3]);
      d = cv::norm(c - centre);
    } else {
      const Eigen::Vector3d c_G = cell_centre_G(config_.shelf, cell);
      d = std::hypot(c_G.y() - next_viewpoint_G.y(), c_G.z() - next_viewpoint_G.z());
    }
    if (!best || d < best_d) {
      best = cell;
      best_d = d;
    }
  }
  if (!best) return false;
  // The target's height, from the full view it was chosen on (the grid pose, G parallel to K).
  std::optional<double> height_m;
  if (const std::optional<PoseEstimate>& pose_G = survey_.pose_G()) {
    height_m = cell_height_m(state_, pose_G->p_FB_m().z() - cell_centre_G(config_.shelf, *best).z());
  }
  // Chosen on a full view, where every cell's grid position is counted from the edges.
  tracker_.choose(*best, survey_.view(), bgr, now_ns_, height_m);
  telemetry_.tracking.target = best;
  telemetry_.tracking.tracked_box_px = tracker_.corners().box_px();
  cell_height_.clear();
  line_hold_.clear();
  forward_gain_.restart();
  telemetry_.tracking.target_identity = tracker_.identification().identity();
  return true;
}

// A sample of the target cell centre's height in the state height's frame (odometry.hpp,
// CellHeightEstimator), from a deciding pose (TargetTracker::pose_decides): with a fresh
// state, inside commit_range_m, and once the state has shown the vehicle vertically still for
// vertical_lag_s.
void FlightSoftware::sample_cell_height(const PoseEstimate& pose) {
  if (!state_fresh() || -pose.p_FB_m().x() > config_.control.commit_range_m) return;
  if (!cell_height_.vertically_still_for(now_ns_, config_.mission.vertical_lag_s)) return;
  cell_height_.sample(state_->height_m, pose.p_FB_m().z());
}

// The target's loss begins (once): the grid is not known to be in view until a nearly whole
// picture shows it.
void FlightSoftware::start_losing_target() {
  if (lost_since_ns_) return;
  lost_since_ns_ = now_ns_;
  grid_in_view_while_lost_ = false;
}

// The target lost: the shelf's view analysed anew, the target looked for near its last box
// (target_tracker.hpp, TargetTracker::reacquire).
bool FlightSoftware::reacquire(const Picture& pic) {
  survey_.analyse(pic.bgr, telemetry_);
  if (!tracker_.reacquire(pic, survey_.view(), survey_.tag_detector(), state_)) return false;
  after_measurement();
  telemetry_.tracking.tracked_box_px = tracker_.corners().box_px();
  return true;
}

// What a successful measurement of the target changed, for the telemetry.
void FlightSoftware::after_measurement() {
  if (tracker_.identification().continuity_lost()) telemetry_.event = "target continuity lost: identity to be confirmed";
  telemetry_.tracking.target_identity = tracker_.identification().identity();
}

// The target's identity judged on this picture (target_tracker.hpp): a contradiction, or no
// confirmation within identity_confirm_s, re-reads the shelf (false: the approach is over).
bool FlightSoftware::check_identity(const Picture& pic, const PoseEstimate& pose) {
  const IdentityCheck check = tracker_.check_identity(pic, pose, survey_.tag_detector(), survey_.marker_detector(), survey_.inventory());
  if (check.verdict == CellIdentity::Confirmed) {
    telemetry_.tracking.target_identity = tracker_.identification().identity();
    telemetry_.event = "target identity confirmed: " + check.why;
    return true;
  }
  if (check.verdict == CellIdentity::Contradicted) {
    ++telemetry_.tracking.identity_contradictions;
    reread_shelf("target identity contradicted (" + check.why + ")");
    return false;
  }
  const std::optional<TimeNs>& since = tracker_.identification().unidentified_since_ns();
  if (since && ns_to_seconds(now_ns_ - *since) > config_.mission.identity_confirm_s) {
    reread_shelf("target not identified within identity_confirm_s");
    return false;
  }
  return true;
}

// The forward speed gain (odometry.hpp, ForwardGainEstimator), on deciding poses.
void FlightSoftware::estimate_forward_gain(const PoseEstimate& pose) {
  forward_gain_.on_pose(now_ns_, pose.p_FB_m().x());
  telemetry_.control.forward_gain = forward_gain_.gain();
}

void FlightSoftware::reread_shelf(const std::string& why, const std::optional<std::string>& give_up_reason) {
  ++telemetry_.tracking.shelf_rereads;
  if (++rereads_ > config_.mission.identity_rereads) {
    const std::string reason = give_up_reason.value_or("target cell not identified: " + why);
    // Close to the shelf: back out and land clear of it; elsewhere land where it hovers.
    if (phase_ == Phase::Approach) return back_out_and_land(reason);
    land(Outcome::Aborted, reason);
    return;
  }
  // Closer than the viewpoint, the shelf may not fit the view or show a single tag (an
  // approach that gave up 0.6 m out sees the inside of a cell), and FindShelf would only turn
  // on the spot looking for it (run 242 of the default sdk campaign, commit bfd468c: 30 s of
  // turning, "shelf not found"). So, seeing nothing, it first backs straight out the way the
  // approach came, to the viewpoint's range (the last pose's range: distance / back-off speed).
  reread_back_until_ns_.reset();
  if (const std::optional<PoseEstimate>& pose_K = tracker_.poses().pose_K()) {
    const double back_m = std::max(0.0, -survey_.viewpoint_G_m().x() + pose_K->p_FB_m().x());
    reread_back_until_ns_ = now_ns_ + seconds_to_ns(back_m / config_.control.back_off_speed_mps);
  }
  tracker_.forget();
  crossing_refusals_ = 0;  // off-centre arrivals count per approach
  telemetry_.tracking.target.reset();
  cell_height_.clear();
  line_hold_.clear();
  telemetry_.tracking.target_identity = tracker_.identification().identity();
  hold_since_ns_.reset();
  sticks_.hover();
  // FindShelf backs away from a fragment until the whole grid is in view, GoToViewpoint flies
  // to the optimal viewpoint, and TakeInventory (its frames already read) chooses the target
  // anew on a full view.
  enter(Phase::FindShelf, why + ": re-reading the shelf from the viewpoint");
}

// The crossing gate (crossing_refusal) judged on the last pose from a nearly whole picture;
// if it is clear, the crossing begins (or, with no room behind the shelf to stop, the vehicle
// lands) and nothing is returned, else the refusal. `why_now` begins the crossing's event.
std::optional<std::string> FlightSoftware::cross_if_clear(const std::string& why_now) {
  const ControlGains& g = config_.control;
  CrossingGateInput gate;
  const PoseEstimate pose = crossing_gate_pose(gate);
  gate.identity = tracker_.identification().identity();
  const std::optional<double> cell_centre_h_m = cell_height_.measured_m();
  if (cell_centre_h_m && state_fresh()) {
    gate.height_above_cell_m = state_->height_m - *cell_centre_h_m;
    gate.vz_mps = state_->vz_H_mps;
  }
  const std::optional<std::string> refusal = crossing_refusal(config_, *tracker_.target(), pose, gate);
  if (refusal) return refusal;
  // Past the back face by beyond_distance_m, or less where a shelf stands behind
  // (guidance.hpp, crossing_beyond_m).
  const std::optional<double>& behind_m = tracker_.record().behind_m;
  const double beyond_m = crossing_beyond_m(config_, behind_m);
  if (beyond_m < config_.mission.min_beyond_distance_m) {
    land(Outcome::Aborted, "no room behind the shelf to stop after crossing (tags " + format_m(*behind_m) + " m behind)");
    return std::nullopt;
  }
  // Along the line from the pose through the cell centre at mid-depth, heading held, ended
  // by the distance the state odometry has flown (guidance.hpp, plan_crossing).
  const double yaw_O = state_ ? state_->yaw_rad : 0.0;
  const CrossingPlan plan =
      plan_crossing(config_, pose, beyond_m, forward_gain_.gain(), odometry_.p_O_m().head<2>(), yaw_O);
  crossing_end_ = plan.end;
  watch_ = plan_crossing_watch(config_, line_room(config_, *tracker_.target(), pose), pose.p_FB_m(),
                               crossing_direction_K(config_.shelf, pose));
  enter(Phase::Cross, why_now + ": crossing " + cell_text(*tracker_.target()) + " (" + format_m(beyond_m) +
                          " m past the back face; speed gain " + format_m(forward_gain_.gain()) + "; " +
                          format_m(*gate.height_above_cell_m) + " m above the cell centre by the state height; " +
                          "line-hold forecast " + format_m(gate.line_hold.y_m) + " m across, " +
                          format_m(gate.line_hold.z_m) + " m up" +
                          (behind_m ? "; tags " + format_m(*behind_m) + " m behind)" : ")"));
  // Horizontally along the line; vertically the cell centre's height held by the state
  // height (on_state), not the line's slope: that slope came from a pose a video latency
  // old, and open loop it flew a vehicle still settling vertically into the beam below.
  crossing_height_m_ = cell_centre_h_m;
  sticks_.set(crossing_velocity(g, plan, crossing_vz_mps(g, *cell_centre_h_m, state_->height_m)), now_ns_);
  return std::nullopt;
}

// The approach's vertical, heading and lateral laws (eq. 12, eq. 15, Fig. 19) on errors `e`,
// the PI states stepped by dt; a lateral command restarts the stillness the crossing waits for.
VelocityCommand FlightSoftware::approach_steering(const ApproachErrors& e, double dt) {
  VelocityCommand v = sticks_.steer(e.e_z_m, e.e_psi_rad, dt);  // eq. 12, eq. 15
  v.vy_B_mps = approach_lateral_mps(config_.control, e);  // Fig. 19
  if (v.vy_B_mps != 0.0) lateral_active_ns_ = now_ns_;
  return v;
}

void FlightSoftware::approach(const Picture& pic) {
  const ControlGains& g = config_.control;
  if (retreat_until_ns_) return sticks_.set(back_off_velocity(g), now_ns_);  // declined: backing out (supervise)
  forward_gain_.on_command_held(now_ns_, sticks_.velocity().vx_B_mps);
  std::optional<OdometryFix> odometry;
  if (state_fresh()) odometry = OdometryFix{odometry_.p_O_m(), state_->yaw_rad};
  const TargetTracker::Prediction predicted = tracker_.predict(pic, odometry);
  telemetry_.tracking.tracker_ok = predicted.tracker_ok;
  const bool found = tracker_.measure(pic, predicted.box_px, survey_.tag_detector(), state_);
  if (found) after_measurement();
  feed_line_hold(found, odometry);
  telemetry_.tracking.tracked_box_px = tracker_.corners().box_px();
  const double dt = sticks_.control_dt_s(now_ns_);
  if (found) return approach_found(pic, predicted, dt);
  if (tracker_.record().hidden_by_damage && !back_off_since_ns_) return approach_unseen(dt);
  approach_without_target(pic);
}

// Eq. 10's forward speed toward the viewpoint from `range_m` out (none while held short).
double FlightSoftware::approach_forward_speed_mps(bool hold, double range_m) const {
  return approach_forward_mps(config_.control, hold, tracker_.identification().identity() == CellIdentity::Confirmed, range_m,
                              -survey_.viewpoint_G_m().x());
}

// The corner tags measured on this picture: steer on their pose, hold short until settled and
// calm, and judge the crossing on the last nearly whole picture before the tags leave.
void FlightSoftware::approach_found(const Picture& pic, const TargetTracker::Prediction& predicted, double dt) {
  lost_since_ns_.reset();
  back_off_since_ns_.reset();
  tracker_.correct(pic, predicted);
  const PoseEstimate& pose = *tracker_.poses().pose_K();
  telemetry_.pose = pose;
  telemetry_.pose_in_cell_frame = true;
  // Unidentified (continuity lost): judge this picture; a contradiction ends the approach.
  // Whole pictures only: a guessed band can put a tag beyond the grid's edge or hide one.
  if (tracker_.identification().identity() != CellIdentity::Confirmed && pic.whole() && !check_identity(pic, pose)) return;
  // Decisions rest only on poses from deciding pictures whose corner tags are clear of the
  // damage (TargetTracker::pose_decides); the others steer. The line-hold monitor measures
  // on the former, carried by the odometry between them (feed_line_hold, line_hold.hpp).
  const bool decides = tracker_.poses().pose_decides();
  // The laws of eq. 10-15 and Fig. 19 (guidance.hpp); the PI states and the timers here.
  const ApproachErrors e = approach_errors(config_.camera, tracker_.corners().box_centre_px(), pose);
  VelocityCommand v = approach_steering(e, dt);
  // Held short inside commit_range_m until settled; settling is given up after
  // settle_hold_s (the crossing gate then decides).
  // Also held short while the air leaves the line no room (too_rough_to_cross: declined
  // after calm_wait_s).
  const ApproachHold h = approach_hold(config_, e, ns_to_seconds(now_ns_ - lateral_active_ns_), -pose.p_FB_m().x());
  const bool rough = too_rough_to_cross(pose);
  if (retreat_until_ns_) return;  // declined just now
  const bool settling = h.settling || rough;
  if (!settling) hold_since_ns_.reset();
  if (settling && !hold_since_ns_) hold_since_ns_ = now_ns_;
  const bool settle_given_up =
      hold_since_ns_ && ns_to_seconds(now_ns_ - *hold_since_ns_) > config_.mission.settle_hold_s;
  const bool hold = !h.in_cone || (settling && !settle_given_up);
  v.vx_B_mps = approach_forward_speed_mps(hold, -pose.p_FB_m().x());  // eq. 10
  // About to lose the tags: the crossing will be judged on the last nearly whole picture,
  // so only such pictures move the vehicle now (it hovers on damaged ones), and the last
  // one before the tags leave is at most a frame old.
  if (tracker_.corners().near_edge() && !decides) v = {};
  // Near the border on a nearly whole picture: its pose is the freshest the approach will
  // get, and the crossing is judged on it now rather than when the tags have left the view
  // on a later nearly whole picture, which over a lossy link may come a second after the
  // last one, its pose then too old to cross on (pose_fresh_s). A refusal here only lets
  // the approach go on.
  if (tracker_.corners().near_edge() && decides && -pose.p_FB_m().x() <= config_.mission.cross_range_max_m &&
      !cross_if_clear("corner tags leaving the view")) {
    return;
  }
  sticks_.set(v, now_ns_);
  if (decides) {
    estimate_forward_gain(pose);
    sample_cell_height(pose);
  }
  telemetry_.control.e_z_m = e.e_z_m;
  telemetry_.control.e_psi_rad = e.e_psi_rad;
  telemetry_.control.psi_cell_rad = e.psi_cell_rad;
  telemetry_.control.yaw_cell_rad = pose.yaw_rad;
  telemetry_.control.lateral_mps = v.vy_B_mps;
  telemetry_.control.settled = h.settled;
  telemetry_.control.holding_short = hold;
}

// A picture whose guessed rows hide the corner tags (or show them where they no longer are):
// the target is not lost, only unseen until a picture shows it clear of the damage, which the
// next key frame brings; the approach's own time limit bounds the wait. Farther out than
// commit_range_m, for at most coast_s after the last pose, the loops steer on that pose
// carried by the state odometry (its drift, 5 cm/s, is far inside what the approach corrects
// later); closer, where the crossing's last centimetres are judged, the vehicle holds.
void FlightSoftware::approach_unseen(double dt) {
  const std::optional<TargetTracker::Carried> carried = tracker_.carried_target(now_ns_);
  if (!carried || -carried->pose_K.p_FB_m().x() <= config_.control.commit_range_m) return hold_or_hover();
  const PoseEstimate& pose = carried->pose_K;
  const cv::Rect2d& b = carried->box_px;
  const ApproachErrors e = approach_errors(config_.camera, {b.x + 0.5 * b.width, b.y + 0.5 * b.height}, pose);
  VelocityCommand v = approach_steering(e, dt);
  const ApproachHold h = approach_hold(config_, e, ns_to_seconds(now_ns_ - lateral_active_ns_), -pose.p_FB_m().x());
  v.vx_B_mps = approach_forward_speed_mps(!h.in_cone, -pose.p_FB_m().x());  // eq. 10
  sticks_.set(v, now_ns_);
}

// The corner tags neither measured nor hidden: cross if they just left the view close and
// centred, back off while not centred, else hover and look for the target again.
void FlightSoftware::approach_without_target(const Picture& pic) {
  const ControlGains& g = config_.control;
  if (!pic.decides && !back_off_since_ns_) {
    // Not found in a damaged picture: the tags may sit in a guessed band. Nothing is decided
    // (no crossing, no re-acquisition) until a nearly whole picture shows where they are.
    start_losing_target();
    hold_or_hover();
    return;
  }
  // The corner tags are gone. Close and at the border: they left the view; cross if centred,
  // judged on the last pose from a nearly whole picture.
  const std::optional<PoseEstimate>& decision_pose_K = tracker_.poses().decision_pose_K();
  if (decision_pose_K && tracker_.corners().near_edge() && -decision_pose_K->p_FB_m().x() <= config_.mission.cross_range_max_m) {
    const std::optional<std::string> refusal = cross_if_clear("corner tags left the view");
    if (!refusal) return;
    const std::string& why = *refusal;
    if (!back_off_since_ns_) {
      if (++crossing_refusals_ >= config_.mission.crossing_attempts) {
        // The air, not the view, keeps the line from being held: a re-read would not help.
        if (why.rfind(kLineHoldNotMeasured, 0) == 0 || why.rfind(kLineCannotBeHeld, 0) == 0) {
          return back_out_and_land(kCrossingDeclined + why);
        }
        reread_shelf(kCouldNotCentre, kCouldNotCentre);
        return;
      }
      back_off_since_ns_ = now_ns_;
      telemetry_.event = "not centred (" + why + "): backing off";
    }
    sticks_.set(back_off_velocity(g), now_ns_);
    sticks_.restart_loops();
    return;
  }
  if (back_off_since_ns_) {  // keep backing off until the tags are back
    sticks_.set(back_off_velocity(g), now_ns_);
    return;
  }
  // Lost: hover, and look for the target among the tags of the whole frame.
  if (!lost_since_ns_) telemetry_.event = "target lost: hovering to re-acquire";
  start_losing_target();
  sticks_.hover();
  if (reacquire(pic)) {
    lost_since_ns_.reset();
    telemetry_.event = "target re-acquired";
  } else if (pic.decides) {
    grid_in_view_while_lost_ = survey_.view().grid.valid;
  }
}

}  // namespace shelfcross::flight_sw
