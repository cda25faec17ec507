#pragma once
// The mission's phases and the transitions between them: the one table the mission's
// `enter` checks (PhaseClock::enter throws std::logic_error on a transition not in it, a
// programming error), and the record of the phase the mission is in. What each phase does is in
// flight_software.hpp; where each transition is taken, in the comment beside the table
// (mission/phases.cpp).

#include "shelfcross/time.hpp"

namespace shelfcross::flight_sw {

enum class Phase {
  Idle,
  EnterSdk,
  StartVideo,
  WaitVideo,
  TakeOff,
  FindShelf,
  GoToViewpoint,
  TakeInventory,
  Approach,
  Cross,
  Transfer,  ///< over_tops / around_ends: flying the planned waypoints on odometry
  Land,
  Done
};
const char* phase_name(Phase phase);

/// True when the mission may go from `from` to `to` (the table in mission/phases.cpp).
bool may_enter(Phase from, Phase to);

/// The phases flown in the air: the keep-alive, the battery and video failsafes run in them,
/// and leaving one for the ground goes through Land.
bool airborne(Phase phase);

/// The airborne phases that steer on pictures: all but the crossing (open loop) and the
/// transfer (odometry).
bool vision_phase(Phase phase);

/// The phase the mission is in and when it began. Only the mission's `enter`
/// (FlightSoftware::enter) changes it; every unit reads it (MissionFacts::phase).
class PhaseClock {
 public:
  Phase current() const { return phase_; }
  /// How long the current phase has lasted at now_ns.
  TimeNs elapsed_ns(TimeNs now_ns) const { return now_ns - start_ns_; }
  double elapsed_s(TimeNs now_ns) const { return ns_to_seconds(elapsed_ns(now_ns)); }
  /// The phase becomes `to` from now_ns. Throws std::logic_error when the table (may_enter) has
  /// no transition from the current phase to `to` (a programming error); nothing changes then.
  void enter(Phase to, TimeNs now_ns);

 private:
  Phase phase_ = Phase::Idle;
  TimeNs start_ns_ = 0;
};

}  // namespace shelfcross::flight_sw
