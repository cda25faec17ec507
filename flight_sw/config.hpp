#pragma once
// The flight software's configuration: what the operator knows about the shelf (its geometry,
// not where it stands), the camera, the perception thresholds, the control gains and the
// mission's timeouts and failsafes. Plain data with defaults (the paper's test shelf, Tello
// calibration A); read from YAML by load_flight_config / parse_flight_config (errors carry
// file:line), or built directly by code (the co-simulation builds it from a scenario) and then
// checked with validate_flight_config.
//
// YAML layout (every key optional unless marked required; see flight_sw/README.md):
//   shelf:      column_pitch_m [required], row_pitch_m [required], post_thickness_m,
//               beam_thickness_m, depth_m, tag_size_m, tag_offset_m, aruco_dictionary,
//               marker_size_m
//   camera:     width_px height_px fx_px fy_px cx_px cy_px k1 k2 p1 p2 k3
//   mount:      pitch_rad, p_BC_B_m [x, y, z]
//   perception: tag_hsv {hue_min hue_max sat_min sat_max val_min val_max}, min_tag_area_px,
//               min_fill_ratio, max_aspect_ratio, area_ratio_threshold,
//               grid_orthogonality_tolerance_rad, marker_area_ratio_threshold,
//               marker_min_agreeing_frames, inventory_frames, decide_max_damage_events,
//               steer_max_damage_events, roi_expand, corner_gate,
//               pipeline (fast | reference), tag_seed_stride_px
//   control:    forward_speed_mps kp_z ki_z z_integral_limit_m_s z_speed_max_mps kp_psi ki_psi
//               psi_integral_limit_rad_s yaw_rate_max_radps lateral_speed_mps
//               psi_lateral_threshold_rad lateral_threshold_m viewpoint_kp viewpoint_speed_max_mps viewpoint_yaw_kp
//               search_yaw_rate_radps back_off_speed_mps crossing_speed_mps max_control_dt_s
//               approach_cone_rad commit_range_m crossing_kp_z crossing_z_speed_max_mps
//               unsteered_hold_s
//   rc:         rc_per_mps_horizontal rc_per_mps_vertical rc_per_radps_yaw rc_period_s
//               keepalive_s
//   timeouts:   command_reply_s takeoff_reply_s land_reply_s command_retries command_gap_s
//               video_start_s find_shelf_s go_to_viewpoint_s take_inventory_s approach_s
//               target_lost_s back_off_s video_hover_s video_land_s mission_s
//   mission:    low_battery_pct takeoff_min_battery_pct airborne_height_m viewpoint_margin
//               viewpoint_position_tolerance_m viewpoint_yaw_tolerance_rad
//               viewpoint_settle_frames viewpoint_lost_s vehicle_size_m [x, y, z]
//               crossing_margin_m crossing_yaw_tolerance_rad crossing_attempts cross_range_max_m
//               beyond_distance_m edge_margin_px settle_s settle_z_m settle_psi_rad
//               settle_heading_band_rad settle_hold_s pose_fresh_s pose_jump_m pose_jump_rad pose_jump_window_s coast_s
//               identity_continuity_s identity_confirm_s identity_rereads stop_distance_m
//               min_beyond_distance_m level_check vertical_lag_s height_hold_range_blend
//               height_hold_time_constant_s line_hold_window_s
//               line_hold_min_span_s calm_wait_s give_up_clearance_m separation_min_m trim_drift
//   layout:     shelf_count shelf_spacing_m (required when shelf_count > 1)
//   strategy:   mode (through_cells | over_tops | around_ends) top_clearance_m end_clearance_m
//               transfer_speed_mps transfer_kp transfer_yaw_kp waypoint_tolerance_m transfer_leg_s

#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "sdk/command.hpp"
#include "shelfcross/camera.hpp"

