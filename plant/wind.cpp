#include "plant/wind.hpp"

#include <cassert>
#include <cmath>
#include <stdexcept>

namespace shelfcross::plant {

WindModel::WindModel(const WindParams& params, std::uint64_t seed)
    : params_(params), seed_(seed), period_ns_(seconds_to_ns(params.gust_sample_period_s)),
      rng_(seed, StreamId::wind) {
  if (!(params.gust_sample_period_s > 0.0) || period_ns_ <= 0)
    throw std::invalid_argument("wind: gust_sample_period_s must be > 0");
  if (!(params.gust_time_constant_s > 0.0)) throw std::invalid_argument("wind: gust_time_constant_s must be > 0");
  if (!(params.gust_stddev_mps >= 0.0)) throw std::invalid_argument("wind: gust_stddev_mps must be >= 0");
  a_ = std::exp(-params.gust_sample_period_s / params.gust_time_constant_s);
  innovation_ = params.gust_stddev_mps * std::sqrt(1.0 - a_ * a_);
  restart();
}

void WindModel::restart() {
  rng_ = RandomStream(seed_, StreamId::wind);
  index_ = 0;
  for (int i = 0; i < 3; ++i) gust_[i] = params_.gust_stddev_mps * rng_.normal();
}

Eigen::Vector3d WindModel::wind_W_mps(TimeNs t_ns) {
  assert(t_ns >= 0);
  if (params_.gust_stddev_mps == 0.0) return params_.steady_W_mps;
  const std::int64_t k = t_ns / period_ns_;
  if (k < index_) restart();
  while (index_ < k) {
    for (int i = 0; i < 3; ++i) gust_[i] = a_ * gust_[i] + innovation_ * rng_.normal();
    ++index_;
  }
  return params_.steady_W_mps + gust_;
}

}  // namespace shelfcross::plant
