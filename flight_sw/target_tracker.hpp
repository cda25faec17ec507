#pragma once
// The target tracker's identity check: which cell of the known shelf is the tracked
// box, from what one picture shows around it, not only from where the box was last seen.
//
// The tracker follows the four corner tags of a cell from frame to frame. A tag grid repeats
// itself: the corner tags of the neighbouring column or level give as good a pose as the
// target's (the state height catches a level; nothing caught a column), and after the target
// was lost, or when tags of a shelf behind are taken for the target's, the box can settle one
// column or level away. Crossing there is a collision. So the crossing needs the cell's
// identity, and identity comes from three places:
//   1. Continuity: the target chosen on a full view (every cell's grid position known) stays
//      identified as long as each accepted pose is compared with the one before it (the
//      pose-jump test of the approach). A gap (target lost, re-acquired, poses too far apart
//      in time to be compared) leaves it unidentified.
//   2. The shelf's edges: the known grid (pitches from the configuration), placed by the
//      pose, predicts where every tag of the shelf is in the picture and where the lattice's
//      continuation one pitch beyond each edge would be. Seeing the edge column (or level)
//      with its tags and the place beyond it empty counts the target's position from that
//      edge. A tag of front-shelf size where the grid should have ended, or tags missing where
//      it should go on, contradicts the hypothesis (a box slid toward or away from an edge).
//   3. The inventory: a marker (ArUco ID) seen whose box the inventory holds in a known cell
//      must lie in that cell as the pose projects it. One agreeing marker confirms; one
//      disagreeing contradicts.
// The row is also checked against the state height on every pose (TargetTracker::measure).
//
// Frames: the hypothesis' cell frame K (navigation.hpp): x into the shelf, y left, z up, origin
// the cell centre on the front bars' plane. The pose X_KC is the camera in K (OpenCV camera
// axes: x right, y down, z forward). A point p_K is seen at p_C = X_KC^-1 p_K, projected with
// the intrinsics and the distortion.
//
// What counts as a tag of the front shelf here: eq. 1 against the area a front tag would have
// at that point (f tag_size / z_C)^2, not against the largest tag in a window (a window can hold
// only tags of a shelf behind, the largest of which then passes eq. 1 against itself).

#include <array>
#include <numbers>
#include <optional>
#include <string>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/tracking.hpp>  // declares the trackers tracking_legacy.hpp derives from
#include <opencv2/tracking/tracking_legacy.hpp>

#include "flight_sw/config.hpp"
#include "flight_sw/inventory.hpp"
#include "flight_sw/line_hold.hpp"
#include "flight_sw/navigation.hpp"
#include "flight_sw/perception.hpp"
#include "shelfcross/sdk_messages.hpp"

