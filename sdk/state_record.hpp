#pragma once
// The Tello's state record (UDP port 8890) as text, SDK 1.3 and 2.0 (docs/tello_sdk.md):
//   "mid:-1;x:-100;y:-100;z:-100;mpry:-1,-1,-1;pitch:0;roll:0;yaw:0;vgx:0;vgy:0;vgz:0;
//    templ:55;temph:57;tof:6553;h:0;bat:5;baro:118.26;time:0;agx:-4.00;agy:1.00;agz:-997.00;\r\n"
//
// Sign conventions. The SDK documents none; we take the aviation convention its numbers
// follow (at rest agz is about -1000 mg, i.e. the body z axis points down): body axes
// forward-right-down, pitch > 0 nose up, roll > 0 right side down, yaw > 0 clockwise seen
// from above; vgx vgy vgz along forward, right, down of the heading frame, in dm/s;
// agx agy agz the specific force along forward, right, down, in thousandths of g.
// shelfcross's frames are forward-left-up (sdk_messages.hpp), so the conversion is
//   roll = roll_t,  pitch = -pitch_t,  yaw = -yaw_t          (degrees -> rad)
//   vx = vgx, vy = -vgy, vz = -vgz                           (dm/s -> m/s)
//   ax = agx, ay = -agy, az = -agz                           (mg -> m/s^2, g = 9.80665)
// The record's format exists here once. The parser is the ground station's side (the driver,
// flight_sw/tello); the drone's side, verification::format_state_record (the simulated Tello
// in verification/), applies the inverse, rounding the way the drone reports: integers for
// attitude, velocity, heights, battery and temperatures.

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

#include "shelfcross/gravity.hpp"
#include "shelfcross/sdk_messages.hpp"

namespace shelfcross::sdk {

/// The state record's accelerations are in thousandths of standard gravity (shelfcross/gravity.hpp).
using shelfcross::kStandardGravity_mps2;
/// tof reads this when the range sensor sees nothing valid.
inline constexpr int kTofInvalid_cm = 6553;

/// What parsing one datagram found, for the driver's counters and logs.
struct StateParseReport {
  int fields = 0;         ///< key:value pairs read
  int unknown_keys = 0;   ///< keys this parser does not use (kept out of the record)
  int missing_keys = 0;   ///< of the SDK 1.3 core set (pitch roll yaw vgx vgy vgz h bat)
  bool mission_pad = false;  ///< SDK 2.0 fields (mid x y z mpry) present
};

/// Parses one state datagram received at `t_ns`. Returns nothing for a datagram that is not
/// a state record (a stray "ok", garbage, a record with no core key, a number that does not
/// parse); the caller counts it as dropped. Unknown keys are tolerated, missing keys keep
/// the record's defaults, `mpry`'s comma-separated triple is skipped, tof 6553 is "invalid".
std::optional<StateRecord> parse_state_record(std::string_view datagram, TimeNs t_ns,
                                              StateParseReport* report = nullptr);

}  // namespace shelfcross::sdk
