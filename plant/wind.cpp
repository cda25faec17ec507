#include "plant/wind.hpp"

#include <cassert>
#include <cmath>
#include <stdexcept>

namespace shelfcross::plant {

double standard_normal(std::mt19937_64& rng) {
  constexpr double kTwoPi = 6.283185307179586476925;
  constexpr double k2m53 = 1.0 / 9007199254740992.0;  // 2^-53
  const double u1 = (static_cast<double>(rng() >> 11) + 1.0) * k2m53;  // (0, 1]
  const double u2 = static_cast<double>(rng() >> 11) * k2m53;          // [0, 1)
  return std::sqrt(-2.0 * std::log(u1)) * std::cos(kTwoPi * u2);
}

WindModel::WindModel(const WindParams& params, std::uint64_t seed)
    : params_(params), seed_(seed), period_ns_(seconds_to_ns(params.gust_sample_period_s)) {
  if (!(params.gust_sample_period_s > 0.0) || period_ns_ <= 0)
    throw std::invalid_argument("wind: gust_sample_period_s must be > 0");
  if (!(params.gust_time_constant_s > 0.0)) throw std::invalid_argument("wind: gust_time_constant_s must be > 0");
  if (!(params.gust_stddev_mps >= 0.0)) throw std::invalid_argument("wind: gust_stddev_mps must be >= 0");
  a_ = std::exp(-params.gust_sample_period_s / params.gust_time_constant_s);
  innovation_ = params.gust_stddev_mps * std::sqrt(1.0 - a_ * a_);
  restart();
}

void WindModel::restart() {
  rng_.seed(seed_);
  index_ = 0;
  for (int i = 0; i < 3; ++i) gust_[i] = params_.gust_stddev_mps * standard_normal(rng_);
}

Eigen::Vector3d WindModel::wind_W_mps(TimeNs t_ns) {
  assert(t_ns >= 0);
  if (params_.gust_stddev_mps == 0.0) return params_.steady_W_mps;
  const std::int64_t k = t_ns / period_ns_;
  if (k < index_) restart();
  while (index_ < k) {
    for (int i = 0; i < 3; ++i) gust_[i] = a_ * gust_[i] + innovation_ * standard_normal(rng_);
    ++index_;
  }
  return params_.steady_W_mps + gust_;
}

}  // namespace shelfcross::plant
