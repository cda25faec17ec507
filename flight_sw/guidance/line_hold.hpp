#pragma once
// Can the crossing's line be held? The crossing is horizontally blind: from the last picture
// that shows the cell's corner tags (0.5-0.9 m out) until the vehicle's rear leaves the back
// face, nothing but the Tello's own position hold keeps it on the line, and whatever pushes it
// sideways in that time (a gust, a draft that turns, an autopilot that holds poorly) carries
// it toward a post or a beam. So before committing, the flight software measures how much the
// vehicle wanders while it holds still in front of the cell, and forecasts what the blind
// crossing may add to the line's offset (docs/method.md section 7, "The line-hold gate"):
//
//   across     the target pose's position across the vehicle's heading (the mean yaw of the
//              stretch), y' = y_K cos(yaw) - x_K sin(yaw), and its height z_K, over samples
//              taken while no lateral command acted on the vehicle (the lateral law quiet for
//              settle_s: more than the video latency plus the autopilot's velocity lag), within
//              the last line_hold_window_s. A sample is a pose from corner tags clear of the
//              damage (measured: TargetTracker::pose_decides), or, on every other picture of
//              the approach, the last such pose carried to it by the state odometry
//              (pose_after_motion), for at most coast_s after it. A pose from tags that a
//              guessed band crosses is no sample: it is accepted anywhere within the jump
//              limit (6 cm inside 1 m) plus the odometry's drift of the carried pose, and
//              such poses widened the measured wander to 9-11 cm over a lossy link. What the odometry misses (a creep below the state's 0.05 m/s
//              rounding) the next measured pose shows, as a step the fit's slope and spread
//              take in. Across the heading, the approach's own forward creep moves nothing;
//   drift      the least-squares slope of y' over time: a steady drift nobody commanded (one
//              below the state record's 0.05 m/s rounding reads 0 there), and its standard
//              error (the residuals counted as n_eff independent ones: fit_line). The crossing
//              flies out what lies beyond the error (trim_drift, trim_crossing); the forecast
//              counts the whole drift either way;
//   wander     half the spread (max - min) / 2 of y' and z_K about their fitted lines;
//   speed      the largest across-line speed the state record showed in the same quiet
//              stretch (the state's velocities turned into the cell frame by the pose's yaw);
//   forecast   f_y = wander_y sqrt(T_blind / span) + |drift| T_blind + |v_across| kVelocityLag_s,
//              f_z = wander_z sqrt(T_blind / span),
//              span the quiet stretch's length, T_blind the blind crossing's duration. Over
//              times short against the disturbance's correlation time a push wanders like a
//              random walk, its spread growing as sqrt(t); beyond the autopilot's recovery time
//              it grows no more, so the square root is conservative there. A drift goes on for
//              the whole crossing. A speed seen carries the vehicle about v tau further before
//              the velocity loop turns it (as the gate's vertical_lag_s does for vz).
//   air        the window is 2.5 s of a gust process of about 1 s correlation: a lull in it
//              forecasts little. So the quiet state records' sideways speed (the heading
//              frame's, in the state's 0.1 m/s steps) is remembered over kAirMemory_s, through
//              the commands and re-reads that end a quiet stretch, and its rms sigma_v stands
//              for the push the air gives: the wander across is max(wander_y sqrt(T_blind /
//              span), kAirReach_s sigma_v). Calm air reads 0 (a quiet speed under 0.05 m/s
//              rounds to 0). kAirReach_s (2.5 s) is above the ratio of a crossing's push off
//              its line to the sigma_v before it on four of five crossings in strong gusts
//              (1.3 to 1.8 s); a lull over every quiet record reads 0 and is not caught
//              (docs/method.md section 7, "The air remembered").
//              The readings are the VPS's estimate, with its white noise (independent from one
//              record to the next: the VPS samples at 50 Hz, the state comes at 10 Hz), while the
//              air moves the vehicle over its correlation time (a second). So sigma_v^2 is the
//              mean product of consecutive records, v_i v_(i+1): the noise's products average to
//              0, the air's to its power (times its correlation over 0.1 s, 0.9 for a second's).
//              The mean square itself would read the noise as air: 0.04 m/s of it makes one
//              record in five read a 0.1 m/s step, sigma_v 0.046 m/s, a reach of 11.5 cm.
//   speed'     for the same reason the across-line speed is the largest mean of kSpeedRecords
//              consecutive quiet records (0.3 s, short against the air's second): one noisy
//              record reads 1/kSpeedRecords of its step.
//   error      the forecast's own error (LineHoldForecast::error_y_m): the pose's across the
//              line at the commit range (kPoseError_m), the air's reach at sigma_v plus one
//              standard error of its estimate less its reach at sigma_v, and the drift's
//              standard error times T_blind. The gate keeps
//              separation_min_m plus it clear (never less than crossing_margin_m).
//
// The gate (crossing_refusal) then requires the line's offset at either face plus the
// forecast to leave crossing_margin_m inside the opening; a quiet stretch shorter than
// line_hold_min_span_s, or with fewer than kLineHoldMinPoses samples or kLineHoldMinMeasured
// measured poses, measures nothing, and the crossing is refused ("line hold not measured").
//
// During the crossing (crossing_watch) the state record alone tells where the vehicle is: the
// odometry's offset from the line and its across-line speed, the height against the cell's.
// While the vehicle can still stop short of the front face, a forecast position that leaves
// less than separation_min_m plus the line's own error (kPoseError_m) clear stops it and backs
// it out; past that point stopping would
// leave it inside the frame, and it flies on (flight_sw/README.md, "The in-crossing watch").

