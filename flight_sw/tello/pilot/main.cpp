// tello_pilot: flies a DJI Tello with the shelfcross flight software (flight_sw/tello/README.md).
// The program's one wall clock is the SteadyClock made here.
#include <csignal>
#include <iostream>

#include "flight_sw/tello/pilot/pilot.hpp"

namespace {

std::atomic<int> g_signals{0};

extern "C" void on_signal(int) { g_signals.fetch_add(1); }

void install_signal_handlers() {
  struct sigaction sa {};
  sa.sa_handler = on_signal;
  sigemptyset(&sa.sa_mask);
  sa.sa_flags = 0;  // no SA_RESTART: poll() returns at once
  sigaction(SIGINT, &sa, nullptr);
  sigaction(SIGTERM, &sa, nullptr);
}

}  // namespace

int main(int argc, char** argv) {
  using namespace shelfcross::tello;
  std::optional<pilot::PilotOptions> options;
  try {
    options = pilot::parse_options(argc, argv);
    if (!options) return 0;  // --help
  } catch (const pilot::UsageError& e) {
    std::cerr << "tello_pilot: " << e.what() << std::endl;
    return 2;
  }
  install_signal_handlers();
  const SteadyClock clock;
  try {
    if (!options->print_dir.empty()) return pilot::run_print_sheets(*options);
    if (!options->calibrate_path.empty()) return pilot::run_calibration(*options, clock, g_signals);
    return pilot::run_pilot(*options, clock, g_signals);
  } catch (const pilot::UsageError& e) {
    std::cerr << "tello_pilot: " << e.what() << std::endl;
    return 2;
  } catch (const std::exception& e) {
    std::cerr << "tello_pilot: " << e.what() << std::endl;
    return 1;
  }
}
