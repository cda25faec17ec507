// sdk::parse_state_record on arbitrary bytes, and the round trip with the drone's side:
// for a record verification::format_state_record writes from finite values, the parser gives
// back the values quantised the way the drone reports them (state_record.hpp), and writing what
// was parsed gives the same text again.
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string_view>

#include <fuzzer/FuzzedDataProvider.h>

#include "sdk/state_record.hpp"
#include "verification/world/tello_state_format.hpp"

using namespace shelfcross;

namespace {

void check(bool ok, const char* what, double got, double want) {
  if (ok) return;
  std::fprintf(stderr, "state record round trip: %s: parsed %.17g, expected %.17g\n", what, got, want);
  std::abort();
}

/// |got - want| within `quantum` (half the SDK's step, converted) plus rounding noise.
void near(const char* what, double got, double want, double quantum) {
  check(std::abs(got - want) <= quantum + 1e-9 * (1.0 + std::abs(want)), what, got, want);
}

void round_trip(FuzzedDataProvider& in) {
  // Values the drone can report: finite, and small enough that the record's integers and
  // two-decimal fields fit its 512-byte buffer (|v| <= 1e6 in SDK units is far beyond any flight).
  const auto f = [&](double lim) { return in.ConsumeFloatingPointInRange<double>(-lim, lim); };
  StateRecord s;
  s.roll_rad = f(1e4);
  s.pitch_rad = f(1e4);
  s.yaw_rad = f(1e4);
  s.vx_H_mps = f(1e5);
  s.vy_H_mps = f(1e5);
  s.vz_H_mps = f(1e5);
  s.ax_B_mps2 = f(1e4);
  s.ay_B_mps2 = f(1e4);
  s.az_B_mps2 = f(1e4);
  s.height_m = f(1e4);
  if (in.ConsumeBool()) s.tof_m = f(1e4);
  if (in.ConsumeBool()) s.baro_m = f(1e6);
  s.battery_pct = in.ConsumeIntegralInRange<int>(-1000000, 1000000);
  s.motor_time_s = in.ConsumeFloatingPointInRange<double>(0.0, 1e6);
  s.temp_low_c = f(1e6);
  s.temp_high_c = f(1e6);

  const std::string text = verification::format_state_record(s);
  sdk::StateParseReport report;
  const auto p = sdk::parse_state_record(text, 42, &report);
  if (!p) {
    std::fprintf(stderr, "state record round trip: refused '%s'\n", text.c_str());
    std::abort();
  }
  check(report.missing_keys == 0 && report.unknown_keys == 0 && report.mission_pad, "report", report.fields, 21);
  check(p->t_ns == 42, "t_ns", double(p->t_ns), 42);
  constexpr double deg = 3.141592653589793 / 180.0;
  const double mg = 1e-3 * sdk::kStandardGravity_mps2;
  near("roll", p->roll_rad, s.roll_rad, 0.5 * deg);
  near("pitch", p->pitch_rad, s.pitch_rad, 0.5 * deg);
  near("yaw", p->yaw_rad, s.yaw_rad, 0.5 * deg);
  near("vgx", p->vx_H_mps, s.vx_H_mps, 0.05);
  near("vgy", p->vy_H_mps, s.vy_H_mps, 0.05);
  near("vgz", p->vz_H_mps, s.vz_H_mps, 0.05);
  near("agx", p->ax_B_mps2, s.ax_B_mps2, 0.005 * mg);
  near("agy", p->ay_B_mps2, s.ay_B_mps2, 0.005 * mg);
  near("agz", p->az_B_mps2, s.az_B_mps2, 0.005 * mg);
  near("h", p->height_m, s.height_m, 0.005);
  near("templ", p->temp_low_c, s.temp_low_c, 0.5);
  near("temph", p->temp_high_c, s.temp_high_c, 0.5);
  near("baro", p->baro_m.value_or(-1e300), s.baro_m.value_or(0.0), 0.005);  // absent: written 0.00
  check(p->battery_pct == s.battery_pct, "bat", p->battery_pct, s.battery_pct);
  check(p->motor_time_s == std::floor(s.motor_time_s), "time", p->motor_time_s, std::floor(s.motor_time_s));
  if (s.tof_m && std::lround(*s.tof_m * 100.0) != sdk::kTofInvalid_cm) {
    check(p->tof_m.has_value(), "tof (absent)", 0, *s.tof_m);
    near("tof", *p->tof_m, *s.tof_m, 0.005);
  } else {
    check(!p->tof_m.has_value(), "tof (present)", p->tof_m.value_or(0), sdk::kTofInvalid_cm);
  }
  // What was parsed is a fixed point: written again, it is the same text.
  const std::string again = verification::format_state_record(*p);
  if (again != text) {
    std::fprintf(stderr, "state record round trip: '%s' written again as '%s'\n", text.c_str(), again.c_str());
    std::abort();
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  sdk::StateParseReport report;
  if (const auto s = sdk::parse_state_record(text, 7, &report)) {
    // An accepted record has finite values and counts that add up.
    const double v[] = {s->roll_rad, s->pitch_rad, s->yaw_rad, s->vx_H_mps, s->vy_H_mps, s->vz_H_mps,
                        s->ax_B_mps2, s->ay_B_mps2, s->az_B_mps2, s->height_m, s->motor_time_s,
                        s->temp_low_c, s->temp_high_c, s->tof_m.value_or(0), s->baro_m.value_or(0)};
    for (const double x : v) check(std::isfinite(x), "finite", x, 0);
    check(report.fields >= 1 && report.missing_keys >= 0 && report.missing_keys < 8, "report", report.fields,
          report.missing_keys);
  }
  FuzzedDataProvider in(data, size);
  round_trip(in);
  return 0;
}
