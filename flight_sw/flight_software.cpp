#include "flight_sw/flight_software.hpp"

#include "flight_sw/guidance.hpp"
#include "flight_sw/mission_text.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace shelfcross::flight_sw {

namespace {

FlightConfig validated(FlightConfig c) {
  validate_flight_config(c);
  return c;
}

// The picture rows the current phase's decisions rest on, from the last analysis: the front
// shelf's tags (finding it, reaching the viewpoint, reading it), the target's tracked box (the
// approach). Nothing where no such rows are known.
std::optional<cv::Rect2d> decision_region_px(Phase phase, const ShelfSurvey& survey, const TargetTracker& tracker) {
  switch (phase) {
    case Phase::FindShelf:
    case Phase::GoToViewpoint:
    case Phase::TakeInventory: {
      const ShelfView& view = survey.view();
      if (!view.full || view.tags.empty()) return std::nullopt;
      cv::Rect region = view.tags.front().bbox_px;
      for (const TagBlob& t : view.tags) region |= t.bbox_px;
      return cv::Rect2d(region);
    }
    case Phase::Approach:
      if (!tracker.target() || tracker.corners().box_px().area() <= 0.0) return std::nullopt;
      return tracker.corners().box_px();
    default:
      return std::nullopt;
  }
}

}  // namespace

FlightSoftware::FlightSoftware(FlightConfig config)
    : config_(std::make_shared<const FlightConfig>(validated(std::move(config)))),
      commands_(*config_),
      sticks_(*config_),
      video_(*config_),
      survey_(*config_),
      approach_(*config_),
      crossing_(*config_) {}

// ---- Entry points ----

std::vector<SdkCommand> FlightSoftware::start(TimeNs t_ns) {
  std::vector<SdkCommand> out;
  if (facts_.phase.current() != Phase::Idle) return out;
  facts_.now_ns = t_ns;
  facts_.telemetry.t_ns = t_ns;
  enter(Phase::EnterSdk, "entering SDK mode");
  commands_.poll(facts_.now_ns, out);
  return out;
}

std::vector<SdkCommand> FlightSoftware::step(const Input& input) {
  out_.clear();
  if (facts_.phase.current() == Phase::Idle || facts_.phase.current() == Phase::Done) {
    if (const auto* r = std::get_if<SdkReply>(&input)) commands_.drain(*r);
    return out_;
  }
  const TimeNs t = std::visit([](const auto& m) { return m.t_ns; }, input);
  facts_.now_ns = std::max(facts_.now_ns, t);
  facts_.telemetry.t_ns = facts_.now_ns;
  std::visit(
      [this](const auto& m) {
        using T = std::decay_t<decltype(m)>;
        if constexpr (std::is_same_v<T, SdkReply>) on_reply(m);
        else if constexpr (std::is_same_v<T, StateRecord>) on_state(m);
        else if constexpr (std::is_same_v<T, CameraFrame>) on_frame(m);
        // ClockTick: only the timers below.
      },
      input);
  commands_.check_timeout(facts_, *this);
  if (facts_.phase.current() != Phase::Done) supervise();
  commands_.poll(facts_.now_ns, out_);
  facts_.telemetry.phase = facts_.phase.current();
  facts_.telemetry.control.velocity = sticks_.velocity();
  facts_.telemetry.link.stale_replies = commands_.stale_replies();
  facts_.telemetry.link.video_stalled = video_.stalled();
  const TrackerRecord& counts = approach_.tracker().record();
  facts_.telemetry.tracking.rejected_poses = counts.rejected_poses;
  facts_.telemetry.tracking.wrong_level_poses = counts.wrong_level_poses;
  facts_.telemetry.tracking.behind_tags_dropped = counts.behind_tags_dropped;
  facts_.telemetry.tracking.identity_checks = counts.identity_checks;
  facts_.telemetry.tracking.hidden_target_pictures = counts.hidden_target_pictures;
  return out_;
}

void FlightSoftware::on_reply(const SdkReply& reply) {
  commands_.on_reply(reply, facts_, *this);
}

