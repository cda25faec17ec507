#include "flight_sw/tello/pilot/pilot.hpp"

#include <poll.h>

#include <fstream>
#include <iostream>

#include "flight_sw/tello/pilot_loop.hpp"

namespace shelfcross::tello::pilot {

int run_pilot(const PilotOptions& o, const Clock& clock, const std::atomic<int>& signals) {
  PilotLoopConfig config;
  config.driver = o.driver;
  config.driver.dry_run = o.dry_run || o.driver.dry_run;
  config.video = o.video;
  config.video.threaded = true;  // decode as datagrams arrive, off the loop's thread
  config.flight = o.flight;
  config.failsafes = o.failsafes;
  config.log_path = o.log_path;
  config.record_dir = o.record_dir;
  config.flight_config_path = o.flight_config_path;
  config.calibration_path = o.calibration_path;
  config.console = &std::cout;
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