#include <deque>
#include <optional>
#include <string>
#include <utility>

#include <Eigen/Core>

#include "flight_sw/config.hpp"
#include "flight_sw/navigation/navigation.hpp"
#include "flight_sw/navigation/odometry.hpp"
#include "shelfcross/sdk_messages.hpp"

namespace shelfcross::flight_sw {

/// Fewer quiet samples than this in the window measure no wander.
constexpr int kLineHoldMinPoses = 5;
/// Fewer measured poses than this among them measure no wander either: a line fitted through
/// two leaves them no residual, so three are the fewest whose spread about it shows anything
/// the camera saw (the carried samples between them show only what the odometry saw).
constexpr int kLineHoldMinMeasured = 3;
/// The crossing gate's refusals for the line's hold (their reasons begin so).
constexpr const char* kLineHoldNotMeasured = "line hold not measured";
constexpr const char* kLineCannotBeHeld = "line cannot be held";
/// The line's offset, not the air, leaves it no room: an arrival centred as the approach
/// settles would be held (crossing_refusal). The approach's to mend, as any off-centre arrival.
constexpr const char* kOffCentreForTheWander = "off-centre for the wander";
/// A crossing given up for the line's hold: the mission's reason begins so.
constexpr const char* kCrossingDeclined = "crossing declined: ";

/// What the quiet stretch before the crossing showed.
struct LineWander {
  int poses = 0;                ///< quiet samples in the window
  int measured = 0;             ///< of them poses measured (the others carried by the odometry)
  double span_s = 0.0;          ///< from the first quiet pose to the last
  double half_spread_y_m = 0.0;  ///< (max - min) / 2 of y' (across the heading) about its fitted line
  double half_spread_z_m = 0.0;  ///< (max - min) / 2 of z_K about its fitted line
  double drift_y_mps = 0.0;      ///< the fitted slope of y'
  double drift_error_y_mps = 0.0;  ///< its standard error (the residuals' correlation counted)
  double across_speed_mps = 0.0;  ///< largest |across-line speed| of quiet state records
  double air_rms_mps = 0.0;       ///< the air remembered (AirMemory::rms_mps)
  double air_error_mps = 0.0;     ///< its standard error (AirMemory::error_mps)
};

/// The forecast of what the blind crossing adds to the line's offset, m (file comment).
struct LineHoldForecast {
  bool measured = false;  ///< enough quiet samples and measured poses over line_hold_min_span_s
  double y_m = 0.0;
  double z_m = 0.0;
  double error_y_m = 0.0;  ///< the forecast's own error across (file comment, "error")
  double error_z_m = 0.0;  ///< and up: the pose's
  double span_s = 0.0;    ///< the quiet stretch it was measured on (at most line_hold_window_s)
  double air_rms_mps = 0.0;  ///< the air remembered, where its reach is the larger wander (else 0)
  /// The drift the crossing flies out, across the heading, m/s: the drift beyond one standard
  /// error, sign(d) max(0, |d| - se_d), with line_hold.trim_drift; else 0.
  double drift_trim_y_mps = 0.0;
};

/// The air remembered (file comment, "air"): the quiet state records' sideways speed of the
/// last kAirMemory_s, through every quiet stretch the line hold forgets.
constexpr double kAirMemory_s = 20.0;
/// Fewer remembered records than this (1 s of the state's 10 Hz) measure no air.
constexpr int kAirMinRecords = 10;
/// The air's reach: a vehicle whose quiet records show a sideways speed of rms sigma_v may be
/// carried kAirReach_s sigma_v across in the blind crossing (file comment, "air").
constexpr double kAirReach_s = 2.5;
/// Two remembered records at most this far apart are consecutive (the state's 10 Hz, one lost
/// between them at most): their product is a sample of the air's power (file comment, "air").
constexpr double kAirPairGap_s = 0.25;
/// The across-line speed is the largest mean of this many consecutive quiet records.
constexpr int kSpeedRecords = 3;
/// The pose's error across the line at the commit range (flight_sw/README.md, "Known
/// limitation": 1 cm for frontal and mildly turned views at 0.6-0.9 m).
constexpr double kPoseError_m = 0.01;

class AirMemory {
 public:
  /// A quiet state record at t_ns: its sideways speed (heading frame), m/s.
  void on_state(TimeNs t_ns, double vy_H_mps);
  /// The air's rms speed over the kAirMemory_s before now_ns: the root of the mean product of
  /// consecutive records (no more than kAirPairGap_s apart), which the readings' white noise
  /// does not enter (file comment, "air"); 0 with fewer than kAirMinRecords records or a
  /// negative mean.
  double rms_mps(TimeNs now_ns) const;
  /// The standard error of rms_mps: sqrt(P + se(P)) - sqrt(P), P the mean product and se(P)
  /// its standard error over the pairs (taken as independent); 0 where rms_mps measures none.
  double error_mps(TimeNs now_ns) const;

