#pragma once
// The crossing gate's law (flight_sw/README.md, "Crossing gate"): a pure function of the
// target's pose, the cell and what the state records and the approach measured, to a refusal
// or none. The mission's CrossingGate (mission/crossing_gate.hpp) gathers its inputs.

#include <deque>
#include <optional>
#include <string>
#include <utility>

#include "flight_sw/config.hpp"
#include "flight_sw/guidance/line_hold.hpp"
#include "flight_sw/navigation/cell_identity.hpp"
#include "flight_sw/navigation/navigation.hpp"
#include "shelfcross/cell_index.hpp"
#include "shelfcross/time.hpp"

namespace shelfcross::flight_sw {

/// The inputs of the crossing gate besides the pose.
struct CrossingGateInput {
  double pose_age_s = 0.0;        ///< now less the pose's frame time
  double still_for_s = 0.0;       ///< the pose's frame time less the last lateral command
  /// The pose's frame time less the start of the heading's still stretch (HeadingStretch,
  /// crossing_gate.hpp): negative when the heading has turned since the pose.
  double heading_still_for_s = 0.0;
  double yaw_rate_cmd_radps = 0.0;  ///< the heading law's command in effect (a turn the vehicle goes on with)
  CellIdentity identity = CellIdentity::Unknown;  ///< the target's identity (never cross unless Confirmed)
  /// The vehicle's height above the target cell's centre now, m, from the state record: its
  /// height h less the cell centre's height in h's frame, measured in the approach. Empty when
  /// that was never measured (never crossed then).
  std::optional<double> height_above_cell_m;
  /// The cell centre's height in the state height's frame (above the take-off point), for the
  /// climb a height hold that follows the range forecasts (range_hold_climb_m); empty: not
  /// measured (then neither is height_above_cell_m).
  std::optional<double> cell_centre_h_m;
  double vz_mps = 0.0;            ///< the state record's vertical speed (vgz), m/s, up positive
  /// What the blind crossing may add to the line's offsets (line_hold.hpp); not measured: the
  /// crossing is refused.
  LineHoldForecast line_hold;
  /// Since the last whole window of this target whose forecast left the line no room
  /// (CrossingGate::too_rough), s; empty: none did. A calm shorter than the blind crossing is
  /// refused.
  std::optional<double> calm_for_s;
};

/// The heading law turning the vehicle: |yaw_rate| above kp_psi * settle_psi_rad, what the law
/// asks for a heading error at the settling tolerance. A crossing started on such a command
/// goes on turning for about the autopilot's lag, and the blind line with it (the crossing
/// gate refuses it; the state's yaw shows a turn that has already happened: HeadingStretch).
bool heading_turning(const FlightConfig& config, double yaw_rate_radps);

/// The crossing gate (flight_sw/README.md): empty when the crossing of `target` from `pose_K`
/// may start, otherwise why not. Refused unless the cell's identity is confirmed; then on the
/// pose's age and stillness, the heading and where the crossing line meets the front and back
/// faces (the footprint crossing_margin_m inside the clear opening); then on the height the
/// state record gives now and where the vertical speed carries it (vz * vertical_lag_s): both
/// must leave the vehicle's height crossing_margin_m inside the opening between the beams,
/// since the pose is a video latency old and the crossing holds the height by the state; last
/// on the line-hold forecast: the line's offsets plus what the blind crossing may add to them
/// must leave the same margin (line_hold.hpp).
std::optional<std::string> crossing_refusal(const FlightConfig& config, CellIndex target,
                                            const PoseEstimate& pose_K, const CrossingGateInput& input);

/// How long the heading has held still, by the state record: the newest stretch of records
/// whose yaw stays within a band of `band_rad` (the SDK reports whole degrees: the band holds
/// one step of flicker). A heading turning at w leaves the band within band / w. A gap of more
/// than `max_gap_s` between records ends the stretch: nothing vouches for the heading across
/// a gap as long as the stillness it is to show (it may have turned and come back).
class HeadingStretch {
 public:
  HeadingStretch(double band_rad, double max_gap_s) : band_rad_(band_rad), max_gap_s_(max_gap_s) {}
  void on_state(TimeNs t_ns, double yaw_rad);
  /// The stretch's first record (0 before any record: nothing known to hold the heading back).
  TimeNs since_ns() const { return since_ns_; }

 private:
  double band_rad_, max_gap_s_;
  std::deque<std::pair<TimeNs, double>> yaw_;  ///< the stretch's records of the last kKeep_s, t and yaw
  TimeNs since_ns_ = 0;
};

}  // namespace shelfcross::flight_sw