namespace shelfcross::flight_sw {

enum class CellIdentity {
  Unknown,       ///< nothing in this picture says which cell it is (nor that it is wrong)
  Confirmed,     ///< counted from an edge or located by a known marker, nothing disagreeing
  Contradicted,  ///< the picture disagrees with the hypothesis: never cross on it
};
const char* cell_identity_name(CellIdentity identity);

/// The verdict on one picture and the evidence counted for it.
struct IdentityCheck {
  CellIdentity verdict = CellIdentity::Unknown;
  std::string why;             ///< the evidence that decided (for logs and refusals)
  int nodes_in_view = 0;       ///< grid tags the pose puts inside the picture
  int nodes_matched = 0;       ///< ... with a front-size tag observed there
  int nodes_missing = 0;       ///< ... without
  int beyond_in_view = 0;      ///< places one pitch beyond an edge inside the picture
  int beyond_occupied = 0;     ///< ... with a front-size tag observed there
  bool column_edge_seen = false;  ///< an edge column seen with the place beyond it empty
  bool level_edge_seen = false;   ///< an edge level alike
  int markers_agreeing = 0;    ///< inventory markers seen in their cell
  int markers_disagreeing = 0; ///< inventory markers seen in another cell
};

/// Where the check looks: the tags' image gate as a fraction of the smallest projected pitch,
/// the border margin in tag sides, and how many missing grid tags a picture may have (tags cut
/// by the picture border, a blob lost to noise) before the hypothesis is contradicted.
struct IdentityCheckParams {
  double node_gate_pitch = 0.3;    ///< an observed tag within this fraction of a pitch is at a node
  double border_tag_sides = 1.5;   ///< nodes closer than this to the border are not judged
  int max_missing_nodes = 1;
  double marker_cell_margin = 0.2; ///< a marker must be this fraction of a pitch inside its cell
};

/// Judges one picture: is the tracked box the cell `target` of the known shelf? `pose_K` is the
/// camera pose measured on the box's corner tags under that hypothesis, `tags` every tag blob
/// found in the picture (before any eq. 1; the check applies its own against the pose), and
/// `markers` the ArUco markers found in it; `inventory` the shelf's inventory (boxes by cell).
/// The verdict is Contradicted if any evidence disagrees, Confirmed if an edge was counted or a
/// marker agreed and nothing disagreed, Unknown otherwise.
IdentityCheck check_cell_identity(CellIndex target, const PoseEstimate& pose_K,
                                  const std::vector<TagBlob>& tags,
                                  const std::vector<MarkerSighting>& markers, const Inventory& inventory,
                                  const FlightConfig& config, const IdentityCheckParams& params = {});

/// The inputs of the crossing gate besides the pose.
struct CrossingGateInput {
  double pose_age_s = 0.0;        ///< now less the pose's frame time
  double still_for_s = 0.0;       ///< the pose's frame time less the last lateral command
  CellIdentity identity = CellIdentity::Unknown;  ///< the target's identity (never cross unless Confirmed)
  /// The vehicle's height above the target cell's centre now, m, from the state record: its
  /// height h less the cell centre's height in h's frame, measured in the approach. Empty when
  /// that was never measured (never crossed then).
  std::optional<double> height_above_cell_m;
  double vz_mps = 0.0;            ///< the state record's vertical speed (vgz), m/s, up positive
  /// What the blind crossing may add to the line's offsets (line_hold.hpp); not measured: the
  /// crossing is refused.
  LineHoldForecast line_hold;
};


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

/// Height above the take-off point of a cell's centre (the origin of K), from a pose that puts
/// the body z_K_m above it: the state's height h less z_K (K and G are parallel, so a grid pose's
/// height above the cell centre serves as well). Empty without a state record.
std::optional<double> cell_height_m(const std::optional<StateRecord>& state, double z_K_m);

/// Height above the take-off point of a point on the shelf's front at image row v_px, seen from
/// range_m in front of it: the state's height h plus range * tan(elevation), the elevation being
/// the row's angle above the optical axis, atan((cy - v) / fy), less the axis' tilt down (the
/// body's pitch from the state record plus the mount's). The body's roll is neglected (the cell
/// is near the image's vertical centre line). Empty without a state record.
std::optional<double> row_height_m(const FlightConfig& config, const std::optional<StateRecord>& state,
                                   double v_px, double range_m);

/// The pose's pitch agrees with the state record's within this (whole degrees in the record,
/// and a video latency newer than the picture), rad: its height is the level check's.
constexpr double kLevelPitchAgreement_rad = 3.0 * std::numbers::pi / 180.0;

/// The target cell's four corner tags (cell_corner_tags_K order) as seen from the camera of
/// `pose_K` (projected with the intrinsics and the distortion). Empty when a tag would lie
/// behind the camera.
std::optional<std::array<cv::Point2d, 4>> corners_seen_from(const FlightConfig& config, CellIndex cell,
                                                            const PoseEstimate& pose_K);

/// How far apart two poses of the target, a frame apart, may lie and still be one: the pose's
/// position error grows as R^2 sigma / (f L) with the range R (depth from the tags' apparent
/// size, lateral from the heading that four tags of spread L resolve), so the limit is
/// pose_jump_m at up to kPoseJumpRange_m and pose_jump_m (R / kPoseJumpRange_m)^2 beyond.
double pose_jump_limit_m(const MissionParams& mission, double range_m);
constexpr double kPoseJumpRange_m = 1.0;

/// How fast the state odometry's position drifts from the truth (integrated velocities in
/// whole cm/s, 10 Hz), m/s: the margin a pose carried by it gains per second.
constexpr double kOdometryDrift_mps = 0.05;

/// The tracked target: the cell chosen on a full view, its four corner tags followed from
/// picture to picture (fast pipeline: BoxTracker; reference: Median Flow), its pose in the cell
/// frame K checked for plausibility (jump, level) and its identity (above: kept by continuity,
/// judged by check_cell_identity when lost). The mission decides what to do with it (approach,
/// cross, back off, re-read); this holds what the target is and where it was last seen.
/// Every picture comes as a Picture (its stamp is the time of the step).
class TargetTracker {
 public:
  explicit TargetTracker(const FlightConfig& config) : config_(config) {}

