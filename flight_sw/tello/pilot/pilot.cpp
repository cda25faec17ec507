#include "flight_sw/tello/pilot/pilot.hpp"

#include <poll.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <memory>
#include <iostream>

#include <opencv2/imgcodecs.hpp>

#include "flight_sw/tello/calibration_manoeuvre.hpp"
#include "flight_sw/tello/pilot_loop.hpp"
#include "sdk/command.hpp"

namespace shelfcross::tello::pilot {
namespace {

// --fly-calibration: the calibration manoeuvre replaces the mission's sticks once airborne
// (PilotLoopConfig::stick_program). The flight software's shelf search must outlast it: its
// find_shelf_s timeout would otherwise land the drone halfway. Each new stick setting goes out
// three times, 20 ms apart (DriverConfig::rc_new_copies): identify takes a step's edge from the
// log's first rc datagram of it, and a lost one would move the edge the drone flew by the
// 100 ms to the next repeat; with three copies that needs all three lost (p^3: 2.7e-5 at 3 %
// loss, against 0.03 for each of the manoeuvre's 46 edges).
void fly_calibration_instead(PilotLoopConfig& config, const std::optional<double>& board_m) {
  auto manoeuvre = std::make_shared<const CalibrationManoeuvre>(
      CalibrationAmplitudes{}, board_m ? std::optional(CalibrationSenses{*board_m}) : std::nullopt);
  config.mode = "calibration_flight";
  config.driver.rc_new_copies = 3;
  config.flight.timeouts.find_shelf_s = std::max(config.flight.timeouts.find_shelf_s, manoeuvre->duration_s() + 15.0);
  config.stick_program = [manoeuvre](TimeNs since_ns) -> std::optional<std::string> {
    const ManoeuvreStep* step = manoeuvre->step_at(ns_to_seconds(since_ns));
    if (!step) return std::nullopt;
    return sdk::rc_text(step->sticks[0], step->sticks[1], step->sticks[2], step->sticks[3]);
  };
  std::cout << "tello_pilot: calibration flight: " << manoeuvre->steps().size() << " steps, "
            << manoeuvre->duration_s() << " s after the takeoff, then land. Open space only: about 1 m clear "
            << "around the take-off point and 0.6 m above the take-off height; it stops and lands if shelf tags come into view."
            << std::endl;
}

}  // namespace

int run_pilot(const PilotOptions& o, const Clock& clock, const std::atomic<int>& signals) {
  PilotLoopConfig config;
  config.driver = o.driver;
  config.driver.dry_run = o.dry_run || o.driver.dry_run;
  config.video = o.video;
  config.video.threaded = true;  // decode as datagrams arrive, off the loop's thread
  config.flight = o.flight;
  config.failsafes = o.failsafes;
  config.log_path = o.log_path;
  if (!o.record_dir.empty()) {
    std::filesystem::create_directories(o.record_dir);
    config.record_frame = [dir = std::filesystem::path(o.record_dir)](const std::string& file_name,
                                                                       const cv::Mat& bgr) {
      return cv::imwrite((dir / file_name).string(), bgr, {cv::IMWRITE_PNG_COMPRESSION, 1});
    };
  }
  config.flight_config_path = o.flight_config_path;
  config.calibration_path = o.calibration_path;
  config.console = &std::cout;
  if (o.fly_calibration) fly_calibration_instead(config, o.senses_board_m);
  std::optional<PilotLoop> loop;
  try {
    loop.emplace(config, clock);
  } catch (const FlightLogError& e) {
    throw UsageError(e.what());
  }
  std::cout << "tello_pilot: drone " << o.driver.drone_ip << ":" << o.driver.drone_command_port << ", command port "
            << loop->driver().local_command_port() << ", state port " << loop->driver().local_state_port()
            << ", video port " << loop->video_port() << (config.driver.dry_run ? ", DRY RUN (no motion command is sent)" : "")
            << std::endl;
  loop->start();
  int code = 0;
  for (;;) {
    // Wait for a datagram or a decoded frame, at most 5 ms (the driver's timers and the
    // failsafes run on every pass). EINTR on a signal: fine, the loop sees the signal count.
    pollfd fds[3] = {{loop->command_fd(), POLLIN, 0}, {loop->state_fd(), POLLIN, 0}, {loop->video_fd(), POLLIN, 0}};
    ::poll(fds, 3, 5);
    if (auto exit_code = loop->step(signals.load())) {
      code = *exit_code;
      break;
    }
  }
  const std::string summary = loop->finish(code);
  const flight_sw::FlightSoftware& fsw = loop->flight_software();
  std::ofstream inventory(o.inventory_path, std::ios::trunc);
  inventory << fsw.inventory_json() << '\n';
  if (!inventory) std::cerr << "tello_pilot: cannot write the inventory '" << o.inventory_path << "'" << std::endl;
  std::cout << "tello_pilot: " << summary << "\n  inventory: " << o.inventory_path << "\n  log: " << o.log_path
            << std::endl;
  return code;
}

}  // namespace shelfcross::tello::pilot
