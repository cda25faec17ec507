#pragma once
// Settings of the lockstep co-simulation that a scenario's `cosim:` section holds. The
// autopilot rate is autopilot.rate_hz and the frame rate camera.frame_rate_hz; these are the
// rest: the state-record rate, the link, the end of a run, and how metrics are judged.

#include <cmath>
#include <numbers>
#include <string>

#include "verification/link_model.hpp"

namespace shelfcross::verification {

struct CosimSettings {
  double state_rate_hz = 10.0;        ///< the Tello pushes a state record every 100 ms
  double fsw_tick_hz = 20.0;          ///< the flight computer's timer (flight_sw::ClockTick)
  double timeout_s = 120.0;           ///< a run not finished by then ends as "timeout"
  double trajectory_rate_hz = 50.0;   ///< trajectory.csv and plot sampling
  double vehicle_margin_m = 0.0;      ///< added around the vehicle box for contacts
  double battery_start_pct = 100.0;
  double endurance_s = 780.0;         ///< 13 min hover from full (METHOD.md Table 4): linear drain
  double render_noise_stddev = 2.0;   ///< camera sensor noise, grey levels
  int motion_blur_samples = 1;        ///< 1: no blur
  double settling_fraction = 0.02;    ///< band: fraction of the initial error ...
  double settling_floor_z_m = 0.01;   ///< ... never tighter than 1 cm ...
  double settling_floor_yaw_rad = 0.5 * std::numbers::pi / 180.0;  ///< ... or 0.5 deg
  double settling_floor_y_m = 0.01;   ///< lateral response band floor
  LinkSettings link;
  /// Fault injection, for verifying the harness and campaigns: from this simulated time on
  /// the flight software's next step raises an exception (as a bug in it would). < 0: off.
  double inject_flight_software_exception_s = -1.0;
  /// The flight software's guidance strategy between shelves (flight_sw::Strategy by name):
  /// through_cells (the paper's), over_tops or around_ends.
  std::string strategy = "through_cells";
  bool operator==(const CosimSettings&) const = default;
};

}  // namespace shelfcross::verification
