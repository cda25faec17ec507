#include "sdk/state_record.hpp"

#include <charconv>
#include <cmath>
#include <numbers>

#include "shelfcross/rotation.hpp"

namespace shelfcross::sdk {
namespace {

std::string_view trim(std::string_view s) {
  while (!s.empty() && (s.front() == ' ' || s.front() == '\r' || s.front() == '\n' || s.front() == '\t')) s.remove_prefix(1);
  while (!s.empty() && (s.back() == ' ' || s.back() == '\r' || s.back() == '\n' || s.back() == '\t' || s.back() == '\0')) s.remove_suffix(1);
  return s;
}

// Whole-string number parse; refuses trailing text, NaN and infinity.
std::optional<double> to_number(std::string_view text) {
  double v = 0.0;
  const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), v);
  if (ec != std::errc() || end != text.data() + text.size() || !std::isfinite(v)) return std::nullopt;
  return v;
}

}  // namespace

std::optional<StateRecord> parse_state_record(std::string_view datagram, TimeNs t_ns, StateParseReport* report) {
  StateParseReport local;
  StateParseReport& r = report ? *report : local;
  r = {};
  StateRecord s;
  s.t_ns = t_ns;
  std::string_view rest = trim(datagram);
  // Core keys, as bits: pitch roll yaw vgx vgy vgz h bat.
  unsigned core_seen = 0;
  while (!rest.empty()) {
    const size_t semi = rest.find(';');
    const std::string_view pair = trim(rest.substr(0, semi));
    rest = semi == std::string_view::npos ? std::string_view{} : rest.substr(semi + 1);
    if (pair.empty()) continue;
    const size_t colon = pair.find(':');
    if (colon == std::string_view::npos) return std::nullopt;  // "ok", garbage
    const std::string_view key = pair.substr(0, colon);
    const std::string_view value = pair.substr(colon + 1);
    ++r.fields;
    if (key == "mpry" || key == "mid" || key == "x" || key == "y" || key == "z") {
      r.mission_pad = true;  // mission-pad fields: not used, and mpry holds "a,b,c"
      continue;
    }
    const std::optional<double> v = to_number(value);
    if (!v) return std::nullopt;
    if (key == "pitch") { s.pitch_rad = deg_to_rad(-*v); core_seen |= 1u; }
    else if (key == "roll") { s.roll_rad = deg_to_rad(*v); core_seen |= 2u; }
    else if (key == "yaw") { s.yaw_rad = deg_to_rad(-*v); core_seen |= 4u; }
    else if (key == "vgx") { s.vx_H_mps = *v * 0.1; core_seen |= 8u; }
    else if (key == "vgy") { s.vy_H_mps = -*v * 0.1; core_seen |= 16u; }
    else if (key == "vgz") { s.vz_H_mps = -*v * 0.1; core_seen |= 32u; }
    else if (key == "h") { s.height_m = *v * 0.01; core_seen |= 64u; }
    else if (key == "bat") { s.battery_pct = static_cast<int>(std::lround(*v)); core_seen |= 128u; }
    else if (key == "tof") { s.tof_m = std::lround(*v) == kTofInvalid_cm ? std::nullopt : std::optional<double>(*v * 0.01); }
    else if (key == "baro") { s.baro_m = *v; }
    else if (key == "time") { s.motor_time_s = *v; }
    else if (key == "templ") { s.temp_low_c = *v; }
    else if (key == "temph") { s.temp_high_c = *v; }
    else if (key == "agx") { s.ax_B_mps2 = *v * 1e-3 * kStandardGravity_mps2; }
    else if (key == "agy") { s.ay_B_mps2 = -*v * 1e-3 * kStandardGravity_mps2; }
    else if (key == "agz") { s.az_B_mps2 = -*v * 1e-3 * kStandardGravity_mps2; }
    else { ++r.unknown_keys; }
  }
  if (core_seen == 0) return std::nullopt;
  for (unsigned bit = 1; bit <= 128u; bit <<= 1) r.missing_keys += (core_seen & bit) ? 0 : 1;
  return s;
}

}  // namespace shelfcross::sdk
