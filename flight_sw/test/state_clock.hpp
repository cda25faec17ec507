#pragma once
// Test helper: the clock of the Tello's state records, 10 a second (its state stream's rate),
// for the flight software's tests that feed records by their index.

#include <cstdint>

#include "shelfcross/time.hpp"

namespace shelfcross::flight_sw::testing {

/// The record period: 0.1 s.
constexpr TimeNs kStateRecordNs = 100 * kMs;

/// The stamp of the k-th state record of a stream that starts at 0.
constexpr TimeNs state_record_ns(std::int64_t k) { return k * kStateRecordNs; }

}  // namespace shelfcross::flight_sw::testing
