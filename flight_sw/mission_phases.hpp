#pragma once
// The mission's phases and the transitions between them: the one table the mission's
// `enter` checks (FlightSoftware::enter throws std::logic_error on a transition not in it, a
// programming error). What each phase does is in flight_software.hpp; where each transition
// is taken, in the comment beside the table (mission_phases.cpp).

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

/// True when the mission may go from `from` to `to` (the table in mission_phases.cpp).
bool may_enter(Phase from, Phase to);

/// The phases flown in the air: the keep-alive, the battery and video failsafes run in them,
/// and leaving one for the ground goes through Land.
bool airborne(Phase phase);

/// The airborne phases that steer on pictures: all but the crossing (open loop) and the
/// transfer (odometry).
bool vision_phase(Phase phase);

}  // namespace shelfcross::flight_sw
