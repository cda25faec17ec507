#pragma once
// The simulated Tello's autopilot parameters (plant/params.hpp AutopilotParams, the ones a
// campaign disperses: verification/scenario/dispersion.hpp) identified from one flight record.
//
// Axes (sticks as the SDK names them; the state record in this project's frames):
//   forward  stick b -> vx_H (state vgx), observed directly
//   lateral  stick a -> vy_H = -a (right stick, left positive), observed directly
//   vertical stick c -> height h, observed through the integral (cm resolution)
//   yaw      stick d -> yaw rate = -d (clockwise stick, counter-clockwise positive),
//            observed through the unwrapped heading (degree resolution)
// State records are fitted at their send times as far as the log tells them (state_send_times):
// a record is stamped when it was read, which a busy computer or a link's queue can make
// several periods late.
// Each axis is fitted (response_fit.hpp) on the windows where its stick moved: from 1 s before
// the first deflection to 3 s after the last, windows closer than 3 s merged; only while
// flying free (after the takeoff's `ok`, before the first `land`). An axis whose stick never
// moved by at least min_stick, or with fewer than min_samples state records in its windows,
// is not identified (and says why). Height and heading, observed through their integrals, get
// an offset per pulse or doublet (from the middle of the hover before it to the middle of the
// hover after it), the velocities none.
//
// The scenario's parameters follow from the axes:
//   rc_horizontal_mps_at_100   forward and lateral gains, inverse-variance weighted
//   velocity_time_constant_s   forward and lateral time constants, likewise
//   rc_vertical_mps_at_100, vertical_time_constant_s, rc_yaw_radps_at_100, yaw_time_constant_s
//   rc_gain_scale              every identified gain over the scenario's nominal of its axis,
//                              weighted (the campaign scales all axes by one number)
//   response_delay_s           the dead time d, one for all axes (the link's: the command's way
//                              to the drone and the state record's way back; the onboard lags
//                              are the tracking loops'): the inverse-variance weighted
//                              combination of the four axes' own dead times; the height and
//                              heading axes are then refitted with it (and with its bootstrap
//                              replicates). Not a scenario parameter: the co-simulation builds
//                              it from its links.
// The Tello's senses (senses_fit.hpp) come from the same record: the still hover and the board
// pass of the calibration's senses block.
// A combination is formed replicate by replicate from the axes' bootstrap replicates (the axes'
// resamplings are independent), so its interval is again a bootstrap percentile interval.

#include <array>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "identify/flight_record.hpp"
#include "identify/response_fit.hpp"
#include "identify/senses_fit.hpp"
#include "plant/params.hpp"