void FlightSoftware::on_state(const StateRecord& s) {
  facts_.on_state(s);
  approach_.on_state(s, facts_.phase.current() == Phase::Approach);
  if (facts_.phase.current() == Phase::Transfer) transfer();
  // The crossing holds the cell centre's height by the state height (no picture shows the cell
  // in there): a drift or a sink the open-loop command would carry into a beam is turned back.
  if (facts_.phase.current() == Phase::Cross && crossing_.holding()) {
    sticks_.set_vz(crossing_.vz_mps(s.height_m));
    // A drift the watch sees while the vehicle can still stop short of the front face stops
    // the crossing and backs it out (the approach counts it as a refusal of the gate).
    if (const std::optional<CrossingStop> stop = crossing_.watch(s, facts_)) {
      enter(Phase::Approach, "crossing stopped: " + stop->why + ": backing out");
      crossing_.stop();
      sticks_.set(back_off_velocity(config_->control), facts_.now_ns);
      follow(approach_.crossing_stopped(*stop, facts_));
      emit_rc(true);
    }
  }
}

void FlightSoftware::on_frame(const CameraFrame& f) {
  const std::optional<Picture> taken =
      video_.take(f, facts_, [this] { return decision_region_px(facts_.phase.current(), survey_, approach_.tracker()); });
  if (!taken) return;  // the wrong size or type: counted, ignored
  const Picture& pic = *taken;
  if (!pic.decides && pic.damage_events > config_->perception.steer_max_damage_events) {
    ++facts_.telemetry.link.unflown_frames;
    if (vision_phase(facts_.phase.current())) hold_or_hover();
    if (facts_.phase.current() == Phase::WaitVideo) commands_.take_off_if_ready(facts_, *this);
    else emit_rc(false);
    return;
  }
  switch (facts_.phase.current()) {
    case Phase::WaitVideo:
      commands_.take_off_if_ready(facts_, *this);
      return;
    case Phase::FindShelf: find_shelf(pic); break;
    case Phase::GoToViewpoint: go_to_viewpoint(pic, false); break;
    case Phase::TakeInventory: take_inventory(pic); break;
    case Phase::Approach: follow(approach_.step(pic, approach_tools())); break;
    default: break;
  }
  sticks_.controlled(facts_.now_ns);
  emit_rc(false);
}

// ---- Timers: failsafes, phase timeouts, keep-alive ----

void FlightSoftware::supervise() {
  // WaitVideo's and Land's timers; the other ground phases have none but their commands'.
  if (!airborne(facts_.phase.current())) return commands_.supervise(facts_, *this);
  const Timeouts& to = config_->timeouts;
  const double in_phase_s = facts_.phase.elapsed_s(facts_.now_ns);
  auto timed_out = [&](double limit_s) { return in_phase_s > limit_s; };
  switch (facts_.phase.current()) {
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
      // A declined crossing backing out (goes on), or landing; the time limit; the target lost
      // or an off-centre back-off too long (TargetApproach::supervise).
      if (const std::optional<ApproachStep> step = approach_.supervise(facts_, survey_, in_phase_s)) {
        follow(*step);
        if (step->next != ApproachStep::Next::Stay) return;
      }
      break;
    case Phase::Cross:
      // No fresh state record: no height to hold by; zero vertical stick (the autopilot holds
      // its own height reference) rather than a correction computed on an old height.
      if (!facts_.state_fresh()) sticks_.set_vz(0.0);
      if (crossing_.flown(facts_.phase.elapsed_ns(facts_.now_ns), facts_)) {
        if (!last_shelf()) {
          sticks_.hover();
          return next_shelf("crossed cell " + cell_text(*approach_.tracker().target()) + " of shelf " + std::to_string(shelf_) +
                            ": finding the next shelf");
        }
        return land(Outcome::Crossed, "crossed cell " + cell_text(*approach_.tracker().target()) +
                                          (shelf_ > 0 ? " of the last shelf" : ""));
      }
      break;
    case Phase::Transfer:
      if (transfer_.leg_s(facts_.now_ns) > config_->strategy.transfer_leg_s) {
        return land(Outcome::Aborted, "transfer waypoint not reached");
      }
      break;
    default:
      break;
  }
  if (!airborne(facts_.phase.current())) return;
  // Low battery: land now, except in the crossing (finish it, then land beyond the shelf).
  if (facts_.phase.current() != Phase::Cross && facts_.state && facts_.state->battery_pct < config_->mission.low_battery_pct) {
    return land(Outcome::Aborted, "low battery (" + std::to_string(facts_.state->battery_pct) + "%)");
  }
  // Video stall: the timers run on whatever input arrives (state records at 10 Hz).
  if (vision_phase(facts_.phase.current())) {
    const VideoStall stall = video_.stall(facts_);
    if (stall == VideoStall::Land) return land(Outcome::Aborted, "video lost");
    if (stall == VideoStall::Hover) {
      sticks_.hover();
      emit_rc(true);
    }
  }
  // Keep-alive (and the steady rc while frames are missing).
  if (sticks_.keepalive_due(facts_.now_ns)) emit_rc(true);
}

