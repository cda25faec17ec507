#include "flight_sw/flight_software.hpp"

#include "flight_sw/guidance.hpp"
#include "flight_sw/mission_text.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace shelfcross::flight_sw {

namespace {
// A state record older than this is not the vehicle's height now (they come at 10 Hz).
constexpr double kStateFresh_s = 0.3;
// After a refused `land`: how long to watch the state height before asking again (the
// tello_pilot's own landing asks every 0.5 s too).
constexpr double kLandRefusedWait_s = 0.5;
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
  telemetry_.control.velocity = sticks_.velocity();
  telemetry_.link.stale_replies = commands_.stale_replies();
  telemetry_.link.video_stalled = video_stalled_;
  const TrackerRecord& counts = tracker_.record();
  telemetry_.tracking.rejected_poses = counts.rejected_poses;
  telemetry_.tracking.wrong_level_poses = counts.wrong_level_poses;
  telemetry_.tracking.behind_tags_dropped = counts.behind_tags_dropped;
  telemetry_.tracking.identity_checks = counts.identity_checks;
  telemetry_.tracking.hidden_target_pictures = counts.hidden_target_pictures;
  return out_;
}

void FlightSoftware::on_reply(const SdkReply& reply) {
  if (auto c = commands_.on_reply(reply)) on_completion(*c);
}

void FlightSoftware::on_state(const StateRecord& s) {
  odometry_.on_state(s);
  state_ = s;
  telemetry_.link.battery_pct = s.battery_pct;
  telemetry_.link.height_m = s.height_m;
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
    ++telemetry_.link.bad_frames;
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
  if (damage > 0) ++telemetry_.link.damaged_frames;
  bool decides = damage <= config_.perception.decide_max_damage_events;
  const cv::Mat* image = &f.bgr;
  if (!decides && damage_clear_of_decision(f)) {
    // The damage lies away from what the decisions need: decide on the rest, with the
    // guessed rows blanked so that nothing is detected in them.
    decides = true;
    blank_rows(f, masked_bgr_);
    image = &masked_bgr_;
    ++telemetry_.link.band_decided_frames;
  }
  const Picture pic{*image, now_ns_, damage, decides, &f.damaged_rows};
  if (!decides && damage > config_.perception.steer_max_damage_events) {
    ++telemetry_.link.unflown_frames;
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
    telemetry_.control.rc = *rc;
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

// A state record within kStateFresh_s: the Tello sends them at 10 Hz.
bool FlightSoftware::state_fresh() const {
  return state_ && ns_to_seconds(now_ns_ - state_->t_ns) <= kStateFresh_s;
}

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
  telemetry_.tracking.target.reset();
  telemetry_.tracking.tracked_box_px.reset();
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
