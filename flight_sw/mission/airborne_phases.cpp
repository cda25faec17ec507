#include "flight_sw/mission/airborne_phases.hpp"

#include <stdexcept>
#include <utility>

#include "flight_sw/guidance/guidance.hpp"
#include "flight_sw/text.hpp"

namespace shelfcross::flight_sw {

namespace {

// A survey step flown: its velocity, then its hover.
void fly(const SurveyStep& step, Sticks& sticks, TimeNs now_ns) {
  if (step.velocity) sticks.set(*step.velocity, now_ns);
  if (step.hover) sticks.hover();
}

Decision entering(Phase phase, std::string event) { return {.change = Transition{phase, std::move(event)}}; }
Decision landing(Outcome outcome, std::string reason) { return {.change = Landing{outcome, std::move(reason)}}; }

// In FindShelf: a re-read that started closer than the viewpoint is still backing straight out.
bool rereading_from_close(const TargetApproach& approach, const MissionFacts& facts) {
  const std::optional<TimeNs>& back_until = approach.reread_back_until_ns();
  return back_until && facts.now_ns < *back_until;
}

}  // namespace

Decision AirbornePhases::on_picture(const Picture& pic, AirborneTools t) {
  switch (t.facts.phase.current()) {
    case Phase::FindShelf: return find_shelf(pic, t);
    case Phase::GoToViewpoint: return go_to_viewpoint(pic, false, t);
    case Phase::TakeInventory: return take_inventory(pic, t);
    case Phase::Approach: return follow(approach_.step(pic, {t.facts, t.sticks, survey_}), t);
    default: return {};
  }
}

Decision AirbornePhases::on_state(const StateRecord& s, AirborneTools t) {
  MissionFacts& facts = t.facts;
  approach_.on_state(s, facts.phase.current() == Phase::Approach);
  if (facts.phase.current() == Phase::Transfer) return transfer(t);
  // The crossing holds the cell centre's height by the state height (no picture shows the cell
  // in there): a drift or a sink the open-loop command would carry into a beam is turned back.
  if (facts.phase.current() == Phase::Cross && crossing_.holding()) {
    crossing_.on_state(s, facts);
    t.sticks.set_vz(crossing_.vz_mps(s.height_m));
    // A drift the watch sees while the vehicle can still stop short of the front face stops
    // the crossing and backs it out (the approach counts it as a refusal of the gate): back in
    // the approach (resume), then the rc at once.
    if (std::optional<CrossingStop> stop = crossing_.watch(s, facts)) {
      Decision d = entering(Phase::Approach, "crossing stopped: " + stop->why + ": backing out");
      pending_ = std::move(*stop);
      d.resume = true;
      d.rc = RcSend::Now;
      return d;
    }
  }
  return {};
}

Decision AirbornePhases::resume(AirborneTools t, const Picture* pic) {
  const Pending pending = std::exchange(pending_, std::monostate{});
  if (std::holds_alternative<ViewpointOnSamePicture>(pending)) {
    if (pic == nullptr) throw std::logic_error("AirbornePhases::resume: the viewpoint needs the picture");
    return go_to_viewpoint(*pic, true, t);
  }
  if (const auto* stop = std::get_if<CrossingStop>(&pending)) {
    crossing_.stop();
    t.sticks.set(back_off_velocity(config_.control), t.facts.now_ns);
    return follow(approach_.crossing_stopped(*stop, t.facts), t);
  }
  if (const auto* line = std::get_if<VelocityCommand>(&pending)) t.sticks.fly_line(*line, t.facts.now_ns);
  return {};
}

Decision AirbornePhases::supervise(AirborneTools t) {
  MissionFacts& facts = t.facts;
  const Timeouts& to = config_.timeouts;
  const double in_phase_s = facts.phase.elapsed_s(facts.now_ns);
  const bool out_of_time = facts.out_of_time(to.mission_s);
  // The phase's time limit or the mission's passed: land, aborted with `reason`.
  auto timed_out = [&](double limit_s, const char* reason) -> Decision {
    if (in_phase_s > limit_s || out_of_time) {
      Decision d = landing(Outcome::Aborted, out_of_time ? kMissionTimeSpent : reason);
      d.supervised = true;
      return d;
    }
    return {};
  };
  switch (facts.phase.current()) {
    case Phase::FindShelf:
      // A re-read from close backs straight out first (TargetApproach::reread_back_until_ns):
      // out of time then, it finishes backing out and lands there, not close to the shelf.
      if (out_of_time && rereading_from_close(approach_, facts)) return {};
      return timed_out(to.find_shelf_s, "shelf not found");
    case Phase::GoToViewpoint: return timed_out(to.go_to_viewpoint_s, "viewpoint not reached");
    case Phase::TakeInventory:
      // Out of time in a hover that has lost the whole grid: search for the shelf once more
      // (the failsafes run after it).
      if (in_phase_s > to.take_inventory_s && !out_of_time && survey_.search_again(facts.now_ns)) {
        return entering(Phase::FindShelf, "inventory not completed, shelf out of view: searching again");
      }
      return timed_out(to.take_inventory_s, "inventory not completed");
    case Phase::Approach:
      // A declined crossing backing out (goes on), or landing; the time limits; the target lost
      // or an off-centre back-off too long (TargetApproach::supervise).
      if (const std::optional<ApproachStep> step = approach_.supervise(facts, survey_, in_phase_s, out_of_time)) {
        Decision d = follow(*step, t);
        d.supervised = step->next != ApproachStep::Next::Stay;
        return d;
      }
      return {};
    case Phase::Cross: {
      // No fresh state record: no height to hold by; zero vertical stick (the autopilot holds
      // its own height reference) rather than a correction computed on an old height.
      if (!facts.state_fresh()) t.sticks.set_vz(0.0);
      if (!crossing_.flown(facts.phase.elapsed_ns(facts.now_ns), facts)) return {};
      Decision d;
      if (!last_shelf()) {
        t.sticks.hover();
        d.change = next_shelf("crossed cell " + cell_text(*approach_.tracker().target()) + " of shelf " +
                                  std::to_string(shelf_) + ": finding the next shelf",
                              t);
      } else {
        d = landing(Outcome::Crossed,
                    "crossed cell " + cell_text(*approach_.tracker().target()) + (shelf_ > 0 ? " of the last shelf" : ""));
      }
      d.supervised = true;
      return d;
    }
    case Phase::Transfer:
      if (transfer_.leg_s(facts.now_ns) > config_.strategy.transfer_leg_s) {
        Decision d = landing(Outcome::Aborted, "transfer waypoint not reached");
        d.supervised = true;
        return d;
      }
      return {};
    default:
      return {};
  }
}

void AirbornePhases::hold_or_hover(const MissionFacts& facts, Sticks& sticks) const {
  sticks.hold_or_hover(facts.now_ns,
                       facts.phase.current() == Phase::Approach && approach_.tracker().corners().near_edge());
}

std::optional<cv::Rect2d> AirbornePhases::decision_region_px(Phase phase) const {
  switch (phase) {
    case Phase::FindShelf:
    case Phase::GoToViewpoint:
    case Phase::TakeInventory: {
      const ShelfView& view = survey_.view();
      if (!view.full || view.tags.empty()) return std::nullopt;
      cv::Rect region = view.tags.front().bbox_px;
      for (const TagBlob& tag : view.tags) region |= tag.bbox_px;
      return cv::Rect2d(region);
    }
    case Phase::Approach: {
      const TargetTracker& tracker = approach_.tracker();
      if (!tracker.target() || tracker.corners().box_px().area() <= 0.0) return std::nullopt;
      return tracker.corners().box_px();
    }
    default:
      return std::nullopt;
  }
}

void AirbornePhases::on_phase_change() {
  survey_.restart_settling();
  approach_.on_phase_change();
}

// ---- Phase behaviours on a picture ----

Decision AirbornePhases::find_shelf(const Picture& pic, AirborneTools t) {
  const SurveyStep step = survey_.find_shelf(pic, rereading_from_close(approach_, t.facts), t.facts.telemetry);
  fly(step, t.sticks, t.facts.now_ns);
  if (step.next != SurveyStep::Next::WholeShelfInView) return {};
  // The viewpoint's step on this same picture, its view fresh, once in GoToViewpoint.
  Decision d = entering(Phase::GoToViewpoint, "whole shelf in view");
  pending_ = ViewpointOnSamePicture{};
  d.resume = true;
  return d;
}

Decision AirbornePhases::go_to_viewpoint(const Picture& pic, bool view_fresh, AirborneTools t) {
  const SurveyStep step = survey_.go_to_viewpoint(pic, t.facts.now_ns, view_fresh, t.facts.telemetry);
  fly(step, t.sticks, t.facts.now_ns);
  if (step.next == SurveyStep::Next::ShelfOutOfView) return entering(Phase::FindShelf, "shelf out of view: searching");
  if (step.next == SurveyStep::Next::AtViewpoint) {
    return entering(Phase::TakeInventory, "at the optimal viewpoint: reading the shelf");
  }
  return {};
}

Decision AirbornePhases::take_inventory(const Picture& pic, AirborneTools t) {
  const MissionFacts& facts = t.facts;
  const SurveyStep step = survey_.take_inventory(pic, t.facts.telemetry);
  fly(step, t.sticks, facts.now_ns);
  if (step.next != SurveyStep::Next::InventoryTaken) return {};
  if (config_.strategy.mode != Strategy::through_cells) {
    const std::optional<PoseEstimate>& pose_G = survey_.pose_G();
    if (!pose_G || !facts.state) return landing(Outcome::Aborted, "no pose or state for the transfer");
    transfer_.plan(config_, *pose_G, facts.state->yaw_rad, facts.odometry.p_O_m(), survey_.viewpoint_G_m(),
                   last_shelf(), facts.now_ns);
    return entering(Phase::Transfer, std::string("inventory taken; ") +
                                         (config_.strategy.mode == Strategy::over_tops ? "over the top" : "around the end") +
                                         (last_shelf() ? " of the last shelf" : " to the next shelf"));
  }
  if (!approach_.choose_target(pic.bgr, {t.facts, t.sticks, survey_}, last_shelf())) {
    return landing(Outcome::NoEmptyCell, "inventory taken; no crossable empty cell");
  }
  return entering(Phase::Approach, "inventory taken; approaching cell " + cell_text(*approach_.tracker().target()));
}

Decision AirbornePhases::follow(const ApproachStep& step, AirborneTools t) {
  if (step.velocity) t.sticks.set(*step.velocity, t.facts.now_ns);
  if (step.restart_loops) t.sticks.restart_loops();
  if (step.hover) t.sticks.hover();
  if (step.hold_or_hover) hold_or_hover(t.facts, t.sticks);
  switch (step.next) {
    case ApproachStep::Next::Reread: return entering(Phase::FindShelf, step.event);
    case ApproachStep::Next::Land: return landing(Outcome::Aborted, step.event);
    case ApproachStep::Next::Cross: {
      // The line flown once in Cross (entering it restarts the PI loops).
      crossing_.begin(*step.crossing, t.facts.now_ns);
      Decision d = entering(Phase::Cross, step.crossing->event);
      pending_ = step.crossing->velocity;
      d.resume = true;
      return d;
    }
    default: return {};
  }
}

// ---- Several shelves and the conventional strategies ----

Transition AirbornePhases::next_shelf(const std::string& event, AirborneTools t) {
  ++shelf_;
  survey_.next_shelf(shelf_);
  approach_.next_shelf(t.facts.telemetry);
  crossing_.stop();
  t.facts.telemetry.shelf = shelf_;
  return {Phase::FindShelf, event};
}

Decision AirbornePhases::transfer(AirborneTools t) {
  MissionFacts& facts = t.facts;
  const StrategyParams& st = config_.strategy;
  const TransferFlight::Progress leg = transfer_.on_state(facts.odometry.p_O_m(), st.waypoint_tolerance_m, facts.now_ns);
  if (leg.arrived) {
    t.sticks.hover();
    if (last_shelf()) {
      return landing(Outcome::Completed,
                     std::string("passed the last shelf ") + (st.mode == Strategy::over_tops ? "over the top" : "around the end"));
    }
    return {.change = next_shelf("transfer done: finding shelf " + std::to_string(shelf_ + 1), t)};
  }
  if (leg.next_leg) facts.telemetry.event = "transfer waypoint " + std::to_string(transfer_.waypoint());
  t.sticks.set(transfer_velocity(config_, leg.e_O_m, facts.state->yaw_rad, transfer_.hold_yaw_O_rad()), facts.now_ns);
  Decision d;
  d.rc = RcSend::Due;
  return d;
}

}  // namespace shelfcross::flight_sw