// ---- Actions ----

// Every transition passes here: the table (mission_phases.cpp) says which are allowed; what
// every phase's start clears, then the phase's own entry (the SDK command it asks for).
void FlightSoftware::enter(Phase p, const std::string& event) {
  const Phase from = facts_.phase.current();
  facts_.phase.enter(p, facts_.now_ns);
  facts_.telemetry.phase = p;
  facts_.telemetry.event = event;
  survey_.restart_settling();
  approach_.on_phase_change();
  sticks_.restart_loops();
  const Timeouts& to = config_->timeouts;
  switch (p) {
    case Phase::EnterSdk: return commands_.ask("command", to.command_reply_s);
    case Phase::StartVideo: return commands_.ask("streamon", to.command_reply_s);
    case Phase::TakeOff: return commands_.ask("takeoff", to.takeoff_reply_s);
    // Airborne: frames are needed from now on (the video's stall timer runs from here).
    case Phase::FindShelf:
      if (from == Phase::TakeOff) video_.airborne_from(facts_.now_ns);
      return;
    case Phase::Land: return commands_.ask("land", to.land_reply_s);
    default: return;
  }
}

void FlightSoftware::land(Outcome outcome, const std::string& reason) {
  // Sticks to zero before "land": no rc goes out while a command is outstanding, so if "land"
  // is lost the Tello would keep the last sticks (the crossing speed, say) until the retry.
  sticks_.hover();
  emit_rc(true);
  commands_.landing(outcome, reason);
  enter(Phase::Land, "landing: " + reason);
}

// A picture that cannot steer (too damaged to fly on, or the target not found in a damaged
// one): the last command held briefly, then a hover (Sticks::hold_or_hover). Not while the
// corner tags are leaving the view: there only nearly whole pictures move the vehicle
// (approach).
void FlightSoftware::hold_or_hover() {
  sticks_.hold_or_hover(facts_.now_ns, facts_.phase.current() == Phase::Approach && approach_.tracker().corners().near_edge());
}

void FlightSoftware::emit_rc(bool force) {
  if (!airborne(facts_.phase.current()) || commands_.outstanding()) return;
  if (const std::optional<RcSticks> rc = sticks_.due(facts_.now_ns, force)) {
    facts_.telemetry.control.rc = *rc;
    out_.push_back({facts_.now_ns, rc->text()});
  }
}

// ---- Phase behaviours ----

void FlightSoftware::fly(const SurveyStep& step) {
  if (step.velocity) sticks_.set(*step.velocity, facts_.now_ns);
  if (step.hover) sticks_.hover();
}

void FlightSoftware::follow(const ApproachStep& step) {
  if (step.velocity) sticks_.set(*step.velocity, facts_.now_ns);
  if (step.restart_loops) sticks_.restart_loops();
  if (step.hover) sticks_.hover();
  if (step.hold_or_hover) hold_or_hover();
  switch (step.next) {
    case ApproachStep::Next::Reread: return enter(Phase::FindShelf, step.event);
    case ApproachStep::Next::Land: return land(Outcome::Aborted, step.event);
    case ApproachStep::Next::Cross:
      crossing_.begin(*step.crossing);
      enter(Phase::Cross, step.crossing->event);
      sticks_.set(step.crossing->velocity, facts_.now_ns);
      return;
    default: return;
  }
}

