#pragma once
// The target tracker: the target cell chosen on a full view, its four corner tags followed
// from picture to picture (corner_tags.hpp), its pose in the cell frame K checked for
// plausibility (target_pose.hpp), its identity kept by continuity and judged on a picture when
// lost (cell_identity.hpp), the tags seen behind it; and the crossing gate on its pose.

#include <optional>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "flight_sw/config.hpp"
#include "flight_sw/navigation/cell_identity.hpp"
#include "flight_sw/navigation/corner_tags.hpp"
#include "flight_sw/navigation/navigation.hpp"
#include "flight_sw/navigation/target_pose.hpp"
#include "flight_sw/navigation/tracking_telemetry.hpp"
#include "flight_sw/perception/inventory.hpp"
#include "flight_sw/perception/shelf_view.hpp"
#include "shelfcross/sdk_messages.hpp"

namespace shelfcross::flight_sw {

/// Within this of the last pose the box is predicted by its image motion; later by the
/// vehicle's own motion (TargetTracker::predict): three frame periods.
constexpr double kMotionPredictAfter_s = 0.1;

/// What the tracker's last measure found beside the pose, and its counters for the telemetry
/// (never reset).
struct TrackerRecord {
  /// The last measure found nothing because the picture hides the target: its damage, or an
  /// attitude changing too fast within the video latency to tell the pose's level. Nothing is
  /// to be decided on it, and the target is not lost.
  bool hidden = false;
  std::optional<double> behind_m;  ///< nearest tag behind the target seen through it, from the front tags, m
  TrackerCounts counts;
  /// The picture's damage hides the target: counted; returns false (measure's result).
  bool hide() {
    hidden = true;
    ++counts.hidden_target_pictures;
    return false;
  }
  /// The pose's level cannot be told on this picture: counted; returns false.
  bool level_unsure() {
    hidden = true;
    ++counts.level_unsure_poses;
    return false;
  }
};

/// The tracked target: the cell chosen on a full view, its four corner tags followed from
/// picture to picture (fast pipeline: BoxTracker; reference: Median Flow), its pose in the cell
/// frame K checked for plausibility (jump, level) and its identity (cell_identity.hpp: kept by
/// continuity, judged by check_cell_identity when lost). The mission decides what to do with
/// it (approach, cross, back off, re-read); this holds what the target is and where it was last
/// seen. Every picture comes as a Picture (its stamp is the time of the step).
///
/// Made of its parts: the corner tags as last measured (CornerTags), the accepted poses
/// (TargetPoses) and the identity kept by continuity (TargetIdentity), read through corners(),
/// poses() and identification(); and the box follower, the corner tags' search and the
/// plausibility filter (judge_pose) it drives.
class TargetTracker {
 public:
  /// `config` must be valid and outlive this (the mission's one configuration, held by reference).
  explicit TargetTracker(const FlightConfig& config)
      : config_(config), follower_(config.perception.pipeline == PerceptionPipeline::fast) {}

  /// The target chosen on the full `view` of the picture `bgr` at `t_ns` (where every cell's
  /// grid position is counted from the edges: identified), `height_m` its centre's height above
  /// the take-off point on that view (cell_height_m; empty: the level is not checked).
  void choose(CellIndex cell, const ShelfView& view, const cv::Mat& bgr, TimeNs t_ns,
              const std::optional<double>& height_m);
  /// Forgets the target (a re-read of the shelf, the next shelf).
  void forget();

  /// Where the tracker puts the box in this picture, and whether it could (else: the last box).
  using Prediction = BoxPrediction;
  /// Where the box is in `pic`. Within kMotionPredictAfter_s of the last pose, the box
  /// tracker's image velocity; later (damaged or tagless pictures in between), the last pose's
  /// corner tags projected after the vehicle's own motion since then (`odometry`, now), as the
  /// image velocity of a few pictures extrapolated over a gap throws the window off the tags.
  Prediction predict(const Picture& pic, const std::optional<OdometryFix>& odometry);
  /// Looks for the target's four corner tags around `predicted`: tags in a window around it,
  /// eq. 1 inside the window, each corner the nearest tag to where the box puts it; the pose
  /// from them, if plausible (jump, level by the state records of the picture's latency in
  /// `states`), becomes the target's. False: not found.
  /// A damaged picture whose guessed rows cross a corner tag (or lie where a missing corner
  /// should be) may show the tag where it was a few pictures ago: its pose only steers
  /// (pose_decides() false), and only if it agrees with the last pose carried to now by the
  /// state odometry; otherwise the picture hides the target (TrackerRecord::hidden).
  bool measure(const Picture& pic, const cv::Rect2d& predicted, TagDetector& detector, const RecentStates& states);
  /// After a measurement: the tracker follows the measured box (the reference pipeline's is
  /// re-seeded when it failed or drifted off the tags).
  void correct(const Picture& pic, const Prediction& prediction);
  /// The target lost: the nearest cell of the (possibly partial) grid of `view` near the last
  /// box whose corner tags give a plausible pose of the right level (measure's tests), so that
  /// a neighbour above or below is passed over.
  bool reacquire(const Picture& pic, const ShelfView& view, TagDetector& detector, const RecentStates& states);
  /// Judges the target's identity on `pic` (every tag and marker of it) against the pose
  /// `pose_K`; a confirmation identifies the target again. The verdict is the caller's to act on.
  IdentityCheck check_identity(const Picture& pic, const PoseEstimate& pose_K, TagDetector& tag_detector,
                               MarkerDetector& marker_detector, const Inventory& inventory);

  const std::optional<CellIndex>& target() const { return target_; }
  /// The corner tags as last measured: the tracked box, its centre, whether a corner tag was
  /// about to leave the view (corner_tags.hpp).
  const CornerTags& corners() const { return corners_; }
  /// The last pose in K, and the last from a nearly whole picture (the crossing's) with its
  /// time; whether the last pose decides (target_pose.hpp).
  const TargetPoses& poses() const { return poses_; }
  /// The target's identity, since when it is unidentified, whether the last measure broke its
  /// continuity (cell_identity.hpp).
  const TargetIdentity& identification() const { return identification_; }
  /// What the last measure found beside the pose, and the counters.
  const TrackerRecord& record() const { return record_; }
  /// Where the vehicle's own motion has carried the target since the last pose, at most
  /// mission.coast_s after it (at `now_ns`): the carried pose and the box its corner tags
  /// make. Empty without odometry at both ends, later, or with a tag behind the camera.
  struct Carried {
    PoseEstimate pose_K;
    cv::Rect2d box_px;
  };
  std::optional<Carried> carried_target(TimeNs now_ns) const;

 private:
  /// Every tag and marker of a whole picture, for the identity check (buffers reused).
  struct PictureFeatures {
    std::vector<TagBlob> tags;
    std::vector<MarkerSighting> markers;
  };

  const FlightConfig& config_;  ///< the mission's one configuration (outlives this)
  std::optional<CellIndex> target_;
  std::optional<double> target_height_m_;  ///< target cell centre above the take-off point (state h)
  BoxFollower follower_;                   ///< the box by its image motion
  CornerTagSearch search_;                 ///< the corner tags found around a predicted box
  PictureFeatures features_;               ///< identity check buffers
  std::optional<cv::Rect2d> moved_box_px_; ///< the last prediction by the vehicle's motion
  CornerTags corners_;
  TargetPoses poses_;
  TargetIdentity identification_;
  TrackerRecord record_;
};

}  // namespace shelfcross::flight_sw
