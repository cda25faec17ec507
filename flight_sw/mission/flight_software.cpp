#include "flight_sw/mission/flight_software.hpp"

#include <algorithm>
#include <utility>

namespace shelfcross::flight_sw {

namespace {

FlightConfig validated(FlightConfig c) {
  validate_flight_config(c);
  return c;
}

}  // namespace

FlightSoftware::FlightSoftware(FlightConfig config)
    : config_(std::make_shared<const FlightConfig>(validated(std::move(config)))),
      commands_(*config_),
      sticks_(*config_),
      video_(*config_),
      shelves_(*config_) {}

// ---- Entry points ----

std::vector<SdkCommand> FlightSoftware::start(TimeNs t_ns) {
  std::vector<SdkCommand> out;
  if (facts_.phase.current() != Phase::Idle) return out;
  facts_.now_ns = t_ns;
  facts_.started_ns = t_ns;
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
        if constexpr (std::is_same_v<T, SdkReply>) {
          take(decided(commands_.on_reply(m, facts_)));
        } else if constexpr (std::is_same_v<T, StateRecord>) {
          facts_.on_state(m);
          sticks_.on_state(m);
          const StickResponse& response = sticks_.response();
          facts_.telemetry.control.sticks = response.estimates();
          if (const std::optional<StickAxis> axis = response.engaged()) {
            facts_.telemetry.event = stick_scaling_event(*axis, response);
          }
          take(shelves_.on_state(m, {facts_, sticks_}));
        } else if constexpr (std::is_same_v<T, CameraFrame>) {
          on_frame(m);
        }
        // ClockTick: only the timers below.
      },
      input);
  take(decided(commands_.check_timeout(facts_)));
  if (facts_.phase.current() != Phase::Done) supervise();
  commands_.poll(facts_.now_ns, out_);
  facts_.telemetry.phase = facts_.phase.current();
  facts_.telemetry.control.velocity = sticks_.velocity();
  facts_.telemetry.link.stale_replies = commands_.stale_replies();
  facts_.telemetry.link.video_stalled = video_.stalled();
  facts_.telemetry.tracking.counts = shelves_.tracker().record().counts;
  return out_;
}

void FlightSoftware::on_frame(const CameraFrame& f) {
  const std::optional<Picture> taken =
      video_.take(f, facts_, [this] { return shelves_.decision_region_px(facts_.phase.current()); });
  if (!taken) return;  // the wrong size or type: counted, ignored
  const Picture& pic = *taken;
  if (!pic.decides && pic.damage_events > config_->perception.steer_max_damage_events) {
    ++facts_.telemetry.link.unflown_frames;
    if (vision_phase(facts_.phase.current())) shelves_.hold_or_hover(facts_, sticks_);
    if (facts_.phase.current() == Phase::WaitVideo) take(decided(commands_.take_off_if_ready(facts_)));
    else emit_rc(false);
    return;
  }
  if (facts_.phase.current() == Phase::WaitVideo) return take(decided(commands_.take_off_if_ready(facts_)));
  take(shelves_.on_picture(pic, {facts_, sticks_}), &pic);
  sticks_.controlled(facts_.now_ns);
  emit_rc(false);
}

// ---- Timers: failsafes, phase timeouts, keep-alive ----

void FlightSoftware::supervise() {
  // WaitVideo's and Land's timers; the other ground phases have none but their commands'.
  if (!airborne(facts_.phase.current())) return take(decided(commands_.supervise(facts_)));
  // The airborne phases' own timers, then the mission's failsafes.
  Decision timers = shelves_.supervise({facts_, sticks_});
  const bool supervised = timers.supervised;
  take(std::move(timers));
  if (supervised) return;
  // Low battery: land now, except in the crossing (finish it, then land beyond the shelf).
  if (facts_.phase.current() != Phase::Cross && facts_.state && facts_.state->battery_pct < config_->mission.low_battery_pct) {
    return take({.change = Landing{Outcome::Aborted, "low battery (" + std::to_string(facts_.state->battery_pct) + "%)"}});
  }
  // Video stall: the timers run on whatever input arrives (state records at 10 Hz).
  if (vision_phase(facts_.phase.current())) {
    const VideoStall stall = video_.stall(facts_);
    if (stall == VideoStall::Land) return take({.change = Landing{Outcome::Aborted, "video lost"}});
    if (stall == VideoStall::Hover) {
      sticks_.hover();
      emit_rc(true);
    }
  }
  // Keep-alive (and the steady rc while frames are missing).
  if (sticks_.keepalive_due(facts_.now_ns)) emit_rc(true);
}

// ---- Decisions and transitions ----

void FlightSoftware::take(Decision d, const Picture* pic) {
  RcSend rc = RcSend::None;
  for (;;) {
    rc = std::max(rc, d.rc);
    if (const Landing* landing = d.landing()) {
      // Sticks to zero before "land": no rc goes out while a command is outstanding, so if
      // "land" is lost the Tello would keep the last sticks (the crossing speed, say) until the
      // retry.
      sticks_.hover();
      emit_rc(true);
      commands_.landing(landing->outcome, landing->reason);
      enter(Phase::Land, "landing: " + landing->reason);
    } else if (const Transition* transition = d.transition()) {
      enter(transition->phase, transition->event);
    }
    if (!d.resume) break;
    d = shelves_.resume({facts_, sticks_}, pic);
  }
  if (rc != RcSend::None) emit_rc(rc == RcSend::Now);
}

// Every transition passes here: the table (mission/phases.cpp) says which are allowed; what
// every phase's start clears, then the phase's own entry (the SDK command it asks for).
void FlightSoftware::enter(Phase p, const std::string& event) {
  const Phase from = facts_.phase.current();
  facts_.phase.enter(p, facts_.now_ns);
  facts_.telemetry.phase = p;
  facts_.telemetry.event = event;
  shelves_.on_phase_change();
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

void FlightSoftware::emit_rc(bool force) {
  if (!airborne(facts_.phase.current()) || commands_.outstanding()) return;
  if (const std::optional<RcSticks> rc = sticks_.due(facts_.now_ns, force)) {
    facts_.telemetry.control.rc = *rc;
    out_.push_back({facts_.now_ns, rc->text()});
  }
}

// ---- The inventories ----

std::vector<BoxEntry> FlightSoftware::all_boxes() const {
  std::vector<BoxEntry> all;
  for (const Inventory& inv : finished_inventories()) {
    const auto b = inv.boxes();
    all.insert(all.end(), b.begin(), b.end());
  }
  const auto b = inventory().boxes();
  all.insert(all.end(), b.begin(), b.end());
  return all;
}

std::string FlightSoftware::inventory_json() const {
  if (config_->layout.shelf_count == 1) return inventory().to_json();
  std::string j = "{\"shelves\":[";
  for (const Inventory& inv : finished_inventories()) j += inv.to_json() + ",";
  return j + inventory().to_json() + "]}";
}

}  // namespace shelfcross::flight_sw
