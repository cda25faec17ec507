#include "identify/drift_track.hpp"

#include <algorithm>
#include <cmath>

namespace shelfcross::identify {
namespace {

// The log-likelihood of the innovations of the Kalman filter of x_k = x_k-1 + q sqrt(dt)
// N(0, 1), w_k = x_k + s N(0, 1); the first record starts it (the diffuse offset: its own
// innovation is not counted).
double innovations_loglik(const std::vector<double>& t, const std::vector<double>& w, double q, double s) {
  const double s2 = s * s;
  double x = w[0], p = s2, l = 0.0;
  for (size_t k = 1; k < t.size(); ++k) {
    const double predicted = p + q * q * std::max(0.0, t[k] - t[k - 1]);
    const double innovation = w[k] - x, var = predicted + s2;
    l -= 0.5 * (std::log(var) + innovation * innovation / var);
    const double gain = predicted / var;
    x += gain * innovation;
    p = (1.0 - gain) * predicted;
  }
  return l;
}

}  // namespace

WalkIntensity walk_intensity(const std::vector<double>& t_s, const std::vector<double>& w_m) {
  WalkIntensity out;
  if (t_s.size() < 20 || t_s.size() != w_m.size()) return out;
  double dw2 = 0.0;
  for (size_t k = 1; k < w_m.size(); ++k) dw2 += (w_m[k] - w_m[k - 1]) * (w_m[k] - w_m[k - 1]);
  out.white_m = std::max(1e-4, std::sqrt(dw2 / static_cast<double>(w_m.size() - 1) / 2.0));
  double best = innovations_loglik(t_s, w_m, 0.0, out.white_m);
  constexpr int kGrid = 40;
  constexpr double kLowest = 1e-4, kHighest = 0.05;
  for (int i = 0; i < kGrid; ++i) {
    const double q = kLowest * std::pow(kHighest / kLowest, i / (kGrid - 1.0));
    const double l = innovations_loglik(t_s, w_m, q, out.white_m);
    if (l > best) {
      best = l;
      out.intensity_m_per_sqrt_s = q;
    }
  }
  return out;
}

}  // namespace shelfcross::identify