 private:
  struct Power {
    double mean = 0.0;    ///< of the products
    double standard_error = 0.0;  ///< of that mean
    bool measured = false;
  };
  Power power(TimeNs now_ns) const;
  std::deque<std::pair<TimeNs, double>> vy_;
};

/// Collects the quiet poses and state records of the approach (file comment).
class LineHoldMonitor {
 public:
  /// Forgets the quiet stretch (the air remembered stays: a command or a re-read does not
  /// change the air).
  void clear();
  /// The target pose of a nearly whole picture: body position p_K_m in the cell frame, taken at
  /// t_ns; `quiet`: no lateral command acted since settle_s before it. A loud pose ends the
  /// quiet stretch (forgets the poses before it). A measured sample.
  void on_pose(TimeNs t_ns, const Eigen::Vector3d& p_K_m, double yaw_K_rad, bool quiet);
  /// An approach picture at t_ns with the odometry fix then (none: the state is stale). A pose
  /// from clean corner tags (`clean_K`) is measured and, taken quiet with a fix, becomes the
  /// anchor; any other picture's sample is the anchor carried to the fix, for at most carry_s
  /// after it (file comment). A loud picture forgets the anchor too.
  void on_picture(TimeNs t_ns, const PoseEstimate* clean_K, const std::optional<OdometryFix>& fix, bool quiet,
                  double carry_s);
  /// The anchor carried to `fix` at t_ns, at most carry_s after it, and the anchor's time.
  std::optional<std::pair<PoseEstimate, TimeNs>> carried(TimeNs t_ns, const OdometryFix& fix, double carry_s) const;
  /// A state record; `quiet` as for poses. Its heading-frame velocity is turned into the cell
  /// frame by the last pose's yaw; only quiet records after the first quiet pose count. Every
  /// quiet record goes to the air remembered.
  void on_state(const StateRecord& s, bool quiet);
  /// The quiet stretch's wander, its poses no older than window_s before now_ns, and the air
  /// remembered at now_ns.
  LineWander wander(TimeNs now_ns, double window_s) const;

