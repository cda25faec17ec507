#pragma once
// The simulated Tello's state datagram (port 8890): the drone's side of the state record whose
// format and sign conventions sdk/state_record.hpp states once (its parser is the ground
// station's side). It lives in verification/, with the rest of the simulated Tello, so that
// `tello_pilot` never links it.

#include <string>

#include "shelfcross/sdk_messages.hpp"

namespace shelfcross::verification {

/// The simulated Tello's state datagram (SDK 2.0 layout, no mission pad seen), from a record
/// in shelfcross units, with the inverse of sdk::parse_state_record's conversion, rounding the
/// way the drone reports: integers for attitude, velocity, heights, battery and temperatures.
/// `battery_pct`, temperatures and times come from the record too. Total for finite fields
/// (no throw); a non-finite or out-of-range field gives an unspecified integer in its place.
std::string format_state_record(const StateRecord& record);

}  // namespace shelfcross::verification
