#pragma once
// The pilot loop's flight log lines (pilot_loop.hpp; flight_sw/tello/README.md lists them):
// the driver's events, the frames handed to the flight software, its phase changes (also on
// the console), its view of the approach, and recorded frames.

#include <functional>
#include <iosfwd>
#include <string>

#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>

#include "flight_sw/mission/flight_software.hpp"
#include "flight_sw/tello/clock.hpp"
#include "flight_sw/tello/flight_log.hpp"
#include "flight_sw/tello/sdk_driver.hpp"
#include "flight_sw/tello/video_receiver.hpp"

namespace shelfcross::tello {

/// Who submitted a command to the driver (CommandOptions::tag; the log's "origin"): the
/// flight software or the program itself (its failsafes, the stick program).
enum PilotTag : int { kTagFlightSoftware = 1, kTagPilot = 2 };

/// Writes a recorded frame under its file name; false when it could not (tello_pilot
/// --record-frames: PilotLoopConfig::record_frame).
using FrameWriter = std::function<bool(const std::string& file_name, const cv::Mat& bgr)>;

class PilotLog {
 public:
  /// Opens the flight log (empty path: none); throws FlightLogError when it cannot be written.
  /// Phase changes also go to `console` when it is not null.
  PilotLog(const std::string& path, std::ostream* console) : log_(path), console_(console) {}

  void write(TimeNs t_ns, const std::string& type, nlohmann::json fields = nlohmann::json::object()) {
    log_.write(t_ns, type, std::move(fields));
  }
  /// A driver event, as it happened.
  void driver_event(const DriverEvent& e);
  /// A frame taken from the receiver at taken_ns.
  void frame(TimeNs taken_ns, const VideoFrame& f);
  /// The flight software's phase and event, when either changed since the last line.
  void telemetry(const flight_sw::Telemetry& tm, const Clock& clock);
  /// What the flight software made of a frame of the approach (nothing in other phases).
  void approach_view(const flight_sw::Telemetry& tm, const Clock& clock);
  /// Hands the frame to `write` as frame_INDEX[_damaged].png (PilotLoopConfig::record_frame); a
  /// failsafe line when it cannot be written.
  void record(const VideoFrame& f, const FrameWriter& write, const Clock& clock);

 private:
  FlightLog log_;
  std::ostream* console_;
  flight_sw::Phase logged_phase_ = flight_sw::Phase::Idle;
  std::string logged_event_;
};

}  // namespace shelfcross::tello