void FlightSoftware::find_shelf(const Picture& pic) {
  const std::optional<TimeNs>& back_until = approach_.reread_back_until_ns();
  const bool back_out = back_until && facts_.now_ns < *back_until;
  const SurveyStep step = survey_.find_shelf(pic, back_out, facts_.telemetry);
  fly(step);
  if (step.next == SurveyStep::Next::WholeShelfInView) {
    enter(Phase::GoToViewpoint, "whole shelf in view");
    go_to_viewpoint(pic, true);
  }
}

void FlightSoftware::go_to_viewpoint(const Picture& pic, bool view_fresh) {
  const SurveyStep step = survey_.go_to_viewpoint(pic, facts_.now_ns, view_fresh, facts_.telemetry);
  fly(step);
  if (step.next == SurveyStep::Next::ShelfOutOfView) enter(Phase::FindShelf, "shelf out of view: searching");
  if (step.next == SurveyStep::Next::AtViewpoint) enter(Phase::TakeInventory, "at the optimal viewpoint: reading the shelf");
}

// The inventory taken: the conventional strategies fly their transfer; through the cells, the
// target is chosen on the full view just read, or, with no crossable empty cell, it lands.
void FlightSoftware::take_inventory(const Picture& pic) {
  const SurveyStep step = survey_.take_inventory(pic, facts_.telemetry);
  fly(step);
  if (step.next != SurveyStep::Next::InventoryTaken) return;
  if (config_->strategy.mode != Strategy::through_cells) {
    start_transfer();
    return;
  }
  if (!approach_.choose_target(pic.bgr, approach_tools(), last_shelf())) {
    land(Outcome::NoEmptyCell, "inventory taken; no crossable empty cell");
    return;
  }
  enter(Phase::Approach, "inventory taken; approaching cell " + cell_text(*approach_.tracker().target()));
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
  if (config_->layout.shelf_count == 1) return survey_.inventory().to_json();
  std::string j = "{\"shelves\":[";
  for (const Inventory& inv : survey_.finished()) j += inv.to_json() + ",";
  return j + survey_.inventory().to_json() + "]}";
}

void FlightSoftware::next_shelf(const std::string& event) {
  ++shelf_;
  survey_.next_shelf(shelf_);
  approach_.next_shelf(facts_.telemetry);
  crossing_.stop();
  facts_.telemetry.shelf = shelf_;
  enter(Phase::FindShelf, event);
}

void FlightSoftware::start_transfer() {
  const std::optional<PoseEstimate>& pose_G = survey_.pose_G();
  if (!pose_G || !facts_.state) return land(Outcome::Aborted, "no pose or state for the transfer");
  transfer_.plan(*config_, *pose_G, facts_.state->yaw_rad, facts_.odometry.p_O_m(), survey_.viewpoint_G_m(), last_shelf(), facts_.now_ns);
  enter(Phase::Transfer, std::string("inventory taken; ") +
                             (config_->strategy.mode == Strategy::over_tops ? "over the top" : "around the end") +
                             (last_shelf() ? " of the last shelf" : " to the next shelf"));
}

// On each state record: the next waypoint once within waypoint_tolerance_m, then the P law
// toward it, heading held on the shelf normal (guidance.hpp, transfer_velocity).
void FlightSoftware::transfer() {
  const StrategyParams& st = config_->strategy;
  const TransferFlight::Progress leg = transfer_.on_state(facts_.odometry.p_O_m(), st.waypoint_tolerance_m, facts_.now_ns);
  if (leg.arrived) {
    sticks_.hover();
    if (last_shelf()) {
      return land(Outcome::Completed, std::string("passed the last shelf ") +
                                          (st.mode == Strategy::over_tops ? "over the top" : "around the end"));
    }
    return next_shelf("transfer done: finding shelf " + std::to_string(shelf_ + 1));
  }
  if (leg.next_leg) facts_.telemetry.event = "transfer waypoint " + std::to_string(transfer_.waypoint());
  sticks_.set(transfer_velocity(*config_, leg.e_O_m, facts_.state->yaw_rad, transfer_.hold_yaw_O_rad()), facts_.now_ns);
  emit_rc(false);
}

}  // namespace shelfcross::flight_sw