  /// Counters for the telemetry (never reset).
  struct Counts {
    int rejected_poses = 0;       ///< implausible jumps of the target's pose, ignored
    int wrong_level_poses = 0;    ///< of which on another level's tags (state height disagrees)
    int behind_tags_dropped = 0;  ///< tags in the target's window too small for the front shelf
    int identity_checks = 0;      ///< pictures judged while the target was unidentified
    int hidden_target_pictures = 0;  ///< pictures whose damage hid the target (hidden_by_damage)
  };

  /// The target chosen on the full `view` of the picture `bgr` at `t_ns` (where every cell's
  /// grid position is counted from the edges: identified), `height_m` its centre's height above
  /// the take-off point on that view (cell_height_m; empty: the level is not checked).
  void choose(CellIndex cell, const ShelfView& view, const cv::Mat& bgr, TimeNs t_ns,
              const std::optional<double>& height_m);
  /// Forgets the target (a re-read of the shelf, the next shelf).
  void forget();

  /// Where the tracker puts the box in this picture, and whether it could (else: the last box).
  struct Prediction {
    cv::Rect2d box_px;
    bool tracker_ok = false;
  };
  /// Where the box is in `pic`. Within kMotionPredictAfter_s of the last pose, the box
  /// tracker's image velocity; later (damaged or tagless pictures in between), the last pose's
  /// corner tags projected after the vehicle's own motion since then (`odometry`, now), as the
  /// image velocity of a few pictures extrapolated over a gap throws the window off the tags.
  Prediction predict(const Picture& pic, const std::optional<OdometryFix>& odometry);
  static constexpr double kMotionPredictAfter_s = 0.1;  ///< three frame periods
  /// Looks for the target's four corner tags around `predicted`: tags in a window around it,
  /// eq. 1 inside the window, each corner the nearest tag to where the box puts it; the pose
  /// from them, if plausible (jump, level by `state`), becomes the target's. False: not found.
  /// A damaged picture whose guessed rows cross a corner tag (or lie where a missing corner
  /// should be) may show the tag where it was a few pictures ago: its pose only steers
  /// (pose_decides() false), and only if it agrees with the last pose carried to now by the
  /// state odometry; otherwise the picture hides the target (hidden_by_damage()).
  bool measure(const Picture& pic, const cv::Rect2d& predicted, TagDetector& detector,
               const std::optional<StateRecord>& state);
  /// After a measurement: the tracker follows the measured box (the reference pipeline's is
  /// re-seeded when it failed or drifted off the tags).
  void correct(const Picture& pic, const Prediction& prediction);
  /// The target lost: the nearest cell of the (possibly partial) grid of `view` near the last
  /// box whose corner tags give a plausible pose of the right level (measure's tests), so that
  /// a neighbour above or below is passed over.
  bool reacquire(const Picture& pic, const ShelfView& view, TagDetector& detector,
                 const std::optional<StateRecord>& state);
  /// Judges the target's identity on `pic` (every tag and marker of it) against the pose
  /// `pose_K`; a confirmation identifies the target again. The verdict is the caller's to act on.
  IdentityCheck check_identity(const Picture& pic, const PoseEstimate& pose_K, TagDetector& tag_detector,
                               MarkerDetector& marker_detector, const Inventory& inventory);

