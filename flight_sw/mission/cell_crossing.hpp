#pragma once
// The crossing of the target cell (flight_software.hpp, phase Cross): horizontally open loop
// along the line planned at the gate (guidance.hpp, plan_crossing), vertically the cell centre's
// height held by the state height, ended by the distance the state odometry has flown
// (odometry.hpp, crossing_flown); on each state record the in-crossing watch (line_hold.hpp)
// may stop it while the vehicle can still stop short of the front face. The crossing's own
// readings (crossing_readings.hpp) say where the Tello's hold has put it: a climb the height
// hold hides from h is held and judged at h less the hold's range offset, and with the VPS lost
// the odometry no longer measures the line: what it misses is flown blind at the speed the VPS
// read in this crossing, and the crossing is never stopped on it. The mission keeps the phase
// and flies what this says.

#include <optional>
#include <string>

#include "flight_sw/config.hpp"
#include "flight_sw/control/control.hpp"
#include "flight_sw/guidance/crossing_readings.hpp"
#include "flight_sw/guidance/line_hold.hpp"
#include "flight_sw/mission/facts.hpp"
#include "flight_sw/navigation/odometry.hpp"

namespace shelfcross::flight_sw {

/// A crossing the gate let start (CrossingGate::judge): its end, the watch's plan, the cell
/// centre's height in the state height's frame it holds, the velocity it starts with, and the
/// event that announces it.
struct CrossingStart {
  CrossingEnd end;
  CrossingWatchPlan watch;
  double height_m = 0.0;
  VelocityCommand velocity;
  std::string event;
};

/// The in-crossing watch stopped the crossing: why, and how far it had flown in along its line.
struct CrossingStop {
  std::string why;
  double flown_in_m = 0.0;
};

class CellCrossing {
 public:
  /// `config` must be valid and outlive this (the mission's one configuration).
  explicit CellCrossing(const FlightConfig& config) : config_(config) {}

  /// The crossing `start` begins: its end, watch and height held from now on.
  void begin(const CrossingStart& start, TimeNs now_ns);
  /// True while a crossing holds its height (begun, not stopped).
  bool holding() const { return height_m_.has_value(); }
  /// Each state record of the crossing (requires holding()), before vz_mps and watch: the
  /// crossing's own readings; announces the first hold offset and VPS loss it reads.
  void on_state(const StateRecord& s, MissionFacts& facts);
  /// The vertical speed that holds the cell centre's height at the state height `height_m`
  /// less the hold's range offset read (its saturation widened by what that offset asks);
  /// requires holding().
  double vz_mps(double height_m) const;
  /// The watch on the state record `s` (requires holding()): the stop, counted in the
  /// telemetry, when the drift it shows would leave the opening; else nothing. Never with the
  /// VPS lost (the odometry cannot tell how far in the vehicle is).
  std::optional<CrossingStop> watch(const StateRecord& s, MissionFacts& facts) const;
  /// The line flown (crossing_flown) `elapsed_ns` into the crossing: by the odometry and what
  /// was flown blind (cell_crossing.cpp), timed where nothing tells.
  bool flown(TimeNs elapsed_ns, const MissionFacts& facts) const;
  /// The height hold ends (the crossing stopped, or the next shelf).
  void stop() { height_m_.reset(); }

 private:
  const FlightConfig& config_;
  CrossingEnd end_;                  ///< crossing_flown (odometry.hpp)
  CrossingWatchPlan watch_;          ///< line_hold.hpp
  std::optional<double> height_m_;   ///< the height the crossing holds, h's frame
  TimeNs started_ns_ = 0;
  CrossingReadings readings_;        ///< crossing_readings.hpp
  bool offset_told_ = false, vps_told_ = false;
};

}  // namespace shelfcross::flight_sw
