#include "plant/mixer.hpp"

#include <algorithm>
#include <cmath>

#include "plant/dynamics.hpp"

namespace shelfcross::plant {

Eigen::Vector4d mix_rotor_speeds(const VehicleParams& vehicle, double thrust_N, const Eigen::Vector3d& tau,
                                 bool& saturated) {
  const double b = vehicle.thrust_coeff_N_per_radps2;
  const double k = vehicle.torque_coeff_Nm_per_radps2 / b;
  const double f_min = b * vehicle.rotor_speed_min_radps * vehicle.rotor_speed_min_radps;
  const double f_max = b * vehicle.rotor_speed_max_radps * vehicle.rotor_speed_max_radps;
  Eigen::Vector4d f_rp, f_y;
  for (int i = 0; i < 4; ++i) {
    f_rp[i] = kRotorSy[i] * tau.x() / (4.0 * vehicle.arm_y_m) - kRotorSx[i] * tau.y() / (4.0 * vehicle.arm_x_m);
    f_y[i] = -kRotorSpin[i] * tau.z() / (4.0 * k);
  }
  double f_t = thrust_N / 4.0;
  saturated = false;
  // 1. Roll and pitch must fit: scale them down if their spread exceeds the range.
  const double spread = f_rp.maxCoeff() - f_rp.minCoeff();
  if (spread > f_max - f_min) {
    f_rp *= (f_max - f_min) / spread;
    saturated = true;
  }
  // 2. Shift the collective so roll and pitch fit.
  const double lo = f_t + f_rp.minCoeff(), hi = f_t + f_rp.maxCoeff();
  if (lo < f_min) { f_t += f_min - lo; saturated = true; }
  if (hi > f_max) { f_t -= hi - f_max; saturated = true; }
  // 3. Yaw gets what is left: the largest scale s in [0, 1] keeping every rotor in range.
  double s = 1.0;
  for (int i = 0; i < 4; ++i) {
    const double base = f_t + f_rp[i];
    if (f_y[i] > 0.0) s = std::min(s, (f_max - base) / f_y[i]);
    if (f_y[i] < 0.0) s = std::min(s, (f_min - base) / f_y[i]);
  }
  s = std::clamp(s, 0.0, 1.0);
  if (s < 1.0) saturated = true;
  Eigen::Vector4d cmd;
  for (int i = 0; i < 4; ++i) {
    const double fi = std::clamp(f_t + f_rp[i] + s * f_y[i], f_min, f_max);
    cmd[i] = std::sqrt(fi / b);
  }
  return cmd;
}

}  // namespace shelfcross::plant
