#pragma once
// The facts the mission's units share on every input (flight_software.hpp): the time of the
// input being handled, the phase and since when, the last state record, the odometry
// integrated from the records, and the telemetry every unit writes. The mission owns one; each
// unit gets it per call.

#include <optional>

#include "flight_sw/mission/phases.hpp"
#include "flight_sw/mission/telemetry.hpp"
#include "flight_sw/navigation/odometry.hpp"
#include "shelfcross/sdk_messages.hpp"

namespace shelfcross::flight_sw {

/// A state record older than this is not the vehicle's height now (they come at 10 Hz).
constexpr double kStateFresh_s = 0.3;
/// The abort reason once the mission's time budget (timeouts.mission_s) is spent.
constexpr const char* kMissionTimeSpent = "mission time limit reached";

struct MissionFacts {
  TimeNs now_ns = 0;                 ///< the stamp of the input being handled (never decreasing)
  PhaseClock phase;                  ///< the phase now (only the mission's `enter` changes it)
  std::optional<StateRecord> state;  ///< the last state record
  StateOdometry odometry;            ///< frame O: the state records' velocities integrated, their height
  Telemetry telemetry;               ///< what the mission is doing, written by every unit
  TimeNs started_ns = 0;             ///< the mission's start (its time budget counts from it)

  /// A state record received: the odometry integrates it, it becomes the last one, the
  /// telemetry shows its battery and height.
  void on_state(const StateRecord& s) {
    odometry.on_state(s);
    state = s;
    telemetry.link.battery_pct = s.battery_pct;
    telemetry.link.height_m = s.height_m;
  }

  /// The mission's time budget (timeouts.mission_s from its start) spent.
  bool out_of_time(double mission_s) const { return ns_to_seconds(now_ns - started_ns) > mission_s; }

  /// A state record within kStateFresh_s of now.
  bool state_fresh() const {
    return state && ns_to_seconds(now_ns - state->t_ns) <= kStateFresh_s;
  }
};

}  // namespace shelfcross::flight_sw
