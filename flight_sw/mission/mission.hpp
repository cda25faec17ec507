#pragma once
// How the mission ends (Outcome, MissionResult), and what a unit's step decides: a transition
// (Transition), a landing (Landing), the rc to send (Decision). FlightSoftware is the mission
// (flight_software.hpp): it takes every decision in one place, and every phase is entered
// there (FlightSoftware::enter). The command phases (command_phases.hpp) return their
// transition, the airborne phases (airborne_phases.hpp) their Decision; none calls the
// mission back.

#include <optional>
#include <string>
#include <variant>

#include "flight_sw/mission/phases.hpp"

namespace shelfcross::flight_sw {

enum class Outcome {
  Running,
  Crossed,      ///< inventory taken, an empty cell crossed, landed beyond the shelf (every shelf)
  Completed,    ///< over_tops / around_ends: every shelf inventoried and passed, landed beyond
  NoEmptyCell,  ///< inventory taken, no crossable empty cell: landed in front of the shelf
  Aborted       ///< gave up (reason says why); landed if it had taken off
};
const char* outcome_name(Outcome outcome);

/// A phase to enter and the event the telemetry writes for it: what a unit's step decided,
/// taken by the mission (FlightSoftware::enter).
struct Transition {
  Phase phase = Phase::Idle;
  std::string event;
  bool operator==(const Transition&) const = default;
};

struct MissionResult {
  Outcome outcome = Outcome::Running;
  std::string reason;   ///< why it ended ("crossed cell L2 C3", "video lost", ...)
  bool landed = false;  ///< a land command was acknowledged (false if it never took off)
};

/// A landing decided: zero sticks sent at once (no rc goes out while `land` is outstanding),
/// then Land, the mission to end in `outcome` with `reason` once down.
struct Landing {
  Outcome outcome = Outcome::Aborted;
  std::string reason;
  bool operator==(const Landing&) const = default;
};

/// The rc datagram a step asks for once its decision is taken: none, when due, or now.
enum class RcSend { None, Due, Now };

/// What an airborne step decided, taken by the mission (FlightSoftware::take) in this order:
/// the landing or the transition; then, where `resume` says so, the rest of the step in the
/// phase entered (AirbornePhases::resume, whose decision is taken the same way); then the rc
/// (the most urgent asked along the way). Sent only airborne with no non-rc command
/// outstanding.
struct Decision {
  std::variant<std::monostate, Transition, Landing> change;
  bool resume = false;          ///< the step goes on once `change` is taken
  RcSend rc = RcSend::None;
  /// The airborne phases' timers (AirbornePhases::supervise) handled this input: the
  /// mission's own failsafes do not run after them.
  bool supervised = false;

  const Transition* transition() const { return std::get_if<Transition>(&change); }
  const Landing* landing() const { return std::get_if<Landing>(&change); }
};

/// A transition returned by a unit (or none), as a decision.
inline Decision decided(const std::optional<Transition>& t) {
  Decision d;
  if (t) d.change = *t;
  return d;
}

}  // namespace shelfcross::flight_sw
