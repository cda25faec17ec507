#pragma once
// The messages between the flight software and a Tello-class vehicle: exactly what any
// client of the Tello text SDK gets and sends (see docs/tello_sdk.md), nothing more.
// Ground truth never travels in these types.
//
// Units: SI inside (m, m/s, rad, s). The SDK's cm, dm/s, degrees and -100..100 sticks exist
// only in the command and reply text and in the state-record text, at the SDK boundary.
// A producer of StateRecord (the simulator, or the driver parsing the drone's datagrams)
// keeps the SDK's resolution: integer degrees, integer dm/s, integer cm.

#include <optional>
#include <string>

#include "shelfcross/time.hpp"

namespace shelfcross {

/// One SDK command as sent on the wire, e.g. "takeoff", "rc 0 50 0 0", "battery?".
/// `t_ns` is when the flight software issued it (the stamp of the input that caused it).
/// Stick order and signs of `rc a b c d` are the SDK's: a right, b forward, c up,
/// d clockwise seen from above; each an integer in -100..100.
struct SdkCommand {
  TimeNs t_ns = 0;
  std::string text;
  bool operator==(const SdkCommand&) const = default;
};

/// One reply datagram as received, trailing "\r\n" removed: "ok", "error Not joystick",
/// "87", "3dm", ... Replies carry no tag naming their command (docs/tello_sdk.md).
struct SdkReply {
  TimeNs t_ns = 0;  ///< receive time
  std::string text;
  bool operator==(const SdkReply&) const = default;
};

/// One state record (the drone's 10 Hz push on port 8890), converted to SI and to this
/// project's frames: body B is x forward, y left, z up; attitude is the ZYX (yaw, pitch, roll)
/// Euler decomposition of R_WB, so roll > 0 lowers the right side, pitch > 0 lowers the nose,
/// yaw > 0 turns left (counter-clockwise seen from above). The Tello reports degrees with yaw
/// clockwise-positive; the parser converts. Yaw is relative to the heading at power-on.
struct StateRecord {
  TimeNs t_ns = 0;  ///< receive time

  double roll_rad = 0.0;
  double pitch_rad = 0.0;
  double yaw_rad = 0.0;

  /// Velocity estimate (vgx, vgy, vgz) in the heading frame H (x forward along the current
  /// heading, y left, z up), m/s at the SDK's 0.1 m/s resolution.
  double vx_H_mps = 0.0;
  double vy_H_mps = 0.0;
  double vz_H_mps = 0.0;

  /// Specific force measured by the IMU (agx, agy, agz) in the body frame, m/s^2.
  /// At rest it points up: about (0, 0, +9.81).
  double ax_B_mps2 = 0.0;
  double ay_B_mps2 = 0.0;
  double az_B_mps2 = 0.0;

  /// Height above the take-off point from the barometer/vision fusion (h), m.
  double height_m = 0.0;
  /// Time-of-flight range to the ground (tof), m; empty when the sensor reports invalid.
  std::optional<double> tof_m;
  /// Barometric altitude (baro), m, noisy and unreferenced; empty when not reported.
  std::optional<double> baro_m;
  /// Battery charge, percent 0..100.
  int battery_pct = 100;
  /// Motor-on time (time), s.
  double motor_time_s = 0.0;
  /// Lowest and highest board temperature (templ, temph), degrees Celsius.
  double temp_low_c = 0.0;
  double temp_high_c = 0.0;

  bool operator==(const StateRecord&) const = default;
};

}  // namespace shelfcross