namespace shelfcross::flight_sw {

/// The shelf as the operator measured it. Its position, and the height of its lowest beam
/// above the floor, are NOT known: the flight software navigates relative to the tag grid
/// only (levels are counted from the lowest tag row, which the full-view inventory sees).
struct KnownShelf {
  std::vector<double> column_pitch_m{0.34, 0.48, 0.34, 0.48};  ///< left to right on approach
  std::vector<double> row_pitch_m{0.34, 0.34, 0.34, 0.34};     ///< bottom to top
  double post_thickness_m = 0.02;
  double beam_thickness_m = 0.02;
  double depth_m = 0.34;        ///< front-face to back-face bar centre lines
  double tag_size_m = 0.06;     ///< side of the square colour tags
  double tag_offset_m = 0.01;   ///< tag face in front of the front bars' centre plane
  std::string aruco_dictionary = "DICT_4X4_50";
  double marker_size_m = 0.10;  ///< black border included

  int columns() const { return static_cast<int>(column_pitch_m.size()); }
  int levels() const { return static_cast<int>(row_pitch_m.size()); }
};

/// An HSV range in OpenCV's 8-bit units: hue 0..179 (degrees / 2), saturation and value
/// 0..255. hue_min > hue_max means the range wraps through red (e.g. 170..10).
struct HsvRange {
  int hue_min = 48;
  int hue_max = 85;
  int sat_min = 80;
  int sat_max = 255;
  int val_min = 30;  ///< loose: lighting changes move V far more than H and S
  int val_max = 255;
};

/// Two implementations of the same perception (perception/). `fast` is flown; `reference`
/// is the straightforward full-frame composition of OpenCV calls it replaced (HSV conversion
/// and connected components on every frame, Median Flow, ArUco over the whole image), kept as
/// the oracle that tests and `shelfcross frames --check` compare the fast one against: both
/// must decide the same (inventory, target, commands; poses within tolerance).
enum class PerceptionPipeline { fast, reference };

struct PerceptionParams {
  HsvRange tag_hsv;
  PerceptionPipeline pipeline = PerceptionPipeline::fast;
  /// Fast pipeline, whole frames: tag seeds are looked for every this many pixels along rows
  /// and columns (each blob found is then measured at full resolution). Exact for every blob
  /// holding a solid stride x stride square (any such square covers a sample): 4 keeps tags of
  /// 4 px and more, what a 6 cm tag is at 13 m, beyond any arena.
  int tag_seed_stride_px = 4;
  double min_tag_area_px = 12.0;     ///< smaller blobs are noise
  double min_fill_ratio = 0.40;      ///< blob area / bounding-box area (a 45 deg square: 0.5)
  double max_aspect_ratio = 3.0;     ///< bounding-box long side / short side
  double area_ratio_threshold = 0.45;  ///< eq. 1: R_A = S_T / L_T below this -> shelf behind
  double grid_orthogonality_tolerance_rad = 0.17;  ///< row vs column direction disagreement
  /// Markers smaller than this fraction of the area expected from the front tags' scale
  /// belong to a box behind the front shelf (eq. 1 applied to markers).
  double marker_area_ratio_threshold = 0.45;
  int marker_min_agreeing_frames = 3;  ///< N: frames that must agree on a cell's marker ID
  int inventory_frames = 5;            ///< full-view frames read before the inventory closes
  /// Damaged (error-concealed) pictures, by their lost bands since the key frame
  /// (CameraFrame::damage_events). Up to decide_max_damage_events a picture counts as whole
  /// enough to decide: reach the viewpoint, read the inventory (only whole pictures vouch for
  /// an empty cell), choose or re-acquire the target, commit to the crossing (on a pose from
  /// such a picture), fly the last centimetres before the tags leave the view. Up to
  /// steer_max_damage_events it only steers the loops; beyond, the vehicle hovers on it.
  int decide_max_damage_events = 1;
  int steer_max_damage_events = 8;
  /// A picture with more damage still decides (and steers) when the receiver placed its
  /// damage (CameraFrame::damaged_rows) and no damaged row lies within band_margin_px of the
  /// rows the decision rests on: the front shelf's tags while reaching the viewpoint and
  /// reading it, the target's tracked box during the approach. Its damaged rows are blanked
  /// first, so nothing is detected in them; only whole pictures still vouch for an empty
  /// cell. Negative: off.
  double band_margin_px = 32.0;
  double roi_expand = 0.6;   ///< approach search window: box grown by this fraction per side
  double corner_gate = 0.35;  ///< corner tag must lie within this fraction of the box size
};

struct ControlGains {
  double forward_speed_mps = 0.25;  ///< xdot_0, eq. 10
  double kp_z = 1.0;                ///< eq. 12, (m/s) per m
  double ki_z = 0.3;                ///< eq. 12, (m/s) per (m s)
  double z_integral_limit_m_s = 0.5;
  double z_speed_max_mps = 0.4;
  double kp_psi = 1.2;              ///< eq. 15, (rad/s) per rad
  double ki_psi = 0.2;
  double psi_integral_limit_rad_s = 0.5;
  double yaw_rate_max_radps = 0.8;
  double lateral_speed_mps = 0.08;          ///< V_y of the bang-off-bang law
  double psi_lateral_threshold_rad = 0.04;  ///< psi_L of the bang-off-bang law
  /// ... never narrower than this offset across the line of sight (guidance.cpp,
  /// approach_lateral_mps: a sideways step's coast ends inside the band).
  double lateral_threshold_m = 0.04;
  double viewpoint_kp = 0.8;                ///< (m/s) per m toward the optimal viewpoint
  double viewpoint_speed_max_mps = 0.4;
  double viewpoint_yaw_kp = 1.0;            ///< (rad/s) per rad toward facing the shelf
  double search_yaw_rate_radps = 0.3;       ///< yaw sweep while no tag is in view
  double back_off_speed_mps = 0.2;          ///< backing away to see a grid fragment whole
  /// Open-loop forward speed through the cell: the transfer's speed (TransferParams), so that
  /// the strategies fly their legs alike; docs/method.md section 7 derives what the gate and
  /// the in-crossing watch can do at it.
  double crossing_speed_mps = 0.4;
  /// Approach path perpendicular to the face (docs/method.md section 3): the forward speed xdot_0
  /// is flown only while the line of sight to the cell is within this angle of its normal;
  /// outside it the vehicle holds its range while the lateral law brings it onto the normal.
  double approach_cone_rad = 0.12;
  /// Settle before committing: inside this range the vehicle flies forward only while it is
  /// settled (see MissionParams::settle_s), so that the crossing starts from a still, centred
  /// state whatever the video latency. Must exceed the range at which the corner tags leave
  /// the view (about 0.55 m for 34 cm cells) plus the stopping distance.
  double commit_range_m = 0.95;
  double max_control_dt_s = 0.2;            ///< integrator step cap across frame gaps
  /// Height hold in the crossing (no picture shows the cell there): on every state record,
  /// vz = kp (z_cell - h) saturated to +-crossing_z_speed_max_mps, z_cell the cell centre's
  /// height in the frame of the state height h, measured in the approach (flight_sw/README.md).
  double crossing_kp_z = 1.0;               ///< (m/s) per m
  double crossing_z_speed_max_mps = 0.1;
  /// A picture that cannot steer (too damaged, or the target not in it) holds the last command
  /// for up to this long after it was set, then the vehicle hovers (FlightSoftware::
  /// hold_or_hover): snapping to hover on every such picture pitches the Tello back and forth.
  double unsteered_hold_s = 0.3;
};

/// Conversion between SI commands and the SDK's -100..100 sticks.
struct RcConversion {
  double rc_per_mps_horizontal = 100.0;
  double rc_per_mps_vertical = 100.0;
  double rc_per_radps_yaw = 66.7;
  double rc_period_s = 0.05;  ///< at most one rc per this period
  double keepalive_s = 1.0;   ///< an rc at least this often while airborne, frames or not
};

struct Timeouts {
  // The reply timeouts' defaults are the SDK's table (sdk::ReplyTimeouts).
  double command_reply_s = sdk::ReplyTimeouts{}.default_s;
  double takeoff_reply_s = sdk::ReplyTimeouts{}.takeoff_s;
  double land_reply_s = sdk::ReplyTimeouts{}.land_s;
  int command_retries = 3;       ///< attempts after the first
  double command_gap_s = 0.1;    ///< between two non-rc commands
  double video_start_s = 10.0;   ///< first frame after streamon
  double find_shelf_s = 30.0;
  double go_to_viewpoint_s = 40.0;
  double take_inventory_s = 15.0;
  /// The approach of one target, from entering it to the crossing. It hovers short of the
  /// cell whenever it cannot decide, and over a link losing 5-6 % of the video datagrams a
  /// picture clean enough to decide on comes only every few seconds (a 30-datagram key frame
  /// arrives whole one time in five or six): how long such approaches took to cross is in
  /// docs/results.md ("A lossy video link"). Past this it backs out and lands clear of the shelf.
  double approach_s = 70.0;
  double target_lost_s = 3.0;    ///< hovering to re-acquire the target, then backing out to re-read
  double back_off_s = 5.0;       ///< backing off an off-centre approach, then re-read the shelf
  double video_hover_s = 0.5;    ///< no frame for this long: hover
  double video_land_s = 3.0;     ///< no frame for this long: land
  /// The mission's time budget from its start (the first command): an operator's limit (the
  /// Tello flies about 13 min on a charge; the battery failsafe lands it at low_battery_pct).
  /// tello_pilot's shipped configuration gives it 110 s, what a campaign of the default
  /// scenario gives (verification's flight_config_for: cosim.timeout_s less 10 s).
  /// Once spent, the airborne mission gives up where that is safe: an approach backs out to
  /// land clear of the shelf, a re-read begun close to the shelf finishes backing out, a
  /// crossing is finished, a transfer flies its leg, the other phases land where they are (in
  /// front of a shelf or beyond it, never in it).
  double mission_s = 600.0;
};

/// Reaching and reading the optimal viewpoint (GoToViewpoint; mission: viewpoint_* keys).
struct ViewpointParams {
  double viewpoint_margin = 0.15;  ///< shelf extent grown by this fraction to fit the view
  double viewpoint_position_tolerance_m = 0.15;
  double viewpoint_yaw_tolerance_rad = 0.08;
  int viewpoint_settle_frames = 5;
  double viewpoint_lost_s = 2.0;   ///< full grid out of view this long: search again
};

/// The approach's settling and its last metres (mission: settle_*, edge_margin_px, coast_s,
/// cross_range_max_m).
struct ApproachParams {
  double cross_range_max_m = 0.9;  ///< tags leaving the view farther than this: lost, not close
  double edge_margin_px = 4.0;     ///< a tag this close to the border is leaving the view
  /// Settled: the lateral law has commanded 0 for this long (more than the video latency plus
  /// the autopilot's velocity time constant, so the last pose is not a moving one) ...
  double settle_s = 1.2;
  double settle_z_m = 0.03;        ///< ... and |e_z| is within this ...
  double settle_psi_rad = 0.04;    ///< ... and |e_psi| within this ...
  /// ... and the state record's yaw has stayed within a band this wide for settle_s: the
  /// open-loop crossing flies on the heading it starts with, judged on a pose a video latency
  /// old, so a heading still turning turns the blind line with it (docs/method.md section 7,
  /// "A still heading"). One step of the SDK's whole degrees (0.01745 rad), no more.
  double settle_heading_band_rad = 0.0175;
  double settle_hold_s = 10.0;     ///< holding short longer than this: go on anyway
  /// A pose from corner tags crossed by a damaged picture's guessed rows is compared with the
  /// last pose carried by the state odometry for at most this long after it (the odometry
  /// drifts about 5 cm/s); later such pictures hide the target until a clean one shows it.
  double coast_s = 1.5;
};

/// The target's pose plausibility and identity (mission: pose_jump_*, level_check,
/// identity_*).
struct TargetParams {
  /// A target pose farther than pose_jump_m (+ 1 m/s; grown as the range squared beyond 1 m,
  /// target_pose.hpp pose_jump_limit_m) or turned more than pose_jump_rad (+ 1 rad/s) from
  /// the last one, taken within pose_jump_window_s, is a wrong tag match.
  double pose_jump_m = 0.06;
  double pose_jump_rad = 0.12;
  double pose_jump_window_s = 0.5;
  /// The level check (every approach pose's cell height against the one measured when the
  /// target was chosen, from the state record's height). Always on in flight; off only for
  /// studies of what it prevents (a campaign over a lossy link then crosses at wrong levels).
  bool level_check = true;
  /// The target's identity (cell_identity.hpp): lost with the pose continuity, it is
  /// re-established while backing off along the cell normal (the view widening until an edge
  /// or a known marker is in it); not within identity_confirm_s, or contradicted, the shelf is
  /// re-read from the optimal viewpoint and the target chosen anew. A target lost for
  /// target_lost_s and an approach that could not centre are re-read the same way (backing
  /// straight out first); the identity_rereads+1-th doubt of any kind in a mission aborts it
  /// (backing out to give_up_clearance_m and landing there, in front of the shelf).
  /// Continuity: a pose within pose_jump_window_s of the last identified one keeps the
  /// identity; up to this time, only with the box found within 0.3 of its width of where it
  /// was last identified (target_tracker.cpp, TargetTracker::measure).
  double identity_continuity_s = 1.0;
  double identity_confirm_s = 10.0;
  int identity_rereads = 2;
};

/// The crossing gate and the crossing's end (mission: crossing_yaw_tolerance_rad,
/// crossing_attempts, pose_fresh_s, beyond_distance_m, stop_distance_m, min_beyond_distance_m,
/// vertical_lag_s).
struct CrossingParams {
  double crossing_yaw_tolerance_rad = 0.15;
  int crossing_attempts = 3;       ///< off-centre arrivals (each backed off) before re-reading the shelf
  /// The crossing is judged on a pose from a frame received at most this long ago.
  double pose_fresh_s = 0.25;
  double beyond_distance_m = 0.5;  ///< flown past the back face before landing
  /// The crossing's end with a shelf seen behind: the vehicle's front plus this (its drift after
  /// the stop: crossing speed x velocity lag, 0.375 m/s x 0.7 s, and the timing's error) stays
  /// short of the nearest tag behind; a crossing that would end less than
  /// min_beyond_distance_m past the back face is not flown (landing in front instead).
  double stop_distance_m = 0.4;
  double min_beyond_distance_m = 0.1;
  /// The autopilot's vertical lag assumed: a vertical speed vz carries the vehicle about
  /// vz * vertical_lag_s further after the command changes (a first-order response; the Tello's
  /// time constant is unidentified, docs/tello_sdk.md: 0.3 to 0.7 s horizontally). The crossing
  /// gate adds it to the state height; the approach's height samples wait this long after the
  /// state last showed vertical motion (the picture is a video latency older than the record).
  double vertical_lag_s = 0.5;
  /// The Tello's height hold as identified (`shelfcross identify`, docs/calibration.md): the
  /// share of a step of the range reading it follows (0: a fused hold that ignores it; 1: it
  /// climbs by the step) and the time constant it follows with. Inside a cell the range steps
  /// from the floor to the cell's bottom beam and the box below, and a hold that follows it
  /// climbs toward the beam above where no picture shows it: the crossing gate refuses a
  /// crossing whose forecast climb leaves no room (line_hold.hpp, range_hold_climb_m). 0 by
  /// default: a hold that follows the range must be identified to be flown around, and the
  /// in-crossing watch reads the climb on the state record (docs/method.md section 7).
  double height_hold_range_blend = 0.0;
  double height_hold_time_constant_s = 0.5;
};

/// The line-hold gate (line_hold.hpp, docs/method.md section 7): the wander of the quiet
/// stretch before the crossing is judged over at most line_hold_window_s, and only over a
/// stretch of line_hold_min_span_s or more; a forecast that leaves no room holds the vehicle
/// short of the cell, for up to calm_wait_s (then, as after crossing_attempts refusals of
/// the gate for it, the crossing is declined: the vehicle backs out to give_up_clearance_m
/// in front of the shelf by the last pose and lands there). calm_wait_s below settle_hold_s:
/// the hold for the air is given up with the settling's, and the gate then decides.
struct LineHoldParams {
  double line_hold_window_s = 2.5;
  double line_hold_min_span_s = 0.5;
  double calm_wait_s = 8.0;
  double give_up_clearance_m = 1.0;
  /// The separation minimum: no crossing is entered, or continued, where the forecast leaves
  /// less than this plus the forecast's own error clear of the frame (line_hold.hpp). The
  /// verifier's near miss (a scenario's cosim.near_miss_m) is the same 2 cm by default; the
  /// flight software cannot read the scenario, so it has its own.
  double separation_min_m = 0.02;
  /// The quiet stretch's drift flown out in the crossing, what of it lies beyond one standard
  /// error: its sticks ask the line's velocity less that (a biased VPS hold moves the vehicle at
  /// minus the bias, which no reading shows). The gate's forecast still carries the whole drift
  /// (line_hold.hpp, "drift").
  bool trim_drift = true;
};

/// The mission's parameters (the YAML section `mission`, its keys flat: config.hpp's key list),
/// grouped here by what they govern; the battery, take-off and landing limits and the vehicle's
/// size are the mission's own.
struct MissionParams {
  int low_battery_pct = 15;
  int takeoff_min_battery_pct = 25;
  double airborne_height_m = 0.3;  ///< a takeoff whose reply was lost counts above this, a land at or below
  Eigen::Vector3d vehicle_size_m = Eigen::Vector3d(0.098, 0.0925, 0.041);
  double crossing_margin_m = 0.03;  ///< kept clear on each side inside the opening
  ViewpointParams viewpoint;
  ApproachParams approach;
  TargetParams target;
  CrossingParams crossing;
  LineHoldParams line_hold;
};

/// The warehouse as the operator describes it: shelf_count shelves of the known geometry in a
/// row, parallel, facing the same way, one behind the other along the approach direction
/// (docs/method.md section 1). Their absolute positions stay unknown: each is found visually.
struct WarehouseLayout {
  int shelf_count = 1;
  double shelf_spacing_m = 0.0;  ///< front face to front face along the normal (> depth)
};

/// How the vehicle gets from one shelf's inventory to the next shelf (and past the last).
enum class Strategy {
  through_cells,  ///< the paper's method: approach an empty cell visually and cross it
  over_tops,      ///< climb above the shelf top (state height), fly over, descend
  around_ends,    ///< sideways past the shelf's nearer end, forward, back to the centre line
};
const char* strategy_name(Strategy strategy);
/// "through_cells", "over_tops", "around_ends"; empty for anything else.
std::optional<Strategy> parse_strategy(const std::string& name);

/// The conventional strategies' transfer: waypoints planned in the grid frame G from the last
/// visual pose at the viewpoint, flown on the Tello's own odometry (its state record's
/// velocities integrated, its height), then the next shelf re-acquired visually.
struct StrategyParams {
  Strategy mode = Strategy::through_cells;
  double top_clearance_m = 0.4;    ///< over_tops: vehicle bottom above the shelf's top tags
  double end_clearance_m = 0.5;    ///< around_ends: vehicle side beyond the grid's side edge
  double transfer_speed_mps = 0.4;
  double transfer_kp = 1.0;        ///< (m/s) per m toward the current waypoint
  double transfer_yaw_kp = 1.0;    ///< (rad/s) per rad: heading held on the shelf normal
  double waypoint_tolerance_m = 0.08;
  double transfer_leg_s = 40.0;    ///< a waypoint not reached in this time: land (aborted)
};

struct FlightConfig {
  KnownShelf shelf;
  CameraIntrinsics camera;
  CameraMount mount;
  PerceptionParams perception;
  ControlGains control;
  RcConversion rc;
  Timeouts timeouts;
  MissionParams mission;
  WarehouseLayout layout;
  StrategyParams strategy;
};

/// Reads a configuration file; throws config::ConfigError ("file:line: reason").
FlightConfig load_flight_config(const std::string& path);
/// Same from text; `name` stands for the file name in error messages.
FlightConfig parse_flight_config(const std::string& yaml_text, const std::string& name);
/// Checks a configuration built by code; throws std::invalid_argument naming the bad field.
/// (The YAML readers check the same through their bounds.)
void validate_flight_config(const FlightConfig& config);

}  // namespace shelfcross::flight_sw
