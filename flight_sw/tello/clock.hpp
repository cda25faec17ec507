#pragma once
// The one place tello_pilot reads the wall clock. The driver and the video receiver take
// every time they need (receive stamps, reply timeouts, the rc rate, the keep-alive) from a
// Clock they are given, so tests drive them with a ManualClock and assert nothing about
// real time, while tello_pilot gives them a SteadyClock.
//
// Times are shelfcross::TimeNs: nanoseconds since the clock's origin (the program's start for
// SteadyClock), the same stamps the flight software receives.

#include <atomic>
#include <chrono>

#include "shelfcross/time.hpp"

namespace shelfcross::tello {

/// A monotonic source of time. Implementations are safe to call from several threads (the
/// video receiver stamps frames on its own thread).
class Clock {
 public:
  virtual ~Clock() = default;
  virtual TimeNs now_ns() const = 0;
};

/// std::chrono::steady_clock, origin at construction. The only wall clock of tello_pilot.
class SteadyClock final : public Clock {
 public:
  SteadyClock();
  TimeNs now_ns() const override;

 private:
  std::chrono::steady_clock::time_point origin_;
};

/// A clock that moves only when told: tests step it to fire timeouts without waiting.
class ManualClock final : public Clock {
 public:
  explicit ManualClock(TimeNs start_ns = 0) : now_ns_(start_ns) {}
  TimeNs now_ns() const override { return now_ns_.load(); }
  void set(TimeNs t_ns) { now_ns_.store(t_ns); }
  void advance(TimeNs dt_ns) { now_ns_.fetch_add(dt_ns); }

 private:
  std::atomic<TimeNs> now_ns_;
};

}  // namespace shelfcross::tello
