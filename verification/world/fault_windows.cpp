#include "verification/world/fault_windows.hpp"

#include <algorithm>
#include <cmath>

namespace shelfcross::verification {

double FaultWindows::Spell::draw_s(RandomStream& stream) const {
  const double u = stream.uniform01();
  // Inverse transform: -mean ln(1 - u), u in [0, 1) so the logarithm stays finite.
  return mean_s > 0.0 ? -mean_s * std::log1p(-u) : min_s + (max_s - min_s) * u;
}

FaultWindows::FaultWindows(Spell quiet, Spell fault, RandomStream stream)
    : quiet_(quiet), fault_(fault), stream_(stream) {}

bool FaultWindows::active(TimeNs t) {
  if (!stream_ || t < 0) return false;
  // Draw spells until one faulty spell ends after t: every window up to t is then known.
  while (windows_.empty() || windows_.back().end_ns <= t) {
    const TimeNs from = windows_.empty() ? 0 : windows_.back().end_ns;
    const TimeNs start = from + seconds_to_ns(quiet_.draw_s(*stream_));
    // At least a nanosecond each: the time line always moves on.
    windows_.push_back({std::max(start, from + 1), 0});
    windows_.back().end_ns = windows_.back().start_ns + std::max<TimeNs>(1, seconds_to_ns(fault_.draw_s(*stream_)));
  }
  for (auto w = windows_.rbegin(); w != windows_.rend(); ++w) {
    if (w->end_ns <= t) return false;
    if (w->start_ns <= t) return true;
  }
  return false;
}

FaultWindows burst_windows(const BurstLoss& b, RandomStream stream) {
  if (!b.on()) return {};
  return FaultWindows({b.good_mean_s, 0.0, 0.0}, {b.bad_mean_s, 0.0, 0.0}, stream);
}

FaultWindows outage_windows(const LinkOutages& o, RandomStream stream) {
  if (!(o.interval_mean_s > 0.0)) return {};
  return FaultWindows({o.interval_mean_s, 0.0, 0.0}, {0.0, o.min_s, o.max_s}, stream);
}

}  // namespace shelfcross::verification
