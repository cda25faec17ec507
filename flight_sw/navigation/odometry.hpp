#pragma once
// Odometry: where the vehicle is by the Tello's own state records, between the visual poses.
// Used where no picture shows the shelf: the crossing (its end, crossing_flown) and the
// transfer between shelves (its waypoints). Also the two state-side measurements the
// crossing needs from the approach: the speed the vehicle really flies per commanded speed
// (ForwardGainEstimator) and the target cell centre's height in the frame of the state height
// (CellHeightEstimator).
//
// Odometry frame O: fixed, x and y the integral of the state's heading-frame velocities turned
// by its yaw (from where the first record came), z the state's height above the take-off
// point (h). It inherits the SDK's 0.1 m/s velocity quantisation; the visual re-acquisition at
// every shelf removes its drift.

#include <optional>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "shelfcross/sdk_messages.hpp"

namespace shelfcross::flight_sw {

/// |vz| below half the SDK's 0.1 m/s step (vgz reads 0): vertically still.
constexpr double kVerticallyStill_mps = 0.05;
/// The autopilot's horizontal velocity lag assumed (a first-order response; the Tello's time
/// constant is unidentified, docs/tello_sdk.md: 0.3 to 0.7 s).
constexpr double kVelocityLag_s = 0.5;

/// Where the vehicle is by its own state records: StateOdometry's position in the odometry
/// frame O and the record's yaw (CCW, rad).
struct OdometryFix {
  Eigen::Vector3d p_O_m = Eigen::Vector3d::Zero();
  double yaw_O_rad = 0.0;
};

/// p_O integrated from the state records' heading-frame velocities.
class StateOdometry {
 public:
  /// p_O += R_z(yaw) v_H dt (rectangle rule on the newer record, dt at most 1 s), z = height.
  void on_state(const StateRecord& s);
  const Eigen::Vector3d& p_O_m() const { return p_O_m_; }

 private:
  std::optional<TimeNs> t_ns_;  ///< the newest record integrated
  Eigen::Vector3d p_O_m_ = Eigen::Vector3d::Zero();
};

/// The crossing's end: the line flown by the state odometry, timed only where nothing tells
/// how far it has flown.
struct CrossingEnd {
  TimeNs timed_ns = 0;  ///< timed: at the measured speed gain, plus the autopilot's lag
  double line_m = 0.0;  ///< the line's horizontal length, m
  Eigen::Vector2d start_O_m = Eigen::Vector2d::Zero();  ///< where it began, odometry frame O
  Eigen::Vector2d axis_O = Eigen::Vector2d::UnitX();    ///< the line's direction in O, unit
};

/// How far along the crossing's line the state odometry's `p_O_m` is from its start, m (p_O_m
/// advances on each state record by R_z(yaw) v_H dt).
double crossing_progress_m(const CrossingEnd& end, const Eigen::Vector3d& p_O_m);

/// The crossing is over when `progress_m`, the line flown as far as the state records tell
/// (the odometry's progress, and what the crossing's own readings add where the VPS read
/// nothing or the records are late: cell_crossing.hpp), has reached the line; with no progress
/// known, when its timed duration has passed; and at kCrossMaxOverTime times that in any case.
/// `elapsed_ns`: time since the crossing began.
bool crossing_flown(const CrossingEnd& end, TimeNs elapsed_ns, std::optional<double> progress_m);

/// The vehicle's forward speed per nominal stick speed, from the visual poses of the approach:
/// the distance flown along x_K since the first pose of the approach over the forward
/// displacement commanded in the same time, D(t) = integral of the commanded vx_B times the
/// horizontal sticks' scale (what a nominal Tello would have flown), taken lag_s earlier (the
/// pose shows the vehicle a video latency ago, and the vehicle follows the command after the
/// autopilot's velocity lag: 0.2 + 0.5 s assumed). Once D has grown by 0.8 m, a lag wrong by
/// 0.35 s moves the estimate by at most 0.25 m/s x 0.35 s / 0.8 m = 11 %; it is refined as D
/// grows. Clamped to 0.5..2; 1 until then.
class ForwardGainEstimator {
 public:
  /// Forgets the approach (a new target).
  void restart();
  /// On each approach frame, before the new command: the forward displacement commanded so
  /// far grows by the last command held since the last frame (`vx_B_mps`) times the
  /// horizontal sticks' scale it was sent at (`stick_scale`, StickResponse).
  void on_command_held(TimeNs t_ns, double vx_B_mps, double stick_scale);
  /// On a nearly whole picture's pose: the gain, once enough was commanded. `x_K_m`: the
  /// body's x in the cell frame.
  void on_pose(TimeNs t_ns, double x_K_m);
  /// Forward speed per nominal stick speed.
  double gain() const { return gain_; }
  /// Forward speed flown per commanded speed now: the gain times the sticks' last scale
  /// (what times the crossing).
  double speed_gain() const { return gain_ * stick_scale_; }

 private:
  double commanded_at(TimeNs t_ns) const;
  std::optional<std::pair<TimeNs, double>> start_;  ///< (t, x_K) of the approach's first pose
  std::vector<std::pair<TimeNs, double>> commanded_m_;  ///< (t, forward displacement commanded)
  std::optional<TimeNs> last_ns_;  ///< the approach's last frame
  double gain_ = 1.0;
  double stick_scale_ = 1.0;  ///< the horizontal sticks' scale at the last frame
};

/// The target cell centre's height in the frame of the state height h (the Tello's height
/// above its take-off point): h - z_K of the body, sampled on close poses of the approach
/// while the state shows the vehicle vertically still. The picture is a video latency
/// (0.1-0.35 s) older than the state record, so a sample is taken only while the state has
/// shown the vehicle vertically still for vertical_lag_s (then h has not changed since the
/// picture); the caller takes it only on nearly whole pictures, with a fresh state, and inside
/// commit_range_m (close in, the 4-tag pose's height is good to about 2 cm; far out its tilt
/// ambiguity moves it by decimetres). The last kCellHeightSamples count.
/// The cell centre's height above the take-off point from a pose: the state height less the
/// body's z_K (z_K = 0 at the cell centre; K and G are parallel).
inline double cell_centre_height_m(double state_height_m, double z_K_m) { return state_height_m - z_K_m; }

class CellHeightEstimator {
 public:
  /// On every state record: remembers the last one showing vertical motion.
  void on_state(const StateRecord& s);
  /// Whether the state has shown no vertical motion for `vertical_lag_s` up to `now_ns`.
  bool vertically_still_for(TimeNs now_ns, double vertical_lag_s) const;
  /// A sample: the state height less the body's z_K from the pose (z_K = 0 at the cell centre).
  void sample(double state_height_m, double z_K_m);
  void clear() { samples_m_.clear(); }
  /// The median of the samples (a wrong corner match or a damaged band moves one, not the
  /// median); empty with fewer than kMinCellHeightSamples: a picture or two is no measurement.
  std::optional<double> measured_m() const;

 private:
  std::vector<double> samples_m_;
  std::optional<TimeNs> vertical_motion_ns_;  ///< last state record showing vertical motion
};

}  // namespace shelfcross::flight_sw