 private:
  struct Sample {
    TimeNs t_ns;
    double x_m, y_m, z_m, yaw_rad;
    bool measured;
  };
  struct Anchor {
    TimeNs t_ns;
    PoseEstimate pose_K;
    OdometryFix fix;
  };
  void add(TimeNs t_ns, const Eigen::Vector3d& p_K_m, double yaw_K_rad, bool quiet, bool measured);
  std::deque<Sample> poses_;
  std::optional<Anchor> anchor_;  ///< the last quiet pose from clean corner tags
  std::deque<std::pair<TimeNs, double>> across_mps_;  ///< quiet state records' across-line speed
  double yaw_K_rad_ = 0.0;
  AirMemory air_;
};

/// The forecast from a wander, for a blind crossing lasting blind_s.
LineHoldForecast forecast_line_hold(const MissionParams& m, const LineWander& w, double blind_s);

/// What the crossing keeps clear of the frame on each side beyond a forecast whose own error is
/// error_m: separation_min_m plus that error, and never less than crossing_margin_m.
double line_hold_keep_m(const MissionParams& m, double error_m);

/// The blind crossing's duration from a pose at range_m in front of the front face: until the
/// vehicle's rear leaves the back face at crossing_speed_mps.
double blind_crossing_s(const FlightConfig& config, double range_m);

/// The climb that a height hold following the range reading (height_hold_range_blend beta, its
/// time constant tau: config.hpp) forecasts in the crossing of `target`, whose centre is
/// cell_centre_h_m above the take-off point (the state height's frame, measured in the
/// approach): under the vehicle the range steps from the floor to the cell's bottom beam, at
/// most s = cell_centre_h_m less half the clear opening above the floor, and to what lies lower
/// behind it (the box of the cell below), for as long as the belly is over the shelf, T = (D +
/// L) / v. Taken at the highest step for all of T: beta s (1 - exp(-T / tau)). 0 for a fused
/// hold (beta 0).
double range_hold_climb_m(const FlightConfig& config, CellIndex target, double cell_centre_h_m);

/// The room the crossing's line leaves (the crossing gate's geometry): the tolerances on the
/// line's offsets at the faces, each the clear opening's half less the footprint's half (the
/// vehicle turned by its heading) less crossing_margin_m, and where the line meets the front
/// and back faces (cell frame K).
struct LineRoom {
  double room_y_m = 0.0;  ///< the clear opening's half less the footprint's half, across
  double room_z_m = 0.0;  ///< and up
  double tol_y_m = 0.0;   ///< room_y_m less crossing_margin_m
  double tol_z_m = 0.0;
  Eigen::Vector3d front_K_m = Eigen::Vector3d::Zero();
  Eigen::Vector3d back_K_m = Eigen::Vector3d::Zero();
  /// The larger |offset| of the line at the two faces, across and up.
  double offset_y_m() const;
  double offset_z_m() const;
};

/// The room the crossing line from `pose_K` through `target` leaves (the line: crossing_direction_K,
/// navigation.hpp).
LineRoom line_room(const FlightConfig& config, CellIndex target, const PoseEstimate& pose_K);

/// Where the crossing may still be stopped and what it must keep clear of, fixed at its start.
struct CrossingWatchPlan {
  double stop_before_m = 0.0;  ///< along the line: beyond this the vehicle's front would not stop short of the front face
  /// Across the line: from it to contact with a post, less separation_min_m and the line's own
  /// error (kPoseError_m).
  double slack_y_m = 0.0;
  double slack_z_m = 0.0;      ///< vertically: from the cell centre's height to a beam, less the same
};

/// The watch's plan from the crossing's room and its starting pose's body position p_K_m (in
/// the cell frame) on the line of direction d_K (crossing_direction_K).
CrossingWatchPlan plan_crossing_watch(const FlightConfig& config, const LineRoom& room, const Eigen::Vector3d& p_K_m,
                                      const Eigen::Vector3d& d_K);

/// The state record's verdict during the crossing.
struct CrossingWatchVerdict {
  bool back_out = false;
  double across_m = 0.0;       ///< forecast offset from the line (odometry + speed x lag)
  double height_m = 0.0;       ///< forecast height above the cell centre (state height + vz x lag)
};

/// During the crossing, on a fresh state record: p_O_m the odometry position, v_O_mps the
/// state's horizontal velocity in O, height_above_cell_m the state height less the cell
/// centre's, vz_mps the state's vertical speed. Backs out while the vehicle can still stop
/// short of the front face (its progress plus v kVelocityLag_s before plan.stop_before_m) and
/// the forecast leaves the slack.
CrossingWatchVerdict crossing_watch(const CrossingEnd& end, const CrossingWatchPlan& plan, const MissionParams& m,
                                    const Eigen::Vector3d& p_O_m, const Eigen::Vector2d& v_O_mps,
                                    double height_above_cell_m, double vz_mps);

/// For the reasons and events that give a forecast: " (the air remembered: 0.053 m/s rms)"
/// where the air's reach is its wander across, else empty.
std::string air_text(const LineHoldForecast& f);

/// A length for the reasons the gate and the watch give: "4.2 cm" (one decimal).
std::string centimetres_text(double length_m);

}  // namespace shelfcross::flight_sw
