#pragma once
// How the mission ends (Outcome, MissionResult), the transition a unit's step decides
// (Transition), and what the airborne units still ask of the mission in the middle of a step
// (Mission: a phase entered, a landing, the rc sent). FlightSoftware is the mission
// (flight_software.hpp): every phase is entered in one place, FlightSoftware::enter. The command
// phases (command_phases.hpp) return their transition and the mission takes it; the airborne
// phases (airborne_phases.hpp) call the mission where their step changes the phase.

#include <string>

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

/// The mission as its units see it: the transitions they take and the rc they send mid-step.
class Mission {
 public:
  /// Enters `phase`, `event` written to the telemetry: every phase's start clears its timers
  /// and restarts the PI loops, then the phase's own entry (the SDK command it asks for).
  /// Throws std::logic_error on a transition the table (mission/phases.cpp) lacks.
  virtual void enter(Phase phase, const std::string& event) = 0;
  /// Zero sticks sent at once (no rc goes out while `land` is outstanding), then Land, the
  /// mission to end in `outcome` with `reason` once down.
  virtual void land(Outcome outcome, const std::string& reason) = 0;
  /// Sends the sticks flown when an rc datagram is due (`force`: now), airborne and with no
  /// non-rc command outstanding; otherwise nothing.
  virtual void emit_rc(bool force) = 0;

 protected:
  ~Mission() = default;
};

}  // namespace shelfcross::flight_sw
