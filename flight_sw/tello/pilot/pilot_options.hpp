#pragma once
// tello_pilot's settings: where the drone is, which ports, the flight software's
// configuration, the program's own failsafes and where its outputs go. Read from an optional
// YAML pilot file (strict: file:line errors) and then the command line, which wins.

#include <optional>
#include <string>

#include "flight_sw/config.hpp"
#include "flight_sw/tello/pilot_loop.hpp"
#include "flight_sw/tello/sdk_driver.hpp"
#include "flight_sw/tello/video_receiver.hpp"

namespace shelfcross::tello::pilot {

struct PilotOptions {
  DriverConfig driver;              ///< drone address, command and state ports, dry_run
  VideoReceiverConfig video;        ///< video port
  flight_sw::FlightConfig flight;   ///< from --config (flight_sw's YAML), camera from --calibration
  std::string flight_config_path;
  std::string calibration_path;     ///< OpenCV FileStorage with camera_matrix, distortion_coefficients
  Failsafes failsafes;
  std::string log_path = "tello_flight_log.jsonl";
  std::string inventory_path = "tello_inventory.json";
  bool dry_run = false;
  std::string record_dir;           ///< --record-frames: every frame handed over, as PNG (debugging)
  /// --fly-calibration: fly the calibration manoeuvre (calibration_manoeuvre.hpp) instead of
  /// the mission, for `shelfcross identify`.
  bool fly_calibration = false;
  /// --senses-board DISTANCE: the calibration flight flies its senses block too, over a board
  /// whose middle lies this far (m) straight behind the take-off point.
  std::optional<double> senses_board_m;
  // Calibration mode (--calibrate OUT): record chessboard views, write the intrinsics, exit.
  std::string calibrate_path;
  int board_columns = 9;            ///< inner corners per row
  int board_rows = 6;               ///< inner corners per column
  double square_m = 0.025;
  int calibration_views = 25;
  // Print mode (--print-markers DIR): marker and tag PNGs for the test shelf, then exit.
  std::string print_dir;
  int marker_first = 0;
  int marker_last = 15;
};

/// Thrown for a bad command line, pilot file, flight configuration or calibration: the
/// message is for the user; main() prints it and exits 2.
struct UsageError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

/// Parses argv (CLI11). Returns nothing when --help was asked (the help is printed).
/// Throws UsageError on every problem.
std::optional<PilotOptions> parse_options(int argc, char** argv);

/// Reads an OpenCV calibration file (YAML or XML as cv::FileStorage writes it:
/// image_width, image_height, camera_matrix 3x3, distortion_coefficients 1x5 or 5x1).
/// Throws UsageError naming the file and the problem.
CameraIntrinsics load_calibration(const std::string& path);

}  // namespace shelfcross::tello::pilot
