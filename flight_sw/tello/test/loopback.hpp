#pragma once
// Test helpers for real UDP on 127.0.0.1: waiting for conditions without reading a clock
// (a bounded number of short poll() waits is the failure guard), and a scripted fake drone.

#include <poll.h>

#include <optional>
#include <string>

#include "flight_sw/tello/udp_socket.hpp"

namespace shelfcross::tello::testing {

/// Sleeps up to `ms` milliseconds without reading any clock (poll on no descriptor).
inline void pause_ms(int ms) { ::poll(nullptr, 0, ms); }

/// Calls step() and then pred() until pred() holds; gives up after `guard` rounds of ~2 ms.
template <class Step, class Pred>
bool pump_until(Step step, Pred pred, int guard = 2000) {
  for (int i = 0; i < guard; ++i) {
    step();
    if (pred()) return true;
    pause_ms(2);
  }
  return false;
}

/// The next datagram on `socket`, waiting up to `guard_ms` for one (failure guard).
inline std::optional<Datagram> receive_within(UdpSocket& socket, int guard_ms = 3000) {
  if (auto d = socket.receive()) return d;
  if (!socket.wait_readable(guard_ms)) return std::nullopt;
  return socket.receive();
}

}  // namespace shelfcross::tello::testing
