#include "flight_sw/tello/stick_program.hpp"

#include <ostream>

namespace shelfcross::tello {

void StickProgramRun::start_when_airborne(flight_sw::Phase phase) {
  if (!program_ || start_ns_ || done_ || phase != flight_sw::Phase::FindShelf) return;
  start_ns_ = clock_.now_ns();
  log_.write(*start_ns_, "stick_program", {{"event", "started"}, {"mode", mode_}});
  if (console_) *console_ << "tello_pilot: " << mode_ << " started" << std::endl;
}

StickProgramRun::Pass StickProgramRun::step(TimeNs now, const flight_sw::FlightSoftware& fsw) {
  Pass pass;
  if (!start_ns_) return pass;
  const flight_sw::Phase phase = fsw.phase();
  if (phase == flight_sw::Phase::Land || phase == flight_sw::Phase::Done) {
    // The flight software's own failsafe is landing the drone: the program stops.
    stop(now, "stopped: the flight software lands (" + fsw.telemetry().event + ")");
    return pass;
  }
  if (!fsw.telemetry().view.tags.empty()) {
    stop(now, "stopped: shelf tags in view");
    pass.land_reason = mode_ + " stopped: shelf tags in view (an obstacle near: fly it in open space)";
    pass.exit_code = 1;
    return pass;
  }
  pass.rc = program_(now - *start_ns_);
  if (!pass.rc) {
    stop(now, "complete");
    pass.land_reason = mode_ + " complete";
    pass.exit_code = 0;
  }
  return pass;
}

void StickProgramRun::stop(TimeNs now, const std::string& event) {
  start_ns_.reset();
  done_ = true;
  log_.write(now, "stick_program", {{"event", event}});
}

}  // namespace shelfcross::tello
