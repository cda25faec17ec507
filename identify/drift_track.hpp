#pragma once
// The intensity of a random walk seen through white noise: the barometer's drift d as
// baro - tof shows it.
//
// Over a flat floor and a board of height H, baro = z + d + noise and tof = tof_ground + z -
// rest - H u + noise (plant/tello_senses.hpp), so
//     w = baro - tof - H u = c + d + e,   e white of variance s^2,
// the drone's own height z cancelling as it does in h - tof. d is a random walk of intensity q
// (Var(d(t + dt) - d(t)) = q^2 dt). s is taken from consecutive differences (E[(w_k -
// w_k-1)^2] = 2 s^2 + q^2 dt, the walk's share a few per cent at 10 Hz), q as the maximum of
// the likelihood of the Kalman filter's innovations (state d, the offset c in its diffuse start)
// over a log grid from 0.1 to 50 mm/sqrt(s), or 0 when no walk beats none.

#include <vector>

namespace shelfcross::identify {

struct WalkIntensity {
  double white_m = 0.0;                 ///< s; 0: fewer than 20 records, nothing estimated
  double intensity_m_per_sqrt_s = 0.0;  ///< q
};

/// s and q of the readings w_m at the increasing times t_s.
WalkIntensity walk_intensity(const std::vector<double>& t_s, const std::vector<double>& w_m);

}  // namespace shelfcross::identify
