#pragma once
// The target's pose in its cell frame K: the poses accepted so far (TargetPoses), and the
// plausibility filter a new one passes first (judge_pose: jump, damage, level). The corner
// tags the pose is measured on: corner_tags.hpp; the tracker: target_tracker.hpp.

#include <deque>
#include <optional>

#include <opencv2/core.hpp>

#include "flight_sw/config.hpp"
#include "flight_sw/navigation/navigation.hpp"
#include "flight_sw/navigation/odometry.hpp"
#include "shelfcross/rotation.hpp"
#include "shelfcross/sdk_messages.hpp"

namespace shelfcross::flight_sw {

/// Height above the take-off point of a cell's centre (the origin of K), from a pose that puts
/// the body z_K_m above it: the state's height h less z_K (K and G are parallel, so a grid pose's
/// height above the cell centre serves as well). Empty without a state record.
std::optional<double> cell_height_m(const std::optional<StateRecord>& state, double z_K_m);

/// Height above the take-off point of a point on the shelf's front at image row v_px, seen from
/// range_m in front of it by a vehicle at height_m pitched pitch_rad: height_m plus range *
/// tan(elevation), the elevation being the row's angle above the optical axis,
/// atan((cy - v) / fy), less the axis' tilt down (the body's pitch plus the mount's). The
/// body's roll is neglected (the cell is near the image's vertical centre line).
double row_height_m(const FlightConfig& config, double height_m, double pitch_rad, double v_px, double range_m);

/// The pose's pitch agrees with the state records' (RecentStates::span) within this (whole
/// degrees in the record, and a video latency newer than the picture), rad: its height is then
/// the level check's.
constexpr double kLevelPitchAgreement_rad = deg_to_rad(3.0);

/// The state records that may describe the vehicle when a picture arriving at t was taken: a
/// video latency (0.1-0.35 s) before t, the records coming at 10 Hz, so those of
/// [t - kLevelWindow_s, t]. The level check judges a pose under each of them.
constexpr double kLevelWindow_s = 0.45;

/// The range of pitch and height over the state records of a window (RecentStates::span).
struct StateSpan {
  double pitch_min_rad = 0.0, pitch_max_rad = 0.0;
  double height_min_m = 0.0, height_max_m = 0.0;
};

/// The state records of the last second, for the level check's window.
class RecentStates {
 public:
  void on_state(const StateRecord& s);
  /// The span of the records of [t_ns - kLevelWindow_s, t_ns]; the newest record alone when none
  /// is that recent (a stale state); empty without a record.
  std::optional<StateSpan> span(TimeNs t_ns) const;

 private:
  std::deque<StateRecord> records_;
};

/// How far apart two poses of the target, a frame apart, may lie and still be one: the pose's
/// position error grows as R^2 sigma / (f L) with the range R (depth from the tags' apparent
/// size, lateral from the heading that four tags of spread L resolve), so the limit is
/// pose_jump_m at up to kPoseJumpRange_m and pose_jump_m (R / kPoseJumpRange_m)^2 beyond.
double pose_jump_limit_m(const MissionParams& mission, double range_m);
constexpr double kPoseJumpRange_m = 1.0;

/// How fast the state odometry's position drifts from the truth (integrated velocities in
/// whole cm/s, 10 Hz), m/s: the margin a pose carried by it gains per second.
constexpr double kOdometryDrift_mps = 0.05;

/// The target's accepted poses: the last one with its time and the odometry fix then, the last
/// from a nearly whole picture (the crossing's), and the odometry fix of the latest picture, by
/// which the last pose is carried to now.
class TargetPoses {
 public:
  /// The last pose in K, and the last from a nearly whole picture (the crossing's) with its time.
  const std::optional<PoseEstimate>& pose_K() const { return pose_K_; }
  const std::optional<PoseEstimate>& decision_pose_K() const { return decision_pose_K_; }
  TimeNs decision_pose_t_ns() const { return decision_pose_t_ns_; }
  /// The last accepted pose came from a picture that decides with its corner tags clear of
  /// the damage: the crossing, the forward gain and the cell height may rest on it. False: it
  /// only steers (and feeds the line-hold monitor if its picture decides).
  bool pose_decides() const { return pose_decides_; }
  /// When the picture of pose_K() was received.
  TimeNs pose_t_ns() const { return pose_t_ns_; }
  /// The odometry fix when pose_K() was measured.
  const std::optional<OdometryFix>& odometry_at_pose() const { return odometry_at_pose_; }

  /// The odometry fix of the picture now being measured (empty: none).
  void set_odometry_now(const std::optional<OdometryFix>& odometry) { odometry_now_ = odometry; }
  /// The last pose carried to the odometry fix now (pose_after_motion); empty without a pose
  /// or without both fixes.
  std::optional<PoseEstimate> carried_pose() const;
  /// `pose` accepted on the picture at `t_ns`; `decides`: see pose_decides().
  void accept(const PoseEstimate& pose, TimeNs t_ns, bool decides);
  /// No pose (the times and the odometry fixes are kept).
  void forget_poses();

 private:
  std::optional<PoseEstimate> pose_K_;    ///< last pose in the cell frame
  TimeNs pose_t_ns_ = 0;                  ///< when the frame of pose_K_ was received
  std::optional<PoseEstimate> decision_pose_K_;  ///< last pose from a nearly whole picture
  TimeNs decision_pose_t_ns_ = 0;
  bool pose_decides_ = false;             ///< see pose_decides()
  std::optional<OdometryFix> odometry_now_;      ///< at the last prediction
  std::optional<OdometryFix> odometry_at_pose_;  ///< when pose_K_ was measured
};

/// What the plausibility filter makes of a new pose.
enum class PoseVerdict {
  Plausible,
  Jumped,      ///< too far or too turned from the last pose: a wrong corner tag
  WrongLevel,  ///< the cell centre's height disagrees with the target's: another level's tags
  Hidden,      ///< from tags the damage touched, and not where the odometry carried the last pose
  /// Its level cannot be told: the target's under some of the window's records, another
  /// level's under others (the attitude or height changing within the video latency). Not a
  /// measurement, and not a sign that the target is lost.
  LevelUnsure,
};

/// A new pose of the target and what it was measured on.
struct PoseCandidate {
  const PoseEstimate& pose;
  TimeNs t_ns = 0;
  bool touched = false;            ///< a corner tag crossed by the picture's guessed rows
  cv::Point2d corners_centre_px;   ///< the mean of its four corner tags' centres
};

/// The plausibility filter (flight_sw/README.md, "Target pose plausibility", "Damaged pictures",
/// "The target's level"), in this order: the jump test against `history`'s last pose, the
/// agreement of a touched pose with the last pose carried by the odometry, and, with
/// mission.level_check and the target's centre height `target_height_m` known, the level by
/// the state records that may describe the picture (`states`, RecentStates::span).
PoseVerdict judge_pose(const FlightConfig& config, const PoseCandidate& candidate, const TargetPoses& history,
                       const std::optional<StateSpan>& states, const std::optional<double>& target_height_m);

}  // namespace shelfcross::flight_sw
