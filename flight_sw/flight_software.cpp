#include "flight_sw/flight_software.hpp"

#include "flight_sw/guidance.hpp"

#include <algorithm>
#include <cstdio>
#include <cmath>
#include <stdexcept>

namespace shelfcross::flight_sw {

namespace {
// A state record older than this is not the vehicle's height now (they come at 10 Hz).
constexpr double kStateFresh_s = 0.3;
// After a refused `land`: how long to watch the state height before asking again (the
// tello_pilot's own landing asks every 0.5 s too).
constexpr double kLandRefusedWait_s = 0.5;
// Why an approach that never centred gives up, once the re-reads are spent.
constexpr const char* kCouldNotCentre = "could not centre on the target cell";
}  // namespace

const char* outcome_name(Outcome o) {
  switch (o) {
    case Outcome::Running: return "running";
    case Outcome::Crossed: return "crossed";
    case Outcome::Completed: return "completed";
    case Outcome::NoEmptyCell: return "no_empty_cell";
    case Outcome::Aborted: return "aborted";
  }
  return "?";
}

namespace {

FlightConfig validated(FlightConfig c) {
  validate_flight_config(c);
  return c;
}

std::string cell_text(CellIndex c) {
  // Appended piece by piece: GCC 12 misreads "literal" + std::string as an overlapping copy
  // (-Wrestrict, a false positive in its own <string>).
  std::string text = "L";
  text += std::to_string(c.level);
  text += " C";
  text += std::to_string(c.column);
  return text;
}

// A length for logs: metres with two decimals.
std::string format_m(double v) {
  char b[32];
  std::snprintf(b, sizeof b, "%.2f", v);
  return b;
}

}  // namespace

FlightSoftware::FlightSoftware(FlightConfig config)
    : config_(validated(std::move(config))),
      commands_(config_.timeouts),
      sticks_(config_),
      survey_(config_),
      tracker_(config_) {}

// ---- Entry points ----

std::vector<SdkCommand> FlightSoftware::start(TimeNs t_ns) {
  std::vector<SdkCommand> out;
  if (phase_ != Phase::Idle) return out;
  now_ns_ = t_ns;
  telemetry_.t_ns = t_ns;
  result_.outcome = Outcome::Running;
  enter(Phase::EnterSdk, "entering SDK mode");
  commands_.poll(now_ns_, out);
  return out;
}

std::vector<SdkCommand> FlightSoftware::step(const Input& input) {
  out_.clear();
  if (phase_ == Phase::Idle || phase_ == Phase::Done) {
    if (const auto* r = std::get_if<SdkReply>(&input)) commands_.on_reply(*r);  // drained
    return out_;
  }
  const TimeNs t = std::visit([](const auto& m) { return m.t_ns; }, input);
  now_ns_ = std::max(now_ns_, t);
  telemetry_.t_ns = now_ns_;
  std::visit(
      [this](const auto& m) {
        using T = std::decay_t<decltype(m)>;
        if constexpr (std::is_same_v<T, SdkReply>) on_reply(m);
        else if constexpr (std::is_same_v<T, StateRecord>) on_state(m);
        else if constexpr (std::is_same_v<T, CameraFrame>) on_frame(m);
        // ClockTick: only the timers below.
      },
      input);
  if (auto c = commands_.check_timeout(now_ns_)) on_completion(*c);
  if (phase_ != Phase::Done) supervise();
  commands_.poll(now_ns_, out_);
  telemetry_.phase = phase_;
  telemetry_.velocity = sticks_.velocity();
  telemetry_.stale_replies = commands_.stale_replies();
  telemetry_.video_stalled = video_stalled_;
  const TrackerRecord& counts = tracker_.record();
  telemetry_.rejected_poses = counts.rejected_poses;
  telemetry_.wrong_level_poses = counts.wrong_level_poses;
  telemetry_.behind_tags_dropped = counts.behind_tags_dropped;
  telemetry_.identity_checks = counts.identity_checks;
  telemetry_.hidden_target_pictures = counts.hidden_target_pictures;
  return out_;
}

void FlightSoftware::on_reply(const SdkReply& reply) {
  if (auto c = commands_.on_reply(reply)) on_completion(*c);
}

void FlightSoftware::on_state(const StateRecord& s) {
  odometry_.on_state(s);
  state_ = s;
  telemetry_.battery_pct = s.battery_pct;
  telemetry_.height_m = s.height_m;
  cell_height_.on_state(s);
  if (phase_ == Phase::Approach) line_hold_.on_state(s, quiet_at(s.t_ns));
  if (phase_ == Phase::Transfer) transfer();
  // The crossing holds the cell centre's height by the state height (no picture shows the cell
  // in there): a drift or a sink the open-loop command would carry into a beam is turned back.
  if (phase_ == Phase::Cross && crossing_height_m_) {
    sticks_.set_vz(crossing_vz_mps(config_.control, *crossing_height_m_, s.height_m));
    watch_crossing(s);
  }
}

void FlightSoftware::on_frame(const CameraFrame& f) {
  if (f.bgr.type() != CV_8UC3 || f.bgr.cols != config_.camera.width_px ||
      f.bgr.rows != config_.camera.height_px) {
    ++telemetry_.bad_frames;
    return;
  }
  last_frame_ns_ = now_ns_;
  if (video_stalled_) {
    video_stalled_ = false;
    telemetry_.event = "video back";
  }
  // Damaged pictures (error-concealed bands, see CameraFrame): the guessed bands last until
  // the next key frame, so such frames come in runs and can show a tag where it is not, or
  // lose it. Decisions (viewpoint reached, inventory read and closed, target chosen or
  // re-acquired, crossing committed, the last centimetres before it) are taken only on
  // pictures with at most decide_max_damage_events lost bands; up to steer_max_damage_events a
  // picture steers the loops; beyond, it is video but not a view: the vehicle hovers on it.
  const int damage = f.damaged || f.damage_events > 0 ? std::max(1, f.damage_events) : 0;
  if (damage > 0) ++telemetry_.damaged_frames;
  bool decides = damage <= config_.perception.decide_max_damage_events;
  const cv::Mat* image = &f.bgr;
  if (!decides && damage_clear_of_decision(f)) {
    // The damage lies away from what the decisions need: decide on the rest, with the
    // guessed rows blanked so that nothing is detected in them.
    decides = true;
    blank_rows(f, masked_bgr_);
    image = &masked_bgr_;
    ++telemetry_.band_decided_frames;
  }
  const Picture pic{*image, now_ns_, damage, decides, &f.damaged_rows};
  if (!decides && damage > config_.perception.steer_max_damage_events) {
    ++telemetry_.unflown_frames;
    if (vision_phase(phase_)) hold_or_hover();
    if (phase_ == Phase::WaitVideo) command_takeoff_if_ready();
    else emit_rc(false);
    return;
  }
  switch (phase_) {
    case Phase::WaitVideo:
      command_takeoff_if_ready();
      return;
    case Phase::FindShelf: find_shelf(pic); break;
    case Phase::GoToViewpoint: go_to_viewpoint(pic, false); break;
    case Phase::TakeInventory: take_inventory(pic); break;
    case Phase::Approach: approach(pic); break;
    default: break;
  }
  sticks_.controlled(now_ns_);
  emit_rc(false);
}

// The picture rows the current phase's decisions rest on, from the last analysis: the front
// shelf's tags (finding it, reaching the viewpoint, reading it), the target's tracked box (the
// approach). Nothing where no such rows are known.
std::optional<cv::Rect2d> FlightSoftware::decision_region_px() const {
  switch (phase_) {
    case Phase::FindShelf:
    case Phase::GoToViewpoint:
    case Phase::TakeInventory: {
      const ShelfView& view = survey_.view();
      if (!view.full || view.tags.empty()) return std::nullopt;
      cv::Rect region = view.tags.front().bbox_px;
      for (const TagBlob& t : view.tags) region |= t.bbox_px;
      return cv::Rect2d(region);
    }
    case Phase::Approach:
      if (!tracker_.target() || tracker_.corners().box_px().area() <= 0.0) return std::nullopt;
      return tracker_.corners().box_px();
    default:
      return std::nullopt;
  }
}

// True when the frame's damage is placed and lies perception.band_margin_px clear of the
// decision region's rows (config.hpp).
bool FlightSoftware::damage_clear_of_decision(const CameraFrame& f) const {
  const double margin = config_.perception.band_margin_px;
  if (margin < 0.0) return false;
  if (f.damaged_rows.empty()) return true;  // the damage has left the picture
  const std::optional<cv::Rect2d> region = decision_region_px();
  if (!region) return false;
  return !rows_touch(f.damaged_rows, region->y - margin, region->y + region->height + margin);
}

// `out` = the frame's picture with its damaged rows mid-grey (no tag colour, no marker).
void FlightSoftware::blank_rows(const CameraFrame& f, cv::Mat& out) {
  f.bgr.copyTo(out);
  for (const RowSpan& r : f.damaged_rows) {
    const int b = std::clamp(r.v_begin_px, 0, out.rows), e = std::clamp(r.v_end_px, 0, out.rows);
    if (e > b) out.rowRange(b, e).setTo(cv::Scalar(128, 128, 128));
  }
}

// ---- SDK command results ----

void FlightSoftware::on_completion(const MissionCommands::Completion& c) {
  // Asked again while retries remain (MissionCommands::retry), the event saying why.
  auto retried = [&](double timeout_s) {
    if (!commands_.retry(c, timeout_s)) return false;
    telemetry_.event = "'" + c.command + "' " + (c.timed_out ? "timed out" : "refused: " + c.reply) +
                       ", retry " + std::to_string(commands_.attempts());
    return true;
  };
  if (c.command == "command" || c.command == "streamon") {
    if (c.ok) {
      if (c.command == "command") {
        enter(Phase::StartVideo, "SDK mode; starting video");
      } else {
        enter(Phase::WaitVideo, "video on; waiting for the first frame");
      }
    } else if (!retried(config_.timeouts.command_reply_s)) {
      abort_on_ground("'" + c.command + "' failed: " + (c.timed_out ? "no reply" : c.reply));
    }
  } else if (c.command == "takeoff") {
    const bool airborne_anyway = c.timed_out && state_ &&
                                 state_->height_m > config_.mission.airborne_height_m;
    if (c.ok || airborne_anyway) {
      airborne_since_ns_ = now_ns_;
      enter(Phase::FindShelf, c.ok ? "airborne" : "airborne (takeoff reply lost)");
    } else if (!retried(config_.timeouts.takeoff_reply_s)) {
      abort_on_ground("takeoff failed: " + (c.timed_out ? std::string("no reply") : c.reply));
    }
  } else if (c.command == "land") {
    // The `ok` comes once the drone is down; if it was lost, a repeated `land` finds the drone
    // on the ground and gets `error`. The state height settles it, as for a takeoff whose reply
    // was lost: at or below airborne_height_m the drone is down. (A stale state record shows
    // the last height in flight, so it can only keep the flight software trying.)
    const bool down_anyway = !c.ok && state_ && state_->height_m <= config_.mission.airborne_height_m;
    if (c.ok || down_anyway) {
      finish_landing(true, c.ok ? "landed" : "landed (no `ok`: the state height says on the ground)");
    } else if (!c.timed_out && !land_given_up()) {
      // Refused in the air: the Tello refuses `land` while it is already landing (a duplicated
      // datagram started the landing, and its `error` was taken for this `land`'s reply) and,
      // now and then, with `error Not joystick`. Retrying at once would spend the retries in a
      // fraction of a second and give up on a drone that is coming down; instead wait
      // kLandRefusedWait_s watching the state height (supervise), then ask again, for up to
      // land_reply_s, the longest a landing may take.
      commands_.ask_again_at("land", config_.timeouts.land_reply_s, now_ns_ + seconds_to_ns(kLandRefusedWait_s));
      telemetry_.event = "'land' refused in the air (" + c.reply + "): waiting for the state height";
    } else if (!(c.timed_out && retried(config_.timeouts.land_reply_s))) {
      result_.reason += "; land not acknowledged";
      finish_landing(false, "land not acknowledged");
    }
  }
}

void FlightSoftware::finish_landing(bool landed, const std::string& why) {
  result_.outcome = pending_outcome_;
  result_.landed = landed;
  commands_.cancel_wait();
  enter(Phase::Done, why);
}

bool FlightSoftware::land_given_up() const {
  // Refusals are waited out, not counted: the bound is the time a landing may take.
  return ns_to_seconds(now_ns_ - phase_start_ns_) > config_.timeouts.land_reply_s;
}

// ---- Timers: failsafes, phase timeouts, keep-alive ----

void FlightSoftware::supervise() {
  const Timeouts& to = config_.timeouts;
  const double in_phase_s = ns_to_seconds(now_ns_ - phase_start_ns_);
  auto timed_out = [&](double limit_s) { return in_phase_s > limit_s; };
  switch (phase_) {
    case Phase::WaitVideo:
      if (timed_out(to.video_start_s)) abort_on_ground("no video after streamon");
      return;
    case Phase::FindShelf:
      if (timed_out(to.find_shelf_s)) return land(Outcome::Aborted, "shelf not found");
      break;
    case Phase::GoToViewpoint:
      if (timed_out(to.go_to_viewpoint_s)) return land(Outcome::Aborted, "viewpoint not reached");
      break;
    case Phase::TakeInventory:
      if (timed_out(to.take_inventory_s)) return land(Outcome::Aborted, "inventory not completed");
      break;
    case Phase::Approach:
      if (retreat_until_ns_) {  // a declined crossing: back out, then land clear of the shelf
        if (now_ns_ >= *retreat_until_ns_) return land(Outcome::Aborted, retreat_reason_);
        sticks_.set(back_off_velocity(config_.control), now_ns_);
        break;
      }
      if (timed_out(to.approach_s)) return land(Outcome::Aborted, "approach timed out");
      if (lost_since_ns_ && ns_to_seconds(now_ns_ - *lost_since_ns_) > to.target_lost_s) {
        // The shelf's grid still in nearly whole pictures, only the target not found again
        // near where it was last seen (the view moved on while the pictures were damaged, or
        // the pose checks refused every candidate): choose it anew from the viewpoint. No
        // grid in view: nothing to re-read from here; land where it hovers.
        if (grid_in_view_while_lost_) return reread_shelf("target lost", "target lost");
        return land(Outcome::Aborted, "target lost");
      }
      if (back_off_since_ns_ && ns_to_seconds(now_ns_ - *back_off_since_ns_) > to.back_off_s) {
        return reread_shelf(kCouldNotCentre, kCouldNotCentre);
      }
      break;
    case Phase::Cross:
      // No fresh state record: no height to hold by; zero vertical stick (the autopilot holds
      // its own height reference) rather than a correction computed on an old height.
      if (!state_fresh()) sticks_.set_vz(0.0);
      if (crossing_flown(crossing_end_, now_ns_ - phase_start_ns_, state_fresh(), odometry_.p_O_m())) {
        if (!last_shelf()) {
          sticks_.hover();
          return next_shelf("crossed cell " + cell_text(*tracker_.target()) + " of shelf " + std::to_string(shelf_) +
                            ": finding the next shelf");
        }
        return land(Outcome::Crossed, "crossed cell " + cell_text(*tracker_.target()) +
                                          (shelf_ > 0 ? " of the last shelf" : ""));
      }
      break;
    case Phase::Transfer:
      if (transfer_.leg_s(now_ns_) > config_.strategy.transfer_leg_s) {
        return land(Outcome::Aborted, "transfer waypoint not reached");
      }
      break;
    case Phase::Land:
      // After a refused `land` (on_completion): down by a fresh state record (low and
      // vertically still: a landing drone passes airborne_height_m still descending), or ask
      // again when the wait is over (MissionCommands::poll).
      if (commands_.waiting() && state_fresh() && state_->height_m <= config_.mission.airborne_height_m &&
          std::abs(state_->vz_H_mps) <= kVerticallyStill_mps) {
        return finish_landing(true, "landed (`land` refused while landing; the state height says on the ground)");
      }
      return;
    default:
      break;
  }
  if (!airborne(phase_)) return;
  // Low battery: land now, except in the crossing (finish it, then land beyond the shelf).
  if (phase_ != Phase::Cross && state_ && state_->battery_pct < config_.mission.low_battery_pct) {
    return land(Outcome::Aborted, "low battery (" + std::to_string(state_->battery_pct) + "%)");
  }
  // Video stall: the timers run on whatever input arrives (state records at 10 Hz).
  if (vision_phase(phase_)) {
    const TimeNs since_ns = now_ns_ - std::max(last_frame_ns_.value_or(0), airborne_since_ns_);
    if (ns_to_seconds(since_ns) > to.video_land_s) return land(Outcome::Aborted, "video lost");
    if (ns_to_seconds(since_ns) > to.video_hover_s && !video_stalled_) {
      video_stalled_ = true;
      telemetry_.event = "video stalled: hovering";
      sticks_.hover();
      emit_rc(true);
    }
  }
  // Keep-alive (and the steady rc while frames are missing).
  if (sticks_.keepalive_due(now_ns_)) emit_rc(true);
}

// ---- Actions ----

// Every transition passes here: the table (mission_phases.cpp) says which are allowed; what
// every phase's start clears, then the phase's own entry (the SDK command it asks for).
void FlightSoftware::enter(Phase p, const std::string& event) {
  if (!may_enter(phase_, p)) {
    throw std::logic_error(std::string("mission: no transition from ") + phase_name(phase_) + " to " + phase_name(p));
  }
  phase_ = p;
  phase_start_ns_ = now_ns_;
  telemetry_.phase = p;
  telemetry_.event = event;
  survey_.restart_settling();
  lost_since_ns_.reset();
  back_off_since_ns_.reset();
  rough_since_ns_.reset();
  retreat_until_ns_.reset();
  sticks_.restart_loops();
  const Timeouts& to = config_.timeouts;
  switch (p) {
    case Phase::EnterSdk: return commands_.ask("command", to.command_reply_s);
    case Phase::StartVideo: return commands_.ask("streamon", to.command_reply_s);
    case Phase::TakeOff: return commands_.ask("takeoff", to.takeoff_reply_s);
    case Phase::Land: return commands_.ask("land", to.land_reply_s);
    default: return;
  }
}

// The first frame proves the video: take off unless the battery is too low.
void FlightSoftware::command_takeoff_if_ready() {
  if (state_ && state_->battery_pct < config_.mission.takeoff_min_battery_pct) {
    abort_on_ground("battery " + std::to_string(state_->battery_pct) + "% below the take-off minimum");
  } else {
    enter(Phase::TakeOff, "taking off");
  }
}

void FlightSoftware::land(Outcome outcome, const std::string& reason) {
  // Sticks to zero before "land": no rc goes out while a command is outstanding, so if "land"
  // is lost the Tello would keep the last sticks (the crossing speed, say) until the retry.
  sticks_.hover();
  emit_rc(true);
  pending_outcome_ = outcome;
  result_.reason = reason;
  enter(Phase::Land, "landing: " + reason);
}

void FlightSoftware::abort_on_ground(const std::string& reason) {
  result_ = {Outcome::Aborted, reason, false};
  enter(Phase::Done, "gave up on the ground: " + reason);
}

// A picture that cannot steer (too damaged to fly on, or the target not found in a damaged
// one): the last command held briefly, then a hover (Sticks::hold_or_hover). Not while the
// corner tags are leaving the view: there only nearly whole pictures move the vehicle
// (approach).
void FlightSoftware::hold_or_hover() {
  sticks_.hold_or_hover(now_ns_, phase_ == Phase::Approach && tracker_.corners().near_edge());
}

void FlightSoftware::emit_rc(bool force) {
  if (!airborne(phase_) || commands_.outstanding()) return;
  if (const std::optional<RcSticks> rc = sticks_.due(now_ns_, force)) {
    telemetry_.rc = *rc;
    out_.push_back({now_ns_, rc->text()});
  }
}

// ---- Phase behaviours ----

void FlightSoftware::fly(const SurveyStep& step) {
  if (step.velocity) sticks_.set(*step.velocity, now_ns_);
  if (step.hover) sticks_.hover();
}

void FlightSoftware::find_shelf(const Picture& pic) {
  const bool back_out = reread_back_until_ns_ && now_ns_ < *reread_back_until_ns_;
  const SurveyStep step = survey_.find_shelf(pic, back_out, telemetry_);
  fly(step);
  if (step.next == SurveyStep::Next::WholeShelfInView) {
    enter(Phase::GoToViewpoint, "whole shelf in view");
    go_to_viewpoint(pic, true);
  }
}

void FlightSoftware::go_to_viewpoint(const Picture& pic, bool view_fresh) {
  const SurveyStep step = survey_.go_to_viewpoint(pic, now_ns_, view_fresh, telemetry_);
  fly(step);
  if (step.next == SurveyStep::Next::ShelfOutOfView) enter(Phase::FindShelf, "shelf out of view: searching");
  if (step.next == SurveyStep::Next::AtViewpoint) enter(Phase::TakeInventory, "at the optimal viewpoint: reading the shelf");
}

// The inventory taken: the conventional strategies fly their transfer; through the cells, the
// target is chosen on the full view just read, or, with no crossable empty cell, it lands.
void FlightSoftware::take_inventory(const Picture& pic) {
  const SurveyStep step = survey_.take_inventory(pic, telemetry_);
  fly(step);
  if (step.next != SurveyStep::Next::InventoryTaken) return;
  if (config_.strategy.mode != Strategy::through_cells) {
    start_transfer();
    return;
  }
  if (!select_target(pic.bgr)) {
    land(Outcome::NoEmptyCell, "inventory taken; no crossable empty cell");
    return;
  }
  enter(Phase::Approach, "inventory taken; approaching cell " + cell_text(*tracker_.target()));
  lateral_active_ns_ = now_ns_;  // not yet seen still
  hold_since_ns_.reset();
}

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
  telemetry_.target = best;
  telemetry_.tracked_box_px = tracker_.corners().box_px();
  cell_height_.clear();
  line_hold_.clear();
  forward_gain_.restart();
  telemetry_.target_identity = tracker_.identification().identity();
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

// A state record within kStateFresh_s: the Tello sends them at 10 Hz.
bool FlightSoftware::state_fresh() const {
  return state_ && ns_to_seconds(now_ns_ - state_->t_ns) <= kStateFresh_s;
}

// The target lost: the shelf's view analysed anew, the target looked for near its last box
// (target_tracker.hpp, TargetTracker::reacquire).
bool FlightSoftware::reacquire(const Picture& pic) {
  survey_.analyse(pic.bgr, telemetry_);
  if (!tracker_.reacquire(pic, survey_.view(), survey_.tag_detector(), state_)) return false;
  after_measurement();
  telemetry_.tracked_box_px = tracker_.corners().box_px();
  return true;
}

// What a successful measurement of the target changed, for the telemetry.
void FlightSoftware::after_measurement() {
  if (tracker_.identification().continuity_lost()) telemetry_.event = "target continuity lost: identity to be confirmed";
  telemetry_.target_identity = tracker_.identification().identity();
}

// The target's identity judged on this picture (target_tracker.hpp): a contradiction, or no
// confirmation within identity_confirm_s, re-reads the shelf (false: the approach is over).
bool FlightSoftware::check_identity(const Picture& pic, const PoseEstimate& pose) {
  const IdentityCheck check = tracker_.check_identity(pic, pose, survey_.tag_detector(), survey_.marker_detector(), survey_.inventory());
  if (check.verdict == CellIdentity::Confirmed) {
    telemetry_.target_identity = tracker_.identification().identity();
    telemetry_.event = "target identity confirmed: " + check.why;
    return true;
  }
  if (check.verdict == CellIdentity::Contradicted) {
    ++telemetry_.identity_contradictions;
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
  telemetry_.forward_gain = forward_gain_.gain();
}

void FlightSoftware::reread_shelf(const std::string& why, const std::optional<std::string>& give_up_reason) {
  ++telemetry_.shelf_rereads;
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
  telemetry_.target.reset();
  cell_height_.clear();
  line_hold_.clear();
  telemetry_.target_identity = tracker_.identification().identity();
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
  telemetry_.tracker_ok = predicted.tracker_ok;
  const bool found = tracker_.measure(pic, predicted.box_px, survey_.tag_detector(), state_);
  if (found) after_measurement();
  feed_line_hold(found, odometry);
  telemetry_.tracked_box_px = tracker_.corners().box_px();
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
  telemetry_.e_z_m = e.e_z_m;
  telemetry_.e_psi_rad = e.e_psi_rad;
  telemetry_.psi_cell_rad = e.psi_cell_rad;
  telemetry_.yaw_cell_rad = pose.yaw_rad;
  telemetry_.lateral_mps = v.vy_B_mps;
  telemetry_.settled = h.settled;
  telemetry_.holding_short = hold;
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

namespace shelfcross::flight_sw {

// ---- Several shelves and the conventional strategies ----

std::vector<BoxEntry> FlightSoftware::all_boxes() const {
  std::vector<BoxEntry> all;
  for (const Inventory& inv : survey_.finished()) {
    const auto b = inv.boxes();
    all.insert(all.end(), b.begin(), b.end());
  }
  const auto b = survey_.inventory().boxes();
  all.insert(all.end(), b.begin(), b.end());
  return all;
}

std::string FlightSoftware::inventory_json() const {
  if (config_.layout.shelf_count == 1) return survey_.inventory().to_json();
  std::string j = "{\"shelves\":[";
  for (const Inventory& inv : survey_.finished()) j += inv.to_json() + ",";
  return j + survey_.inventory().to_json() + "]}";
}

void FlightSoftware::next_shelf(const std::string& event) {
  ++shelf_;
  survey_.next_shelf(shelf_);
  tracker_.forget();
  cell_height_.clear();
  crossing_height_m_.reset();
  crossing_refusals_ = 0;
  hold_since_ns_.reset();
  telemetry_.target.reset();
  telemetry_.tracked_box_px.reset();
  telemetry_.shelf = shelf_;
  enter(Phase::FindShelf, event);
}

void FlightSoftware::start_transfer() {
  const std::optional<PoseEstimate>& pose_G = survey_.pose_G();
  if (!pose_G || !state_) return land(Outcome::Aborted, "no pose or state for the transfer");
  transfer_.plan(config_, *pose_G, state_->yaw_rad, odometry_.p_O_m(), survey_.viewpoint_G_m(), last_shelf(), now_ns_);
  enter(Phase::Transfer, std::string("inventory taken; ") +
                             (config_.strategy.mode == Strategy::over_tops ? "over the top" : "around the end") +
                             (last_shelf() ? " of the last shelf" : " to the next shelf"));
}

// On each state record: the next waypoint once within waypoint_tolerance_m, then the P law
// toward it, heading held on the shelf normal (guidance.hpp, transfer_velocity).
void FlightSoftware::transfer() {
  const StrategyParams& st = config_.strategy;
  const TransferFlight::Progress leg = transfer_.on_state(odometry_.p_O_m(), st.waypoint_tolerance_m, now_ns_);
  if (leg.arrived) {
    sticks_.hover();
    if (last_shelf()) {
      return land(Outcome::Completed, std::string("passed the last shelf ") +
                                          (st.mode == Strategy::over_tops ? "over the top" : "around the end"));
    }
    return next_shelf("transfer done: finding shelf " + std::to_string(shelf_ + 1));
  }
  if (leg.next_leg) telemetry_.event = "transfer waypoint " + std::to_string(transfer_.waypoint());
  sticks_.set(transfer_velocity(config_, leg.e_O_m, state_->yaw_rad, transfer_.hold_yaw_O_rad()), now_ns_);
  emit_rc(false);
}

}  // namespace shelfcross::flight_sw
