#include "flight_sw/tello/clock.hpp"

namespace shelfcross::tello {

SteadyClock::SteadyClock() : origin_(std::chrono::steady_clock::now()) {}

TimeNs SteadyClock::now_ns() const {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::steady_clock::now() -
                                                              origin_)
      .count();
}

}  // namespace shelfcross::tello