namespace shelfcross::identify {

enum class Axis { forward, lateral, vertical, yaw };
inline constexpr std::array<Axis, 4> kAxes = {Axis::forward, Axis::lateral, Axis::vertical, Axis::yaw};
const char* axis_name(Axis axis);
/// The stick's name and unit of the axis's gain, for people ("m/s at full stick", ...).
const char* axis_gain_unit(Axis axis);

/// The model-error allowance, relative to the value: a bias bound for what no resampling of
/// this record shows, combined with each axis's bootstrap interval as an independent uniform
/// error (root sum of squares; Interval::margin). Its parts, measured on noise-free records
/// (docs/calibration.md, "The model's own error"): the linearised loops against the full plant
/// flying the calibration manoeuvre through `shelfcross plant` (rotor dynamics, quadratic drag,
/// the attitude loops' nonlinearity: time constants of height and heading 2 to 3.5 % long,
/// gains within 0.3 %); the SDK's rounding of a record with little noise, whose error does not
/// average out (synthetic records of the fit's own model across the scenario's ranges: velocity
/// gains within 2 %, time constants within 3.7 %); and the time the command and the state
/// record take through a loaded computer, which moves a pulse's edges by tens of ms against the
/// log's stamps (1 to 1.5 % of a 1.5 to 2 s pulse's displacement: the height and heading gains).
inline constexpr double kAllowanceVelocityGain = 0.02;
inline constexpr double kAllowanceIntegralGain = 0.012;
inline constexpr double kAllowanceTimeConstant = 0.035;
/// The heading's time constant, at least this much (s): against the full plant its fit leans
/// long by about the same time whatever the constant (rotor dynamics and the mixer in the yaw
/// loop, which the linearised rate loop leaves out): +0.018 s at 0.3 s on the noise-free plant,
/// +0.010 to +0.019 s on tello-sim's clean seeds 2 to 6 (true 0.17 to 0.43 s): 11 % of a 0.17 s
/// constant, beyond the relative allowance (docs/calibration.md, "The model's own error").
inline constexpr double kAllowanceYawTimeConstant_s = 0.02;

struct IdentifyOptions {
  int bootstrap_replicates = 200;
  std::uint64_t seed = 1;
  double block_s = 2.0;  ///< moving blocks: about twice the residuals' correlation (gusts: 1 s)
  int min_stick = 5;      ///< an axis counts as excited from this deflection on
  int min_samples = 30;   ///< state records in its windows
  /// The simulated Tello whose parameters are identified: its loops' gains (the tracking
  /// loops of the fit) and the nominal gains rc_gain_scale multiplies (rc_*_at_100): the
  /// scenario's (plant defaults without one).
  plant::AutopilotParams autopilot;
  plant::VehicleParams vehicle;
  FitBounds bounds;
  /// The board the senses block passed over (--board-height), for the height hold.
  std::optional<double> board_height_m;
};

struct AxisResult {
  Axis axis = Axis::forward;
  bool identified = false;
  std::string why_not;         ///< when not identified
  AxisRecord record;           ///< what was fitted (times from the takeoff's `ok`)
  AxisIdentification id;
  int windows = 0;
};

/// Figures the log's stamps give directly (program clock): the state records' arrival, and
/// the video's stages after its last datagram. The capture-to-receive latency of the video is
/// not among them: a Tello stamps neither its frames nor its state records.
struct LinkFigures {
  int state_records = 0, bad_states = 0;
  double state_period_p50_s = 0, state_period_p95_s = 0, state_gap_max_s = 0;
  int held_up_states = 0;          ///< records restamped earlier than read by 10 ms or more (state_send_times)
  double held_up_max_s = 0;        ///< the most a record was restamped
  int frames = 0, damaged_frames = 0;
  double frame_period_p50_s = 0, frame_period_p95_s = 0;
  double rx_to_handed_p50_s = 0, rx_to_handed_p95_s = 0;    ///< last datagram -> decoded
  double handed_to_taken_p50_s = 0, handed_to_taken_p95_s = 0;
};

struct Identification {
  std::string source;
  double flight_s = 0.0;                  ///< takeoff `ok` to first `land`
  std::array<AxisResult, 4> axes;
  std::map<std::string, Interval> parameters;  ///< names above and the senses'; only those identified
  SensesIdentification senses;                 ///< the senses (senses_fit.hpp); theirs are in parameters too
  LinkFigures link;
  IdentifyOptions options;
};

/// Throws std::invalid_argument when the record has no flight (no takeoff acknowledged, or no
/// state record while flying) or no axis could be identified.
Identification identify_flight(const FlightRecord& record, const IdentifyOptions& options);

/// rc_gain_scale against the nominal gains of `nominal` (rc_*_at_100): each identified axis's
/// gain over its nominal, combined as above; nothing when no axis was identified.
std::optional<Interval> gain_scale(const Identification& id, const plant::AutopilotParams& nominal);

/// The axis records of a flight (exposed for tests and plots), without their tracking loop.
AxisRecord axis_record(const FlightRecord& record, Axis axis, int min_stick, int* windows);
/// The simulated autopilot's loop that tracks the axis's reference (response_fit.hpp).
TrackingLoop tracking_loop(Axis axis, const plant::AutopilotParams& autopilot, const plant::VehicleParams& vehicle);

}  // namespace shelfcross::identify
