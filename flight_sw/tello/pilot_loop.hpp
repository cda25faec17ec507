#pragma once
// The pilot loop: what flies a Tello. The SDK driver and the H.264 video receiver in, the
// flight software in the middle, commands out, the program's own failsafes around it, every
// command, reply, state record and frame time in the flight log. `tello_pilot` drives it from
// UDP sockets and a steady clock; the co-simulation drives the very same loop from in-memory
// channels (datagram_channel.hpp) and its simulated clock, so a campaign verifies what flies.
//
//   step(): video.service() (unthreaded receivers) -> driver.service() -> inputs (state
//           records, replies to the flight software's commands, the newest frame) sorted by
//           their clock stamps -> FlightSoftware::step -> commands -> driver.submit -> the
//           failsafes -> driver.service()
//
// The failsafes do not rely on the flight software: a signal (Ctrl-C, SIGTERM), no state
// record for link_outage_s, the battery at critical_battery_pct, no frame for video_hover_s
// (hover) then video_land_s (land), airborne longer than max_flight_s, and the flight software
// ending while airborne, all send `land` (urgent: displacing any command), wait for its reply
// or its last retry, and end the loop. No state record for state_timeout_s is a link outage,
// ridden through hovering until link_outage_s (link_watch.hpp). "Airborne" = a takeoff was sent
// and no land has been acknowledged since.

#include <functional>
#include <iosfwd>
#include <memory>
#include <optional>
#include <string>

#include "flight_sw/config.hpp"
#include "flight_sw/mission/flight_software.hpp"
#include "flight_sw/tello/clock.hpp"
#include "flight_sw/tello/flight_log.hpp"
#include "flight_sw/tello/pilot_log.hpp"
#include "flight_sw/tello/sdk_driver.hpp"
#include "flight_sw/tello/video_receiver.hpp"
#include "sdk/command.hpp"

namespace shelfcross::tello {

/// The program's last-line failsafes, independent of the flight software's own.
struct Failsafes {
  double state_timeout_s = 2.0;        ///< airborne and no state record this long: the link is out, hover
  /// ... and no state record this long: land (link_watch.hpp: at most the Tello's watchdog,
  /// 15 s, less the driver's keep-alive period, 5 s)
  double link_outage_s = 10.0;
  double state_start_timeout_s = 10.0; ///< no state record at all this long after start: give up
  double video_hover_s = 5.0;          ///< airborne and no frame this long: hover (rc 0 0 0 0)
  double video_land_s = 8.0;           ///< airborne and no frame this long: land
  int critical_battery_pct = 10;       ///< battery at or below: land
  double max_flight_s = 480.0;         ///< airborne this long: land
  double land_reply_s = sdk::ReplyTimeouts{}.land_s;  ///< the program's own land: reply timeout (3 retries)
};

struct PilotLoopConfig {
  DriverConfig driver;              ///< drone address, command and state ports, dry_run
  VideoReceiverConfig video;        ///< video port; threaded or not
  flight_sw::FlightConfig flight;
  Failsafes failsafes;
  std::string log_path;             ///< the flight log (JSON lines); empty: none
  /// Records every frame handed to the flight software (debugging: tello_pilot --record-frames):
  /// called with the frame's file name, frame_INDEX[_damaged].png, and its picture; false when it
  /// could not (a failsafe line in the log). The program writes the file: image files are
  /// OpenCV's imgcodecs, whose hundred-odd shared libraries (GDAL and its formats) the loop
  /// leaves to the programs that write pictures, not to every co-simulated run. Empty: none.
  FrameWriter record_frame;
  std::string flight_config_path;   ///< for the log's start line
  std::string calibration_path;     ///< for the log's start line
  std::ostream* console = nullptr;  ///< phase changes and failsafe messages for people; null: silent
  /// Called with each frame right after the flight software stepped on it (replay videos).
  std::function<void(const CameraFrame&, const flight_sw::FlightSoftware&)> on_frame;
  /// A stick program flown instead of the mission once the flight software reports the drone
  /// airborne (tello_pilot --fly-calibration): called on every pass with the time since then,
  /// it returns the rc text to hold, or nothing once it is over; the loop then lands (exit 0).
  /// The flight software keeps running beside it as the mission's watchman: its pre-flight
  /// checks (state, video, battery) gate the takeoff, its failsafes' `land`s pass, only its
  /// sticks are dropped; and the program stops and lands (exit 1) as soon as its perception
  /// sees shelf tags, the one obstacle a Tello's camera can recognise. Empty: the mission flies.
  std::function<std::optional<std::string>(TimeNs since_airborne_ns)> stick_program;
  std::string mode = "mission";  ///< the start line's `mode` (what the loop flies)
};

/// In-memory channels for the driver (commands and replies, state) and the video receiver;
/// all null: UDP sockets from the configuration.
struct PilotChannels {
  std::unique_ptr<DatagramChannel> command, state, video;
};

/// Exit codes of a loop that ended: 0 the mission ended (crossed, or no empty cell) or a
/// signal stopped it and the drone landed; 1 the mission was aborted, a program failsafe
/// landed it, or the land went unacknowledged; 130 stopped by a signal on the ground.
class PilotLoop {
 public:
  /// Keeps references to `config` and `clock`: both must outlive the loop. Throws
  /// std::runtime_error (port busy, no H.264 decoder), FlightLogError, config errors.
  PilotLoop(const PilotLoopConfig& config, const Clock& clock, PilotChannels channels = {});
  ~PilotLoop();
  PilotLoop(const PilotLoop&) = delete;
  PilotLoop& operator=(const PilotLoop&) = delete;

  /// Starts the flight software (its first commands go to the driver).
  void start();
  /// One pass of the loop. `signals` counts the signals received so far. Returns the exit
  /// code once the loop has ended (then finish() may be called), else nothing.
  std::optional<int> step(int signals = 0);
  /// Writes the end line of the flight log; returns a summary for people.
  std::string finish(int code);

  /// Descriptors to poll for input (command, state, video ready); -1 for in-memory channels.
  int command_fd() const;
  int state_fd() const;
  int video_fd() const;

  const flight_sw::FlightSoftware& flight_software() const;
  const SdkDriver& driver() const;
  VideoStats video_stats() const;
  std::uint16_t video_port() const;
  bool airborne() const;
  /// Why the program's failsafe landed the drone (empty when it did not).
  const std::string& failsafe_reason() const;

 private:
  class Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace shelfcross::tello
