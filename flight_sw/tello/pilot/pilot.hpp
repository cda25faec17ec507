#pragma once
// The tello_pilot main loop: UDP driver and video receiver in, the flight software in the
// middle, commands out; every command, reply, state record and frame time in the flight log.
//
//   loop: poll(command, state, video-ready; 5 ms) -> driver.service() -> inputs (state
//         records, replies to the flight software's commands, the newest frame) sorted by
//         their program-clock stamps -> FlightSoftware::step -> commands -> driver.submit
//         -> the program's own failsafes -> driver.service()
//
// The program's failsafes do not rely on the flight software: a signal (Ctrl-C, SIGTERM),
// no state record for link_outage_s (for state_timeout_s: the link is out, hover), the battery at critical_battery_pct, no frame for
// video_hover_s (hover) then video_land_s (land), airborne longer than max_flight_s, and the
// flight software ending while airborne, all send `land` (urgent: displacing any command),
// wait for its reply or its last retry, and exit. "Airborne" = a takeoff was sent and no land
// has been acknowledged since.

#include <atomic>

#include "flight_sw/tello/clock.hpp"
#include "flight_sw/tello/pilot/pilot_options.hpp"

namespace shelfcross::tello::pilot {

/// Exit codes: 0 the mission ended (crossed, or no empty cell) or a signal stopped it and the
/// drone landed (or the calibration was written); 1 the mission was aborted or a program
/// failsafe landed it, or a runtime failure (no drone, land unacknowledged, port busy);
/// 2 bad input (main); 130 stopped by a signal on the ground. Throws UsageError when the
/// flight log cannot be opened (bad input, exit 2).
int run_pilot(const PilotOptions& options, const Clock& clock, const std::atomic<int>& signals);

/// Calibration mode: `command`, `streamon`, then chessboard views from the stream until
/// options.calibration_views are collected; writes the OpenCV calibration file. No motion
/// command is ever sent (the driver runs in dry-run mode). Throws UsageError when the flight
/// log cannot be opened.
int run_calibration(const PilotOptions& options, const Clock& clock, const std::atomic<int>& signals);

/// --print-markers mode: PNG sheets (300 dpi) of the box markers and the colour tag of the
/// flight configuration, written to options.print_dir. Throws UsageError.
int run_print_sheets(const PilotOptions& options);

}  // namespace shelfcross::tello::pilot
