#pragma once
// Guidance: the control laws of the phases (docs/method.md sections 3-4), pure functions of
// the poses, the image measurements and the configuration to a VelocityCommand (control.hpp:
// body frame B, x forward, y left, z up, yaw rate CCW positive). The PI loops' states, the
// timers and the phase changes stay with the mission (flight_software.cpp), which calls these.
//
// Frames: the grid frame G and the cell frame K (navigation.hpp: x into the shelf, y left, z
// up); the odometry frame O (odometry.hpp). A heading yaw in a frame F turns a horizontal
// velocity of F into the body frame by R_z(-yaw) (to_body_xy).
//
// Lateral law sign (paper Fig. 19): see flight_software.hpp's header comment; the approach's
// laws here are eq. 10-15 with the psi that comment explains.

#include <optional>
#include <vector>

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include "flight_sw/config.hpp"
#include "flight_sw/control/control.hpp"
#include "flight_sw/navigation/navigation.hpp"
#include "flight_sw/navigation/odometry.hpp"
#include "flight_sw/perception/shelf_view.hpp"

namespace shelfcross::flight_sw {

/// R_z(-yaw) v_F: a horizontal velocity (or direction) of a frame F in the body frame of a
/// vehicle whose heading in F is yaw_F_rad (CCW positive). Keeps the norm.
Eigen::Vector2d to_body_xy(const Eigen::Vector2d& v_F, double yaw_F_rad);

/// v scaled down to |v| = max_norm when it is longer (direction kept).
Eigen::Vector3d capped(Eigen::Vector3d v, double max_norm);

// ---- FindShelf and GoToViewpoint ----

/// FindShelf on a fragment of the grid (`tags` not empty): centre it (yaw toward the tags'
/// mean column, climb toward their mean row) and back away while the shelf is too close to
/// fit the view: while its largest tag is bigger than a front tag seen from 1.2 times the
/// optimal viewpoint's range `viewpoint_range_m` (side f s / (1.2 D)). Beyond that, what keeps
/// the grid from being whole is not the range (tags of a shelf behind, a turned view) and
/// backing on would only meet the wall behind.
VelocityCommand fragment_velocity(const FlightConfig& config, const std::vector<TagBlob>& tags,
                                  double largest_tag_area_px, double viewpoint_range_m);

/// The viewpoint law: e1_G_m, from the current body position to the optimal viewpoint in G,
/// times viewpoint_kp, capped at viewpoint_speed_max_mps, flown in the body frame (R_z(-yaw)
/// v_G); the heading turned to the shelf normal (yaw_G 0), the rate saturated.
VelocityCommand viewpoint_velocity(const ControlGains& g, const Eigen::Vector3d& e1_G_m, double yaw_G_rad);

// ---- Approach (eq. 10-15, Fig. 19) ----

/// The approach's errors from the target box's centre in the image and the pose in K.
struct ApproachErrors {
  /// Vertical: dy_im = cy - v_box (pixels, > 0 when the target is above the principal point);
  /// e_z = dy_im * range / fy (metres, eq. 11 with k_e = fy / range).
  double e_z_m = 0.0;
  /// Heading: e_psi = atan(-(u_box - cx) / fx) (eq. 13-14 with k_dpsi = 1, > 0 when the target
  /// is left).
  double e_psi_rad = 0.0;
  /// Heading relative to the cell for the lateral law: the heading at which the cell is
  /// centred (the vehicle's heading plus the cell's remaining bearing in the image), i.e. the
  /// heading the yaw loop converges to. Using it rather than the vehicle's momentary heading
  /// keeps the yaw loop's lag (a second or more with the video latency) out of the lateral
  /// loop; with that lag the law pushed sideways the wrong way while the yaw caught up.
  double psi_cell_rad = 0.0;
  /// The range to the cell's tag plane by the pose (at least 5 cm), metres.
  double range_m = 0.0;
};
ApproachErrors approach_errors(const CameraIntrinsics& k, const cv::Point2d& box_centre_px,
                               const PoseEstimate& pose_K);

/// The lateral law (Fig. 19): vy_B = bang_off_bang(psi_cell, threshold, V_y), the threshold
/// psi_L or, closer than lateral_threshold_m / tan(psi_L), the bearing of lateral_threshold_m
/// across the line of sight, atan(lateral_threshold_m / range), whichever is wider.
double approach_lateral_mps(const ControlGains& g, const ApproachErrors& e);

/// What holds the forward speed of eq. 10 at 0.
struct ApproachHold {
  bool settled = false;   ///< still for settle_s, centred vertically and in heading
  bool in_cone = false;   ///< the line of sight within approach_cone_rad of the normal
  bool settling = false;  ///< inside commit_range_m and not yet settled
};
/// `still_s`: since the lateral law last commanded a speed and the heading last left its band
/// (CrossingGate::still_s); `range_x_m`: -x_K of the body.
ApproachHold approach_hold(const FlightConfig& config, const ApproachErrors& e, double still_s,
                           double range_x_m);

/// Forward at the constant xdot_0 (eq. 10) along the cell normal: held at 0 while `hold` (the
/// line of sight outside the approach cone, or, inside commit_range_m, until settled, so that
/// the crossing starts from a state the last pose describes, whatever the latency; settling is
/// given up after settle_hold_s and the crossing gate then decides). An unidentified target
/// (`identified` false) is never approached: back off along the normal (the other loops
/// keeping the box centred) so that the view widens until an edge or a known marker shows
/// which cell it is, no farther than the optimal viewpoint's range `viewpoint_range_m`.
double approach_forward_mps(const ControlGains& g, bool hold, bool identified, double range_x_m,
                            double viewpoint_range_m);

/// Backing off along the normal (crossing refused, corner tags gone off-centre): -back_off_speed.
VelocityCommand back_off_velocity(const ControlGains& g);

// ---- Crossing ----

/// How far past the back face the crossing ends: beyond_distance_m, or less where a shelf
/// stands behind (`behind_m`: the nearest tag seen behind through the cell, from the front
/// tags): the vehicle's front, plus what it drifts after the stop (stop_distance_m), must stay
/// short of it. Below min_beyond_distance_m the crossing is not to be flown.
double crossing_beyond_m(const FlightConfig& config, const std::optional<double>& behind_m);

/// How long a commanded turn goes on turning the heading after the pose it was judged on: the
/// pose is a video latency old (0.12-0.35 s, about 0.2 s typical) and the autopilot's yaw
/// reference lags the stick (a first-order response, its time constant unidentified; assumed
/// 0.3 s). The crossing holds the heading (yaw stick 0), so a turn rate r still commanded at
/// the gate leaves the vehicle r kHeadingCarry_s further round than its pose: 0.03 rad/s (two
/// yaw sticks) turns it 0.9 deg, and a body-frame line turned so is 1.8 cm off at 1.2 m.
constexpr double kHeadingCarry_s = 0.5;

/// The crossing, planned on the last pose.
struct CrossingPlan {
  Eigen::Vector2d dir_B = Eigen::Vector2d::UnitX();  ///< the line's horizontal part in B, |dir_B| = |d_xy|
  Eigen::Vector2d trim_B_mps = Eigen::Vector2d::Zero();  ///< added to the line's velocity (trim_crossing)
  CrossingEnd end;  ///< where it ends (odometry.hpp)
};
/// Along the crossing line (crossing_direction_K, navigation.hpp) at crossing_speed_mps,
/// heading held (yaw rate 0); the line in K turned into the body frame by the heading the
/// vehicle settles on once the yaw stick is released, v_B = R_z(-(yaw + r kHeadingCarry_s)) v_K
/// with r `yaw_rate_cmd_radps`, the heading law's command at the gate. Ended by distance flown,
/// not by time (crossing_flown): the line's horizontal length, distance / d_x along the normal
/// times |d_xy|, along the line's direction in the odometry frame O (the body direction turned
/// by the state heading `yaw_O_rad` and the same carried turn; the state's whole degrees hide
/// the latency's part of it), from `start_O_m`. Timed only as a fallback: at the speed the
/// vehicle really flies (the commanded one times `forward_gain`, measured in the approach; the
/// rc-to-speed gain of a Tello varies by tens of percent) plus the autopilot's lag (from rest,
/// a first-order response flies v (T - tau (1 - e^(-T/tau))) >= v (T - tau) in T). Timed
/// alone, a gain over-estimated by a fifth and the lag left a vehicle starting from rest 0.6 m
/// short, landing onto the back face's beam.
CrossingPlan plan_crossing(const FlightConfig& config, const PoseEstimate& pose_K, double yaw_rate_cmd_radps,
                           double beyond_m, double forward_gain, const Eigen::Vector2d& start_O_m, double yaw_O_rad);

/// The crossing's vertical speed: the cell centre's height `cell_height_m` held by the state
/// height h (control.hpp, height_hold_vz_mps, with crossing_kp_z and crossing_z_speed_max_mps).
double crossing_vz_mps(const ControlGains& g, double cell_height_m, double height_m);

/// A drift of `drift_y_mps` across the heading (the line hold's, line_hold.hpp) flown out: the
/// crossing asks the line's velocity less the drift, v_B - (0, d). The Tello then moves along the
/// line while its own estimate, and so the state odometry, moves along the commanded velocity
/// (a biased VPS hold flies the estimate): the odometry's axis, along which the watch measures
/// the offset and the progress, is turned by the angle between the two.
void trim_crossing(CrossingPlan& plan, const ControlGains& g, double drift_y_mps);

/// Horizontally along the line at crossing_speed_mps (plus the plan's trim), vertically
/// `vz_mps`, heading held.
VelocityCommand crossing_velocity(const ControlGains& g, const CrossingPlan& plan, double vz_mps);

// ---- Transfer between shelves (over_tops, around_ends) ----

/// Waypoints in the grid frame G of the shelf just read (x_G into the shelf, grid centre at the
/// origin), from the vehicle's visual position p_G_m at the viewpoint; the last one is the next
/// shelf's optimal viewpoint (`viewpoint_G_m` moved shelf_spacing_m along x_G), or past the last
/// shelf as far as a crossing ends.
std::vector<Eigen::Vector3d> transfer_waypoints_G(const FlightConfig& config, const Eigen::Vector3d& p_G_m,
                                                  const Eigen::Vector3d& viewpoint_G_m, bool last_shelf);

/// A P law toward the current waypoint (`e_O_m`: from the vehicle to it, in O), capped at
/// transfer_speed_mps, turned into the body frame by the state's heading `yaw_O_rad`; the
/// heading held on the shelf normal (`hold_yaw_O_rad`), the rate saturated.
VelocityCommand transfer_velocity(const FlightConfig& config, const Eigen::Vector3d& e_O_m, double yaw_O_rad,
                                  double hold_yaw_O_rad);

}  // namespace shelfcross::flight_sw
