#pragma once
// tello_pilot's flight log: one JSON object per line (JSON lines), flushed line by line so a
// crash loses nothing. Every line has "t_s" (seconds since the program started, from the
// program clock, microsecond resolution), "t_ns" (the same in integer ns) and "type"; the
// other fields depend on the type (flight_sw/tello/README.md lists them).

#include <fstream>
#include <string>

#include <nlohmann/json.hpp>

#include "shelfcross/time.hpp"

namespace shelfcross::tello::pilot {

class FlightLog {
 public:
  /// Opens (truncates) the file; throws UsageError when it cannot.
  explicit FlightLog(const std::string& path);
  void write(TimeNs t_ns, const std::string& type, nlohmann::json fields = nlohmann::json::object());

 private:
  std::ofstream out_;
};

}  // namespace shelfcross::tello::pilot
