#pragma once
// Settings of the lockstep co-simulation that a scenario's `cosim:` section holds. The
// autopilot rate is autopilot.rate_hz and the frame rate camera.frame_rate_hz; these are the
// rest: the state-record rate, the link, the end of a run, and how metrics are judged.

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>
#include <string>

#include "verification/scenario/link_settings.hpp"

namespace shelfcross::verification {

/// One point of the measured distribution of the flight software's step time.
struct StepLatencyQuantile {
  double probability;  ///< P(step time <= seconds)
  double seconds;
};

/// The flight software's whole per-frame step (FlightSoftware::step on a camera frame, fast
/// perception pipeline) during the approach, the phase that flies most frames, measured on
/// one core at 960 x 720 by the perception benchmark on its frame set: BM_Step/nominal/approach
/// (bench/README.md has the command, the machine and the other phases): thread CPU time per
/// step, 400 steps over the 100 approach frames, 2026-11-21 on the 2-core AMD EPYC VM the
/// project is built on (shared, loaded: an idle core is faster). Quantiles in seconds.
/// Re-measure and update these when the flight software's perception changes.
inline constexpr std::array<StepLatencyQuantile, 8> kMeasuredStepLatency{{
    {0.00, 0.000229},
    {0.10, 0.000262},
    {0.25, 0.000306},
    {0.50, 0.000427},
    {0.75, 0.000690},
    {0.90, 0.001099},
    {0.99, 0.001420},
    {1.00, 0.001453},
}};

/// The step time at quantile q in [0, 1] of the measured distribution: its inverse CDF,
/// linear between the measured quantiles (q outside [0, 1] is clamped; NaN is not allowed:
/// std::clamp passes it through and the result is unspecified).
inline double measured_step_latency_s(double q) {
  q = std::clamp(q, 0.0, 1.0);
  for (size_t i = 1; i < kMeasuredStepLatency.size(); ++i) {
    const StepLatencyQuantile& a = kMeasuredStepLatency[i - 1];
    const StepLatencyQuantile& b = kMeasuredStepLatency[i];
    if (q <= b.probability) return a.seconds + (b.seconds - a.seconds) * (q - a.probability) / (b.probability - a.probability);
  }
  return kMeasuredStepLatency.back().seconds;
}

/// The measured median step time: the co-simulation's default compute latency.
inline constexpr double kMeasuredStepLatencyP50_s = kMeasuredStepLatency[3].seconds;
static_assert(kMeasuredStepLatency[3].probability == 0.50);

/// The link's defaults with the flight software's compute latency at its measured median.
inline LinkSettings default_link_settings() {
  LinkSettings l;
  l.compute_latency_s = kMeasuredStepLatencyP50_s;
  return l;
}

/// The pilot program's own settings that a campaign may vary (sdk link only): the rest are
/// tello_pilot's defaults, as it flies.
struct PilotSettings {
  /// The driver's stop-sticks rule (DriverConfig::stop_rc_repeats): "rc 0 0 0 0" this many
  /// times before a manoeuvre that follows deflected sticks; 0 switches the rule off.
  int stop_rc_repeats = 2;
  /// The flight software's level check (flight_sw MissionParams::level_check); false switches
  /// it off.
  bool level_check = true;
  bool operator==(const PilotSettings&) const = default;
};

struct CosimSettings {
  double state_rate_hz = 10.0;        ///< the Tello pushes a state record every 100 ms
  double fsw_tick_hz = 20.0;          ///< the flight computer's timer (flight_sw::ClockTick)
  double timeout_s = 120.0;           ///< a run not finished by then ends as "timeout" (one landing then gets 30 s more)
  double trajectory_rate_hz = 50.0;   ///< trajectory.csv and plot sampling
  double vehicle_margin_m = 0.0;      ///< added around the vehicle box for contacts
  double battery_start_pct = 100.0;
  double endurance_s = 780.0;         ///< 13 min hover from full (docs/method.md Table 4): linear drain
  double render_noise_stddev = 2.0;   ///< camera sensor noise, grey levels
  int motion_blur_samples = 1;        ///< 1: no blur
  double settling_fraction = 0.02;    ///< band: fraction of the initial error ...
  double settling_floor_z_m = 0.01;   ///< ... never tighter than 1 cm ...
  double settling_floor_yaw_rad = 0.5 * std::numbers::pi / 180.0;  ///< ... or 0.5 deg
  double settling_floor_y_m = 0.01;   ///< lateral response band floor
  /// A run that touched nothing but whose least clearance to a shelf (WorldTruth::min_clearance_m)
  /// fell below this is a near miss: counted apart from contacts and from success
  /// (is_near_miss, stored_run.hpp). Judged when runs are summarized, never stored in a run.
  double near_miss_m = 0.02;
  /// compute_latency_s defaults to the measured median step time (kMeasuredStepLatencyP50_s);
  /// the dispersion compute_latency_quantile draws it from the measured distribution.
  LinkSettings link = default_link_settings();
  PilotSettings pilot;
  /// Fault injection, for verifying the harness and campaigns: from this simulated time on
  /// the flight software's next step raises an exception (as a bug in it would). < 0: off.
  double inject_flight_software_exception_s = -1.0;
  /// Fault injection of the run's process: at this simulated time it raises SIGSEGV (as a
  /// crash in a graphics driver would). < 0: off. Only for campaigns, whose runs live in
  /// worker processes (verification/campaign/run_process.hpp): `shelfcross run` itself would die.
  double inject_crash_s = -1.0;
  /// Likewise: at this simulated time the run stops making progress for good (as a deadlock
  /// would); a campaign's worker is killed at its wall-clock limit. < 0: off.
  double inject_hang_s = -1.0;
  /// The flight software's guidance strategy between shelves (flight_sw::Strategy by name):
  /// through_cells (the paper's), over_tops or around_ends.
  std::string strategy = "through_cells";
  bool operator==(const CosimSettings&) const = default;
};

}  // namespace shelfcross::verification
