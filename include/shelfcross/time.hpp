#pragma once
// Simulated and message time: a signed 64-bit count of nanoseconds.
//
// Every event time is computed from integers (a tick index and an integer rate), never
// accumulated in floating point, so that a run's timeline is identical on every machine.
// Doubles appear only at the edges: reading a configuration in seconds and writing logs.

#include <cmath>
#include <cstdint>

namespace shelfcross {

/// Nanoseconds since the start of a run (simulation) or since the program started (tello_pilot).
using TimeNs = std::int64_t;

inline constexpr TimeNs kNsPerSecond = 1'000'000'000;
/// One millisecond in TimeNs.
inline constexpr TimeNs kMs = 1'000'000;

/// The k-th tick of a clock running at `rate_hz` ticks per second, first tick at 0:
/// t_k = floor(k * 1e9 / rate_hz), exact in integers for k * 1e9 < 2^63 (k < 9.2e9).
constexpr TimeNs tick_time_ns(std::int64_t k, std::int64_t rate_hz) {
  return k * kNsPerSecond / rate_hz;
}

/// A rate given in hertz (a configuration value, possibly fractional: 29.97) as an integer
/// count of millihertz, rounded to the nearest. Requires 0 < rate_hz < 9.2e15.
inline std::int64_t millihertz(double rate_hz) { return std::llround(rate_hz * 1000.0); }

/// The event clock: the k-th event (first at 0) of a clock at `mhz` millihertz is at
/// t_k = floor(k * 1e12 / mhz) ns, exact in integers for k < 9.2e6. Requires mhz > 0.
constexpr TimeNs event_time(std::int64_t k, std::int64_t mhz) { return k * (kNsPerSecond * 1000) / mhz; }

/// Seconds (a configuration value) to nanoseconds, rounded to the nearest nanosecond.
inline TimeNs seconds_to_ns(double t_s) { return static_cast<TimeNs>(std::llround(t_s * 1e9)); }

/// Nanoseconds to seconds, for logs and for the integrator's real-valued time.
constexpr double ns_to_seconds(TimeNs t_ns) { return static_cast<double>(t_ns) * 1e-9; }

}  // namespace shelfcross
