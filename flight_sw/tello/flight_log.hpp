#pragma once
// The pilot loop's flight log: one JSON object per line (JSON lines), flushed line by line so
// a crash loses nothing. Every line has "t_s" (seconds since the loop's clock origin,
// microsecond resolution), "t_ns" (the same in integer ns) and "type"; the other fields depend
// on the type (flight_sw/tello/README.md lists them). A log made with an empty path writes
// nothing (the co-simulation runs the loop without one).

#include <fstream>
#include <stdexcept>
#include <string>

#include <nlohmann/json.hpp>

#include "shelfcross/time.hpp"

namespace shelfcross::tello {

/// The log file cannot be written.
struct FlightLogError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

class FlightLog {
 public:
  /// Opens (truncates) the file; throws FlightLogError when it cannot. Empty: no log.
  explicit FlightLog(const std::string& path);
  void write(TimeNs t_ns, const std::string& type, nlohmann::json fields = nlohmann::json::object());
  bool enabled() const { return out_.is_open(); }

 private:
  std::ofstream out_;
};

}  // namespace shelfcross::tello
