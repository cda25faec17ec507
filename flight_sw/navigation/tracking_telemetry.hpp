#pragma once
// The target as the approach tracks it, for the telemetry (mission/telemetry.hpp).

#include <optional>

#include <opencv2/core.hpp>

#include "flight_sw/navigation/cell_identity.hpp"
#include "shelfcross/cell_index.hpp"

namespace shelfcross::flight_sw {

/// The tracker's counters (never reset), kept by the tracker and shown as they are.
struct TrackerCounts {
  int rejected_poses = 0;      ///< implausible jumps of the target's pose, ignored
  int wrong_level_poses = 0;   ///< of which on another level's tags (state height disagrees)
  int level_unsure_poses = 0;  ///< poses whose level the state records of the video latency could not tell: held
  int behind_tags_dropped = 0; ///< tags in the target's window too small for the front shelf (eq. 1 against the tracked tags)
  int identity_checks = 0;     ///< pictures judged while the target was unidentified
  int hidden_target_pictures = 0;  ///< damaged pictures whose guessed rows hid the target's corner tags: held
};

/// The target as the approach tracks it (TargetTracker and the mission's approach).
struct TrackingTelemetry {
  std::optional<CellIndex> target;
  std::optional<cv::Rect2d> tracked_box_px;
  bool tracker_ok = false;
  CellIdentity target_identity = CellIdentity::Unknown;  ///< cell_identity.hpp
  int identity_contradictions = 0;  ///< of which disagreed with the target (re-read from the viewpoint)
  int shelf_rereads = 0;       ///< shelf re-read from the viewpoint because the target was in doubt
  TrackerCounts counts;        ///< the tracker's own (TargetTracker::record)
};

}  // namespace shelfcross::flight_sw
