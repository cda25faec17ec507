#pragma once
// The crossing gate's side of the approach (flight_software.hpp): what the approach measures
// for the crossing (the vehicle's lateral stillness, the line's hold by the LineHoldMonitor,
// line_hold.hpp; the cell centre's height in the state height's frame and the forward speed
// gain, odometry.hpp), when the air holds the vehicle short or declines the crossing, and the
// gate judged on the last deciding pose (crossing_refusal, crossing_law.hpp): a refusal, or
// the crossing to fly (cell_crossing.hpp).

#include <deque>
#include <optional>
#include <string>
#include <utility>

#include "flight_sw/config.hpp"
#include "flight_sw/guidance/crossing_law.hpp"
#include "flight_sw/guidance/line_hold.hpp"
#include "flight_sw/mission/cell_crossing.hpp"
#include "flight_sw/mission/facts.hpp"
#include "flight_sw/navigation/odometry.hpp"
#include "flight_sw/navigation/target_tracker.hpp"

namespace shelfcross::flight_sw {

/// The gate's verdict (CrossingGate::judge): exactly one of the three is set.
struct GateVerdict {
  std::optional<std::string> refusal;  ///< refused: why (the approach goes on)
  std::optional<std::string> no_room;  ///< clear, but no room behind the shelf to stop: land, this the reason
  std::optional<CrossingStart> start;  ///< clear: the crossing to fly
};

/// What the air leaves the line, inside commit_range_m (CrossingGate::too_rough).
struct RoughAir {
  bool hold_short = false;              ///< the forecast is not yet measured or leaves no room
  std::optional<std::string> declined;  ///< no room for calm_wait_s: the crossing declined, this the reason
};

class CrossingGate {
 public:
  /// `config` must be valid and outlive this (the mission's one configuration).
  explicit CrossingGate(const FlightConfig& config)
      : config_(config),
        heading_(config.mission.approach.settle_heading_band_rad, config.mission.approach.settle_s) {}

  /// A new target: its cell height, line hold and forward gain measured anew.
  void new_target();
  void clear_line_hold() { line_hold_.clear(); }  ///< the line hold measured anew (a re-read, a stopped crossing)
  void clear_cell_height() { cell_height_.clear(); }  ///< the cell height measured anew (a re-read, the next shelf)
  /// A phase change: the rough air's hold starts anew.
  void forget_rough() { rough_since_ns_.reset(); }

  /// The lateral law commanded a sideways speed at t_ns (stillness to be shown anew).
  void moved_sideways(TimeNs t_ns) { lateral_active_ns_ = t_ns; }
  /// Seconds the vehicle has been still: since the last sideways command and since the heading
  /// last left its band (HeadingStretch).
  double still_s(TimeNs now_ns) const { return ns_to_seconds(now_ns - still_since_ns()); }

  /// Each state record: the heading's stillness and the cell height's; in the approach
  /// (`approaching`), the line hold's across-line speed.
  void on_state(const StateRecord& s, bool approaching);
  /// Each approach picture: the forward command held since the last, and the horizontal
  /// sticks' scale it was sent at (StickResponse): the forward gain is measured against the
  /// sticks a nominal Tello would have answered, and the crossing is timed at that gain times
  /// the scale it flies at.
  void on_command_held(TimeNs now_ns, double vx_B_mps, double stick_scale) {
    forward_gain_.on_command_held(now_ns, vx_B_mps, stick_scale);
  }
  /// The monitor's sample of this approach picture (LineHoldMonitor::on_picture); `found`: the
  /// target was measured on it; `odometry`: the fix now (none: the state is stale).
  void on_picture(const MissionFacts& facts, const TargetTracker& tracker, bool found,
                  const std::optional<OdometryFix>& odometry);
  /// A deciding pose (TargetTracker::pose_decides): the forward gain and the cell height sampled.
  void on_deciding_pose(MissionFacts& facts, const PoseEstimate& pose_K);
  /// Inside commit_range_m with the identity confirmed: hold short while the forecast is not yet
  /// measured or leaves no room, or has left room for less than the blind crossing lasts since
  /// a whole window last left none; declined after calm_wait_s of that.
  RoughAir too_rough(MissionFacts& facts, const TargetTracker& tracker, const PoseEstimate& pose_K);
  /// The gate on the last deciding pose (requires one, and a target); `sticks`: the command in
  /// effect; `why_now` begins the crossing's event.
  GateVerdict judge(MissionFacts& facts, const TargetTracker& tracker, const VelocityCommand& sticks,
                    const std::string& why_now);

 private:
  TimeNs still_since_ns() const { return std::max(lateral_active_ns_, heading_.since_ns()); }
  bool quiet_at(TimeNs t_ns) const;
  LineHoldForecast forecast(MissionFacts& facts, const PoseEstimate& pose_K);
  PoseEstimate gate_pose(MissionFacts& facts, const TargetTracker& tracker, CrossingGateInput& gate);

  const FlightConfig& config_;
  TimeNs lateral_active_ns_ = 0;          ///< last time the lateral law commanded a speed
  HeadingStretch heading_;                ///< since when the state's yaw has held still
  LineHoldMonitor line_hold_;             ///< line_hold.hpp
  std::optional<TimeNs> rough_since_ns_;  ///< held short since then: the forecast left no room
  std::optional<TimeNs> rough_seen_ns_;  ///< the last whole window of this target that left the line no room
  ForwardGainEstimator forward_gain_;     ///< forward speed per nominal stick speed, for timing the crossing
  CellHeightEstimator cell_height_;       ///< the target cell centre's height in the frame of the state height h
};

}  // namespace shelfcross::flight_sw
