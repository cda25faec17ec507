#pragma once
// Decision equivalence of the fast and the reference perception pipelines on a
// sequence of the benchmark frame set: both flight softwares get the same inputs (the
// SequencePlayer's), and after every frame their phase, target, rc commands, full-view state
// and inventory so far must be equal, their SI velocity commands within kVelocityTolerance and
// their poses (when both have one) within kPoseTolerance_m / _rad. (The poses agree to about
// 1e-14: the same tag centroids go into the PnP.)

#include <string>

#include "flight_sw/config.hpp"
#include "verification/frames/frame_set.hpp"

namespace shelfcross::frames {

inline constexpr double kPoseTolerance_m = 0.002;
inline constexpr double kPoseTolerance_rad = 0.002;
/// SI velocity commands before their rounding to rc sticks (which must be equal).
inline constexpr double kVelocityTolerance = 1e-6;

struct PipelineComparison {
  bool same = true;
  int frames = 0;
  int poses_compared = 0;
  double max_pose_diff_m = 0.0;
  double max_pose_diff_rad = 0.0;
  std::string target;     ///< fast pipeline's target ("L3 C3", or "none")
  std::string inventory;  ///< fast pipeline's inventory JSON
  std::string phases;     ///< "phase@frame ..." of the fast pipeline
  std::string summary;    ///< one paragraph for people
};

PipelineComparison compare_pipelines(const FrameSet& set, const std::string& condition,
                                     flight_sw::FlightConfig config);

/// Whole-frame tag detection of both pipelines on every frame of the set (stills included),
/// as the flight software uses it: the front-shelf tags after eq. 1 must be the same, in the
/// same order, with bit-identical centroids, areas and boxes. (Before eq. 1 the fast detector
/// may miss blobs with no solid stride x stride part, such as a tag cut to a sliver by the
/// image border or a bar: counted in `raw_missed`. Such a sliver is far below 45 % of a whole
/// tag's area, so eq. 1 drops it in both pipelines.)
struct TagComparison {
  bool same = true;
  int frames = 0, front_tags = 0, raw_missed = 0;
  std::string summary;
};

TagComparison compare_tag_detection(const FrameSet& set, flight_sw::FlightConfig config);

}  // namespace shelfcross::frames
