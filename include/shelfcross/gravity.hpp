#pragma once
// Gravity, stated once: the simulated world's default, the Tello's accelerometer unit (the
// state record's agx, agy, agz are in thousandths of it) and the tilt a speed limit implies.

namespace shelfcross {

/// Standard gravity (CGPM 1901), m/s^2.
inline constexpr double kStandardGravity_mps2 = 9.80665;

}  // namespace shelfcross
