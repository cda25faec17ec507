#include "flight_sw/mission/command_phases.hpp"

#include <cmath>

namespace shelfcross::flight_sw {

namespace {
// After a refused `land`: how long to watch the state height before asking again (the
// tello_pilot's own landing asks every 0.5 s too).
constexpr double kLandRefusedWait_s = 0.5;
// After every `takeoff` was refused: how long to watch the state height for a takeoff that is
// under way before saying the drone stayed on the ground. A Tello idles its motors about 1 s
// and climbs at about 0.45 m/s, so it passes airborne_height_m (0.3 m) about 1.7 s after the
// `takeoff` it took; the refusals come within 0.5 s of that first send.
constexpr double kTakeoffShowsWithin_s = 3.0;
}  // namespace

std::optional<Transition> CommandPhases::on_reply(const SdkReply& reply, MissionFacts& facts) {
  if (auto c = commands_.on_reply(reply)) return on_completion(*c, facts);
  return std::nullopt;
}

std::optional<Transition> CommandPhases::check_timeout(MissionFacts& facts) {
  if (auto c = commands_.check_timeout(facts.now_ns)) return on_completion(*c, facts);
  return std::nullopt;
}

std::optional<Transition> CommandPhases::on_completion(const MissionCommands::Completion& c, MissionFacts& facts) {
  // Asked again while retries remain (MissionCommands::retry), the event saying why.
  auto retried = [&](double timeout_s) {
    if (!commands_.retry(c.command, timeout_s)) return false;
    facts.telemetry.event = "'" + c.command + "' " + (c.timed_out ? "timed out" : "refused: " + c.reply) +
                            ", retry " + std::to_string(commands_.attempts());
    return true;
  };
  if (c.command == "command" || c.command == "streamon") {
    if (c.ok) {
      if (c.command == "command") return Transition{Phase::StartVideo, "SDK mode; starting video"};
      return Transition{Phase::WaitVideo, "video on; waiting for the first frame"};
    }
    if (!retried(config_.timeouts.command_reply_s)) {
      return abort_on_ground("'" + c.command + "' failed: " + (c.timed_out ? "no reply" : c.reply));
    }
  } else if (c.command == "takeoff") {
    const bool airborne_anyway = c.timed_out && facts.state &&
                                 facts.state->height_m > config_.mission.airborne_height_m;
    if (c.ok || airborne_anyway) return Transition{Phase::FindShelf, c.ok ? "airborne" : "airborne (takeoff reply lost)"};
    if (!retried(config_.timeouts.takeoff_reply_s)) {
      if (c.timed_out) return abort_on_ground("takeoff failed: no reply");
      // Every attempt refused. A Tello refuses `takeoff` while it is taking off, so a
      // duplicated datagram that started the takeoff has its `error` taken for this one's
      // reply and every retry refused too, while the drone climbs. Watch the state height
      // before saying the drone stayed on the ground (supervise).
      takeoff_refused_ = TakeoffRefused{c.reply, facts.now_ns};
      facts.telemetry.event = "'takeoff' refused (" + c.reply + "): watching the state height for a takeoff under way";
    }
  } else if (c.command == "land") {
    // The `ok` comes once the drone is down; if it was lost, a repeated `land` finds the drone
    // on the ground and gets `error`. The state height settles it, as for a takeoff whose reply
    // was lost: at or below airborne_height_m the drone is down. (A stale state record shows
    // the last height in flight, so it can only keep the flight software trying.)
    const bool down_anyway = !c.ok && facts.state && facts.state->height_m <= config_.mission.airborne_height_m;
    if (c.ok || down_anyway) {
      return finish_landing(true, c.ok ? "landed" : "landed (no `ok`: the state height says on the ground)");
    }
    if (!c.timed_out && !land_given_up(facts)) {
      // Refused in the air: the Tello refuses `land` while it is already landing (a duplicated
      // datagram started the landing, and its `error` was taken for this `land`'s reply) and,
      // now and then, with `error Not joystick`. Retrying at once would spend the retries in a
      // fraction of a second and give up on a drone that is coming down; instead wait
      // kLandRefusedWait_s watching the state height (supervise), then ask again, for up to
      // land_reply_s, the longest a landing may take.
      commands_.ask_again_at("land", config_.timeouts.land_reply_s, facts.now_ns + seconds_to_ns(kLandRefusedWait_s));
      facts.telemetry.event = "'land' refused in the air (" + c.reply + "): waiting for the state height";
    } else if (!(c.timed_out && retried(config_.timeouts.land_reply_s))) {
      result_.reason += "; land not acknowledged";
      return finish_landing(false, "land not acknowledged");
    }
  }
  return std::nullopt;
}

Transition CommandPhases::take_off_if_ready(const MissionFacts& facts) {
  if (facts.state && facts.state->battery_pct < config_.mission.takeoff_min_battery_pct) {
    return abort_on_ground("battery " + std::to_string(facts.state->battery_pct) + "% below the take-off minimum");
  }
  return Transition{Phase::TakeOff, "taking off"};
}

std::optional<Transition> CommandPhases::supervise(const MissionFacts& facts) {
  switch (facts.phase.current()) {
    case Phase::WaitVideo:
      if (facts.phase.elapsed_s(facts.now_ns) > config_.timeouts.video_start_s) {
        return abort_on_ground("no video after streamon");
      }
      return std::nullopt;
    case Phase::TakeOff: {
      // After every `takeoff` was refused (on_completion): up and vertically still on a fresh
      // state record, the takeoff that was under way has ended; still low after
      // kTakeoffShowsWithin_s, none was. Up but still climbing, wait on (a climb ends).
      if (!takeoff_refused_) return std::nullopt;
      const bool up = facts.state && facts.state->height_m > config_.mission.airborne_height_m;
      if (up && facts.state_fresh() && std::abs(facts.state->vz_H_mps) <= kVerticallyStill_mps) {
        return Transition{Phase::FindShelf,
                          "airborne (every `takeoff` refused, but the state height says up: a takeoff was under way)"};
      }
      if (!up && ns_to_seconds(facts.now_ns - takeoff_refused_->since_ns) > kTakeoffShowsWithin_s) {
        return abort_on_ground("takeoff failed: " + takeoff_refused_->reply);
      }
      return std::nullopt;
    }
    case Phase::Land:
      // Once `land` went out: down by a fresh state record (low and vertically still: a
      // landing drone passes airborne_height_m still descending). After a refused `land`
      // (on_completion) that ends the wait before it is asked again (MissionCommands::poll);
      // while the reply is outstanding it ends a landing whose `ok` was lost without waiting
      // out land_reply_s (10 s) for the timeout that would otherwise tell.
      if ((commands_.waiting() || commands_.outstanding()) && facts.state_fresh() &&
          facts.state->height_m <= config_.mission.airborne_height_m &&
          std::abs(facts.state->vz_H_mps) <= kVerticallyStill_mps) {
        return finish_landing(true, commands_.waiting()
                                        ? "landed (`land` refused while landing; the state height says on the ground)"
                                        : "landed (no `ok` yet: the state height says on the ground)");
      }
      return std::nullopt;
    default:
      return std::nullopt;
  }
}

void CommandPhases::landing(Outcome outcome, const std::string& reason) {
  pending_outcome_ = outcome;
  result_.reason = reason;
}

Transition CommandPhases::finish_landing(bool landed, const std::string& why) {
  result_.outcome = pending_outcome_;
  result_.landed = landed;
  commands_.cancel_wait();
  return Transition{Phase::Done, why};
}

bool CommandPhases::land_given_up(const MissionFacts& facts) const {
  // Refusals are waited out, not counted: the bound is the time a landing may take.
  return facts.phase.elapsed_s(facts.now_ns) > config_.timeouts.land_reply_s;
}

Transition CommandPhases::abort_on_ground(const std::string& reason) {
  result_ = {Outcome::Aborted, reason, false};
  return Transition{Phase::Done, "gave up on the ground: " + reason};
}

}  // namespace shelfcross::flight_sw
