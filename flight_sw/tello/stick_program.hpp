#pragma once
// The stick program's run in the pilot loop (PilotLoopConfig::stick_program): it starts when
// the flight software has the drone airborne, holds the sticks the program gives, and stops
// when the flight software lands, when shelf tags come into view (then the loop lands), or
// when the program is over (then the loop lands).

#include <functional>
#include <iosfwd>
#include <optional>
#include <string>

#include "flight_sw/mission/flight_software.hpp"
#include "flight_sw/tello/clock.hpp"
#include "flight_sw/tello/pilot_log.hpp"

namespace shelfcross::tello {

class StickProgramRun {
 public:
  using Program = std::function<std::optional<std::string>(TimeNs since_airborne_ns)>;
  /// What one pass asks of the loop.
  struct Pass {
    std::optional<std::string> rc;           ///< the sticks to hold
    std::optional<std::string> land_reason;  ///< the run ended: land for this reason
    int exit_code = 0;                       ///< ... and exit with this code
  };

  /// Keeps references to all: they must outlive the run. `mode` names it in the log; an
  /// empty `program` never starts.
  StickProgramRun(const Program& program, const std::string& mode, PilotLog& log, std::ostream* console,
                  const Clock& clock)
      : program_(program), mode_(mode), log_(log), console_(console), clock_(clock) {}

  /// Starts the program when the flight software has the drone airborne (FindShelf: its
  /// takeoff acknowledged, or the height saying so when the reply was lost).
  void start_when_airborne(flight_sw::Phase phase);
  /// True while the program flies (its rc lines replace the flight software's).
  bool flying() const { return start_ns_.has_value(); }
  /// One pass at now while airborne (nothing while not flying).
  Pass step(TimeNs now, const flight_sw::FlightSoftware& fsw);

 private:
  void stop(TimeNs now, const std::string& event);

  const Program& program_;
  const std::string& mode_;
  PilotLog& log_;
  std::ostream* console_;
  const Clock& clock_;
  std::optional<TimeNs> start_ns_;  ///< the stick program flies since
  bool done_ = false;
};

}  // namespace shelfcross::tello
