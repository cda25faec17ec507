// The approach of the target cell (target_approach.hpp): the target chosen on the full view,
// followed, measured, re-acquired and its identity judged; the laws of eq. 10-15 and Fig. 19 on
// its pose; when to hold short, back off, re-read the shelf, give up or cross (the gate,
// crossing_gate.hpp).

#include "flight_sw/mission/target_approach.hpp"

#include <algorithm>
#include <cmath>

#include "flight_sw/guidance/guidance.hpp"
#include "flight_sw/text.hpp"

namespace shelfcross::flight_sw {

namespace {

// A step that flies `v` and goes on.
ApproachStep flying(const VelocityCommand& v) {
  ApproachStep s;
  s.velocity = v;
  return s;
}

// A step that lands here, aborted, with `reason`.
ApproachStep landing(const std::string& reason) {
  ApproachStep s;
  s.next = ApproachStep::Next::Land;
  s.event = reason;
  return s;
}

// The step after a gate that did not refuse: the crossing, or the landing with no room behind.
ApproachStep crossing_step(GateVerdict&& verdict) {
  if (!verdict.start) return landing(*verdict.no_room);
  ApproachStep s;
  s.next = ApproachStep::Next::Cross;
  s.crossing = std::move(verdict.start);
  return s;
}

// What a successful measurement of the target changed, for the telemetry.
void note_measurement(const TargetTracker& tracker, Telemetry& telemetry) {
  if (tracker.identification().continuity_lost()) telemetry.event = "target continuity lost: identity to be confirmed";
  telemetry.tracking.target_identity = tracker.identification().identity();
}

// The target lost: the shelf's view analysed anew, the target looked for near its last box
// (target_tracker.hpp, TargetTracker::reacquire).
bool reacquire(const Picture& pic, TargetTracker& tracker, const RecentStates& states, ApproachTools tools) {
  tools.survey.analyse(pic.bgr, tools.facts.telemetry);
  if (!tracker.reacquire(pic, tools.survey.view(), tools.survey.tag_detector(), states)) return false;
  note_measurement(tracker, tools.facts.telemetry);
  tools.facts.telemetry.tracking.tracked_box_px = tracker.corners().box_px();
  return true;
}

// The approach's vertical, heading and lateral laws (eq. 12, eq. 15, Fig. 19) on errors `e`,
// the PI states stepped by dt; a lateral command restarts the stillness the crossing waits for.
VelocityCommand steer_on(const ApproachErrors& e, double dt, const ControlGains& g, ApproachTools tools,
                         CrossingGate& gate) {
  VelocityCommand v = tools.sticks.steer(e.e_z_m, e.e_psi_rad, dt);  // eq. 12, eq. 15
  v.vy_B_mps = approach_lateral_mps(g, e);  // Fig. 19
  if (v.vy_B_mps != 0.0) gate.moved_sideways(tools.facts.now_ns);
  return v;
}

// Eq. 10's forward speed toward the viewpoint from `range_m` out (none while held short).
double forward_speed_mps(const FlightConfig& config, const TargetTracker& tracker, const ShelfSurvey& survey, bool hold,
                         double range_m) {
  return approach_forward_mps(config.control, hold, tracker.identification().identity() == CellIdentity::Confirmed,
                              range_m, -survey.viewpoint_G_m().x());
}

}  // namespace

bool TargetApproach::choose_target(const cv::Mat& bgr, ApproachTools tools, bool last_shelf) {
  const ShelfSurvey& survey = tools.survey;
  const cv::Point2d centre(config_.camera.cx_px, config_.camera.cy_px);
  // With a shelf after this one: the cell nearest the next shelf's optimal viewpoint. The
  // shelves are parallel and aligned, so that viewpoint is this one moved shelf_spacing_m along
  // x_G; the crossing flies along x_G, so only the (y, z) distance in G counts.
  const Eigen::Vector3d next_viewpoint_G =
      survey.viewpoint_G_m() + Eigen::Vector3d(config_.layout.shelf_spacing_m, 0.0, 0.0);
  std::optional<CellIndex> best;
  double best_d = 0.0;
  for (const CellIndex& cell : survey.inventory().empty_cells()) {
    // Only cells the vehicle fits through, centred and level.
    const Eigen::Vector2d opening = cell_opening_m(config_.shelf, cell);
    const Eigen::Vector3d& size = config_.mission.vehicle_size_m;
    if (opening.x() - size.y() - 2.0 * config_.mission.crossing_margin_m <= 0.0 ||
        opening.y() - size.z() - 2.0 * config_.mission.crossing_margin_m <= 0.0) {
      continue;
    }
    double d = 0.0;
    if (last_shelf) {  // the last (or only) shelf: nearest the image centre
      const auto q = cell_quad(survey.view(), cell);
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
  Telemetry& telemetry = tools.facts.telemetry;
  // The target's height, from the full view it was chosen on (the grid pose, G parallel to K).
  std::optional<double> height_m;
  if (const std::optional<PoseEstimate>& pose_G = survey.pose_G()) {
    height_m = cell_height_m(tools.facts.state, pose_G->p_FB_m().z() - cell_centre_G(config_.shelf, *best).z());
  }
  // Chosen on a full view, where every cell's grid position is counted from the edges.
  tracker_.choose(*best, survey.view(), bgr, tools.facts.now_ns, height_m);
  telemetry.tracking.target = best;
  telemetry.tracking.tracked_box_px = tracker_.corners().box_px();
  gate_.new_target();
  telemetry.tracking.target_identity = tracker_.identification().identity();
  gate_.moved_sideways(tools.facts.now_ns);  // not yet seen still
  timers_.hold_since_ns.reset();
  return true;
}

// The target's identity judged on this picture (target_tracker.hpp): a contradiction, or no
// confirmation within identity_confirm_s, re-reads the shelf (the approach is over).
std::optional<ApproachStep> TargetApproach::check_identity(const Picture& pic, const PoseEstimate& pose,
                                                           ApproachTools tools) {
  ShelfSurvey& survey = tools.survey;
  Telemetry& telemetry = tools.facts.telemetry;
  const IdentityCheck check =
      tracker_.check_identity(pic, pose, survey.tag_detector(), survey.marker_detector(), survey.inventory());
  if (check.verdict == CellIdentity::Confirmed) {
    telemetry.tracking.target_identity = tracker_.identification().identity();
    telemetry.event = "target identity confirmed: " + check.why;
    return std::nullopt;
  }
  if (check.verdict == CellIdentity::Contradicted) {
    ++telemetry.tracking.identity_contradictions;
    return reread("target identity contradicted (" + check.why + ")", std::nullopt, tools.facts, survey);
  }
  const std::optional<TimeNs>& since = tracker_.identification().unidentified_since_ns();
  if (since && ns_to_seconds(tools.facts.now_ns - *since) > config_.mission.target.identity_confirm_s) {
    return reread("target not identified within identity_confirm_s", std::nullopt, tools.facts, survey);
  }
  return std::nullopt;
}

ApproachStep TargetApproach::reread(const std::string& why, const std::optional<std::string>& give_up_reason,
                                    MissionFacts& facts, const ShelfSurvey& survey) {
  ++facts.telemetry.tracking.shelf_rereads;
  if (++rereads_ > config_.mission.target.identity_rereads) {
    // Every re-read starts in the approach, close to the shelf: back out and land clear of it.
    return give_up(give_up_reason.value_or("target cell not identified: " + why), 0.0, facts);
  }
  // Closer than the viewpoint, the shelf may not fit the view or show a single tag (an
  // approach that gave up 0.6 m out sees the inside of a cell), and FindShelf would only turn
  // on the spot looking for it, for 30 s until "shelf not found". So, seeing nothing, it first backs straight out the way the
  // approach came, to the viewpoint's range (the last pose's range: distance / back-off speed).
  reread_back_until_ns_.reset();
  if (const std::optional<PoseEstimate>& pose_K = tracker_.poses().pose_K()) {
    const double back_m = std::max(0.0, -survey.viewpoint_G_m().x() + pose_K->p_FB_m().x());
    reread_back_until_ns_ = facts.now_ns + seconds_to_ns(back_m / config_.control.back_off_speed_mps);
  }
  tracker_.forget();
  crossing_refusals_ = 0;  // off-centre arrivals count per approach
  facts.telemetry.tracking.target.reset();
  gate_.clear_cell_height();
  gate_.clear_line_hold();
  facts.telemetry.tracking.target_identity = tracker_.identification().identity();
  timers_.hold_since_ns.reset();
  // FindShelf backs away from a fragment until the whole grid is in view, GoToViewpoint flies
  // to the optimal viewpoint, and TakeInventory (its frames already read) chooses the target
  // anew on a full view.
  ApproachStep s;
  s.hover = true;
  s.next = ApproachStep::Next::Reread;
  s.event = why + ": re-reading the shelf from the viewpoint";
  return s;
}

ApproachStep TargetApproach::give_up(const std::string& reason, double flown_in_m, MissionFacts& facts) {
  // Back straight out (the heading is on the cell normal) to give_up_clearance_m in front of
  // the shelf by the last pose (and what was flown in since), then land there (supervise):
  // clear of the frame whatever a gust does during the descent.
  double back_m = config_.mission.line_hold.give_up_clearance_m + flown_in_m;
  if (const std::optional<PoseEstimate>& pose_K = tracker_.poses().pose_K()) back_m += pose_K->p_FB_m().x();
  retreat_.until_ns = facts.now_ns + seconds_to_ns(std::max(0.0, back_m) / config_.control.back_off_speed_mps);
  retreat_.reason = reason;
  facts.telemetry.event = retreat_.reason + ": backing out to land clear of the shelf";
  ApproachStep s = flying(back_off_velocity(config_.control));
  s.restart_loops = true;
  s.next = ApproachStep::Next::GiveUp;
  return s;
}

std::optional<ApproachStep> TargetApproach::supervise(MissionFacts& facts, const ShelfSurvey& survey,
                                                      double in_phase_s, bool out_of_time) {
  const Timeouts& to = config_.timeouts;
  if (retreat_.until_ns) {  // a declined crossing: back out, then land clear of the shelf
    if (facts.now_ns >= *retreat_.until_ns) return landing(retreat_.reason);
    return flying(back_off_velocity(config_.control));
  }
  // Too long short of the cell (a link too lossy to decide on, a target never settled on):
  // backed straight out to land clear of the shelf, not where it hovers.
  if (in_phase_s > to.approach_s) return give_up("approach timed out", 0.0, facts);
  if (out_of_time) return give_up(kMissionTimeSpent, 0.0, facts);
  const std::optional<TimeNs>& lost = timers_.lost_since_ns;
  if (lost && ns_to_seconds(facts.now_ns - *lost) > to.target_lost_s) {
    // The target not found again near where it was last seen (the view moved on while the
    // pictures were damaged, the pose checks refused every candidate, or the tags left a view
    // too close to hold them): choose it anew from the viewpoint. The re-read first backs
    // straight out the way the approach came, seeing nothing or not, and after
    // identity_rereads of them the mission gives up, backing out to land clear of the shelf.
    return reread("target lost", std::string("target lost"), facts, survey);
  }
  const std::optional<TimeNs>& back_off = timers_.back_off_since_ns;
  if (back_off && ns_to_seconds(facts.now_ns - *back_off) > to.back_off_s) {
    return reread(kCouldNotCentre, std::string(kCouldNotCentre), facts, survey);
  }
  return std::nullopt;
}

ApproachStep TargetApproach::crossing_stopped(const CrossingStop& stop, MissionFacts& facts) {
  gate_.clear_line_hold();
  gate_.moved_sideways(facts.now_ns);  // stillness to be shown anew
  if (++crossing_refusals_ >= config_.mission.crossing.crossing_attempts) {
    return give_up(std::string(kCrossingDeclined) + kLineCannotBeHeld + ": " + stop.why, stop.flown_in_m, facts);
  }
  timers_.back_off_since_ns = facts.now_ns;
  return {};
}

void TargetApproach::on_phase_change() {
  timers_.lost_since_ns.reset();
  timers_.back_off_since_ns.reset();
  gate_.forget_rough();
  retreat_.until_ns.reset();
}

void TargetApproach::next_shelf(Telemetry& telemetry) {
  tracker_.forget();
  gate_.clear_cell_height();
  crossing_refusals_ = 0;
  timers_.hold_since_ns.reset();
  telemetry.tracking.target.reset();
  telemetry.tracking.tracked_box_px.reset();
}

ApproachStep TargetApproach::step(const Picture& pic, ApproachTools tools) {
  MissionFacts& f = tools.facts;
  if (retreat_.until_ns) return flying(back_off_velocity(config_.control));  // declined: backing out (supervise)
  gate_.on_command_held(f.now_ns, tools.sticks.velocity().vx_B_mps, tools.sticks.response().scale(StickAxis::Horizontal));
  std::optional<OdometryFix> odometry;
  if (f.state_fresh()) odometry = OdometryFix{f.odometry.p_O_m(), f.state->yaw_rad};
  const TargetTracker::Prediction predicted = tracker_.predict(pic, odometry);
  f.telemetry.tracking.tracker_ok = predicted.tracker_ok;
  const bool measured = tracker_.measure(pic, predicted.box_px, tools.survey.tag_detector(), states_);
  if (measured) note_measurement(tracker_, f.telemetry);
  gate_.on_picture(f, tracker_, measured, odometry);
  f.telemetry.tracking.tracked_box_px = tracker_.corners().box_px();
  const double dt = tools.sticks.control_dt_s(f.now_ns);
  if (measured) return found(pic, predicted, dt, tools);
  if (tracker_.record().hidden && !timers_.back_off_since_ns) return unseen(dt, tools);
  return without_target(pic, tools);
}

// The corner tags measured on this picture: steer on their pose, hold short until settled and
// calm, and judge the crossing on the last nearly whole picture before the tags leave.
ApproachStep TargetApproach::found(const Picture& pic, const TargetTracker::Prediction& predicted, double dt,
                                   ApproachTools tools) {
  MissionFacts& f = tools.facts;
  timers_.lost_since_ns.reset();
  timers_.back_off_since_ns.reset();
  tracker_.correct(pic, predicted);
  const PoseEstimate& pose = *tracker_.poses().pose_K();
  f.telemetry.pose = pose;
  f.telemetry.pose_in_cell_frame = true;
  // Unidentified (continuity lost): judge this picture; a contradiction ends the approach.
  // Whole pictures only: a guessed band can put a tag beyond the grid's edge or hide one.
  if (tracker_.identification().identity() != CellIdentity::Confirmed && pic.whole()) {
    if (std::optional<ApproachStep> over = check_identity(pic, pose, tools)) return *over;
  }
  // Decisions rest only on poses from deciding pictures whose corner tags are clear of the
  // damage (TargetTracker::pose_decides); the others steer. The line-hold monitor measures
  // on the former, carried by the odometry between them (CrossingGate::on_picture).
  const bool decides = tracker_.poses().pose_decides();
  // The laws of eq. 10-15 and Fig. 19 (guidance.hpp); the PI states and the timers here.
  const ApproachErrors e = approach_errors(config_.camera, tracker_.corners().box_centre_px(), pose);
  VelocityCommand v = steer_on(e, dt, config_.control, tools, gate_);
  // Held short inside commit_range_m until settled; settling is given up after
  // settle_hold_s (the crossing gate then decides).
  // Also held short while the air leaves the line no room (CrossingGate::too_rough: declined
  // after calm_wait_s).
  const ApproachHold h = approach_hold(config_, e, gate_.still_s(f.now_ns), -pose.p_FB_m().x());
  const RoughAir rough = gate_.too_rough(f, tracker_, pose);
  if (rough.declined) return give_up(*rough.declined, 0.0, f);
  const bool settling = h.settling || rough.hold_short;
  std::optional<TimeNs>& hold_since = timers_.hold_since_ns;
  if (!settling) hold_since.reset();
  if (settling && !hold_since) hold_since = f.now_ns;
  const bool settle_given_up = hold_since && ns_to_seconds(f.now_ns - *hold_since) > config_.mission.approach.settle_hold_s;
  const bool hold = !h.in_cone || (settling && !settle_given_up);
  v.vx_B_mps = forward_speed_mps(config_, tracker_, tools.survey, hold, -pose.p_FB_m().x());  // eq. 10
  // About to lose the tags: the crossing will be judged on the last nearly whole picture,
  // so only such pictures move the vehicle now (it hovers on damaged ones), and the last
  // one before the tags leave is at most a frame old.
  if (tracker_.corners().near_edge() && !decides) v = {};
  // Near the border on a nearly whole picture: its pose is the freshest the approach will
  // get, and the crossing is judged on it now rather than when the tags have left the view
  // on a later nearly whole picture, which over a lossy link may come a second after the
  // last one, its pose then too old to cross on (pose_fresh_s). A refusal here only lets
  // the approach go on.
  if (tracker_.corners().near_edge() && decides && -pose.p_FB_m().x() <= config_.mission.approach.cross_range_max_m) {
    GateVerdict verdict = gate_.judge(f, tracker_, tools.sticks.velocity(), "corner tags leaving the view");
    if (!verdict.refusal) return crossing_step(std::move(verdict));
  }
  const ApproachStep s = flying(v);
  if (decides) gate_.on_deciding_pose(f, pose);
  ControlTelemetry& c = f.telemetry.control;
  c.e_z_m = e.e_z_m;
  c.e_psi_rad = e.e_psi_rad;
  c.psi_cell_rad = e.psi_cell_rad;
  c.yaw_cell_rad = pose.yaw_rad;
  c.lateral_mps = v.vy_B_mps;
  c.settled = h.settled;
  c.holding_short = hold;
  return s;
}

// A picture whose guessed rows hide the corner tags (or show them where they no longer are),
// or whose pose's level the state records of the video latency cannot tell (the vehicle
// tipping or climbing as it starts: target_pose.hpp, PoseVerdict::LevelUnsure): the target
// is not lost, only unseen until a picture shows it clear of the damage (the next key frame)
// or under a steadier attitude; the approach's own time limit bounds the wait. Farther out than
// commit_range_m, for at most coast_s after the last pose, the loops steer on that pose
// carried by the state odometry (its drift, 5 cm/s, is far inside what the approach corrects
// later); closer, where the crossing's last centimetres are judged, the vehicle holds.
ApproachStep TargetApproach::unseen(double dt, ApproachTools tools) {
  const std::optional<TargetTracker::Carried> carried = tracker_.carried_target(tools.facts.now_ns);
  if (!carried || -carried->pose_K.p_FB_m().x() <= config_.control.commit_range_m) {
    ApproachStep s;
    s.hold_or_hover = true;
    return s;
  }
  const PoseEstimate& pose = carried->pose_K;
  const cv::Rect2d& b = carried->box_px;
  const ApproachErrors e = approach_errors(config_.camera, {b.x + 0.5 * b.width, b.y + 0.5 * b.height}, pose);
  VelocityCommand v = steer_on(e, dt, config_.control, tools, gate_);
  const ApproachHold h =
      approach_hold(config_, e, gate_.still_s(tools.facts.now_ns), -pose.p_FB_m().x());
  v.vx_B_mps = forward_speed_mps(config_, tracker_, tools.survey, !h.in_cone, -pose.p_FB_m().x());  // eq. 10
  return flying(v);
}

// The corner tags neither measured nor hidden: cross if they just left the view close and
// centred, back off while not centred, else hover and look for the target again.
ApproachStep TargetApproach::without_target(const Picture& pic, ApproachTools tools) {
  MissionFacts& f = tools.facts;
  const ControlGains& g = config_.control;
  if (!pic.decides && !timers_.back_off_since_ns) {
    // Not found in a damaged picture: the tags may sit in a guessed band. Nothing is decided
    // (no crossing, no re-acquisition) until a nearly whole picture shows where they are.
    timers_.start_losing(f.now_ns);
    ApproachStep s;
    s.hold_or_hover = true;
    return s;
  }
  // The corner tags are gone. Close and at the border: they left the view; cross if centred,
  // judged on the last pose from a nearly whole picture. Not once a back-off is under way: it
  // was started by a refusal (or a stopped crossing), and a later verdict on that same pose,
  // older now and with the vehicle backing since, may pass only because what it lacked (a
  // quiet state record, a still heading) arrived meanwhile; it committed a crossing 0.11 s
  // into a back-off, 9 cm low, into 0.9 m/s gusts, and the crossing touched a post. The
  // back-off runs until the tags are measured again (found), and the gate judges anew there.
  const std::optional<PoseEstimate>& decision_pose_K = tracker_.poses().decision_pose_K();
  if (decision_pose_K && tracker_.corners().near_edge() &&
      -decision_pose_K->p_FB_m().x() <= config_.mission.approach.cross_range_max_m) {
    GateVerdict verdict = gate_.judge(f, tracker_, tools.sticks.velocity(), "corner tags left the view");
    if (!timers_.back_off_since_ns) {
      if (!verdict.refusal) return crossing_step(std::move(verdict));
      const std::string& why = *verdict.refusal;
      if (++crossing_refusals_ >= config_.mission.crossing.crossing_attempts) {
        // The air, not the view, keeps the line from being held: a re-read would not help.
        // A line hold not measured (too few quiet poses from deciding pictures before the tags
        // left the view, as after a back-off) says nothing of the air: re-read, as for the
        // other refusals; the gate still refuses any crossing it cannot measure.
        if (why.rfind(kLineCannotBeHeld, 0) == 0) {
          return give_up(kCrossingDeclined + why, 0.0, f);
        }
        return reread(kCouldNotCentre, std::string(kCouldNotCentre), f, tools.survey);
      }
      timers_.back_off_since_ns = f.now_ns;
      f.telemetry.event = "not centred (" + why + "): backing off";
    }
    ApproachStep s = flying(back_off_velocity(g));
    s.restart_loops = true;
    return s;
  }
  if (timers_.back_off_since_ns) return flying(back_off_velocity(g));  // keep backing off until the tags are back
  // Lost: hover, and look for the target among the tags of the whole frame.
  if (!timers_.lost_since_ns) f.telemetry.event = "target lost: hovering to re-acquire";
  timers_.start_losing(f.now_ns);
  ApproachStep s;
  s.hover = true;
  if (reacquire(pic, tracker_, states_, tools)) {
    timers_.lost_since_ns.reset();
    f.telemetry.event = "target re-acquired";
  }
  return s;
}

}  // namespace shelfcross::flight_sw