  const std::optional<CellIndex>& target() const { return target_; }
  const cv::Rect2d& box_px() const { return box_px_; }
  cv::Point2d box_centre_px() const;
  /// The last pose in K, and the last from a nearly whole picture (the crossing's) with its time.
  const std::optional<PoseEstimate>& pose_K() const { return pose_K_; }
  const std::optional<PoseEstimate>& decision_pose_K() const { return decision_pose_K_; }
  /// The last accepted pose came from a picture that decides with its corner tags clear of
  /// the damage: the crossing, the forward gain and the cell height may rest on it. False: it
  /// only steers (and feeds the line-hold monitor if its picture decides).
  bool pose_decides() const { return pose_decides_; }
  /// The last measure found nothing because the picture's damage hides the target: nothing is
  /// to be decided on it, and the target is not lost.
  bool hidden_by_damage() const { return hidden_by_damage_; }
  /// Where the vehicle's own motion has carried the target since the last pose, at most
  /// mission.coast_s after it (at `now_ns`): the carried pose and the box its corner tags
  /// make. Empty without odometry at both ends, later, or with a tag behind the camera.
  struct Carried {
    PoseEstimate pose_K;
    cv::Rect2d box_px;
  };
  std::optional<Carried> carried_target(TimeNs now_ns) const;
  TimeNs decision_pose_t_ns() const { return decision_pose_t_ns_; }
  /// A corner tag was about to leave the view on the last measurement.
  bool near_edge() const { return near_edge_; }
  CellIdentity identity() const { return identity_; }
  /// Since when the target is unidentified (empty while identified).
  const std::optional<TimeNs>& unidentified_since_ns() const { return unidentified_since_ns_; }
  /// The last successful measure found the target's continuity broken (identity to confirm).
  bool continuity_lost() const { return continuity_lost_; }
  /// Nearest tag behind the target seen through it, from the front tags, m.
  const std::optional<double>& behind_m() const { return behind_m_; }
  const Counts& counts() const { return counts_; }

 private:
  bool fast() const { return config_.perception.pipeline == PerceptionPipeline::fast; }
  void start_tracker(const cv::Mat& bgr, const cv::Rect2d& box, TimeNs t_ns);
  /// The last pose carried to the last prediction's odometry fix (pose_after_motion); empty
  /// without both fixes.
  std::optional<PoseEstimate> carried_pose() const;
  /// The picture hides the target (hidden_by_damage): counted; measure() returns false.
  bool hidden();

  FlightConfig config_;
  std::optional<CellIndex> target_;
  std::optional<double> target_height_m_;  ///< target cell centre above the take-off point (state h)
  cv::Ptr<cv::legacy::Tracker> tracker_;  ///< reference pipeline: Median Flow
  BoxTracker box_tracker_;                ///< fast pipeline: constant image velocity
  double tag_side_px_ = 0.0;              ///< mean side of the target's corner tags, last seen
  std::vector<cv::Point3d> pose_obj_;     ///< PnP buffers, reused
  std::vector<cv::Point2d> pose_img_;
  std::vector<TagBlob> roi_tags_;         ///< the window's tags, reused
  cv::Rect2d box_px_;                     ///< tracked box: corner tag centres +- half a tag
  std::array<cv::Point2d, 4> corner_px_;  ///< last measured corner tag centres
  std::optional<PoseEstimate> pose_K_;    ///< last pose in the cell frame
  TimeNs pose_t_ns_ = 0;                  ///< when the frame of pose_K_ was received
  std::optional<PoseEstimate> decision_pose_K_;  ///< last pose from a nearly whole picture
  TimeNs decision_pose_t_ns_ = 0;
  bool pose_decides_ = false;             ///< see pose_decides()
  bool hidden_by_damage_ = false;         ///< see hidden_by_damage()
  bool near_edge_ = false;                ///< a corner tag was about to leave the view
  // Identity: confirmed on the full view the target was chosen on and kept while every
  // accepted pose follows the last identified one (mission.identity_continuity_s).
  CellIdentity identity_ = CellIdentity::Unknown;
  TimeNs identity_vouched_ns_ = 0;        ///< the last picture that kept or confirmed it
  std::optional<cv::Rect2d> vouched_box_px_;  ///< the target's box on that picture
  std::optional<TimeNs> unidentified_since_ns_;
  bool continuity_lost_ = false;
  std::vector<TagBlob> frame_tags_;       ///< identity check buffers
  std::vector<MarkerSighting> frame_markers_;
  std::optional<double> behind_m_;        ///< nearest tag behind the target seen through it, from the front tags, m
  std::optional<OdometryFix> odometry_now_;      ///< at the last prediction
  std::optional<OdometryFix> odometry_at_pose_;  ///< when pose_K_ was measured
  std::optional<cv::Rect2d> moved_box_px_;       ///< the last prediction by the vehicle's motion
  Counts counts_;
};

}  // namespace shelfcross::flight_sw
