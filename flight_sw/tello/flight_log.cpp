#include "flight_sw/tello/flight_log.hpp"

#include <cmath>

namespace shelfcross::tello {

FlightLog::FlightLog(const std::string& path) {
  if (path.empty()) return;
  out_.open(path, std::ios::trunc);
  if (!out_) throw FlightLogError("cannot write the flight log '" + path + "'");
}

void FlightLog::write(TimeNs t_ns, const std::string& type, nlohmann::json fields) {
  if (!out_.is_open()) return;
  nlohmann::ordered_json line = nlohmann::ordered_json::object();  // t_s, t_ns, type first
  line["t_s"] = std::round(ns_to_seconds(t_ns) * 1e6) / 1e6;
  line["t_ns"] = t_ns;
  line["type"] = type;
  for (auto& [key, value] : fields.items()) line[key] = std::move(value);
  // Replace invalid UTF-8 (a garbage datagram's text) instead of throwing.
  out_ << line.dump(-1, ' ', false, nlohmann::ordered_json::error_handler_t::replace) << '\n';
  out_.flush();
}

}  // namespace shelfcross::tello
