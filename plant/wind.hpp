#pragma once
// Wind: a steady world-frame velocity plus Ornstein-Uhlenbeck gusts from a seeded stream.
//
// The gust process lives on a fixed time grid t_k = k * gust_sample_period_s, independent of how
// often it is queried, so the wind a run sees depends only on (params, seed):
//   g_0 ~ N(0, sigma^2),  g_{k+1} = a g_k + sigma sqrt(1 - a^2) n_k,  a = exp(-h / tau)
// (the exact discretisation of dg = -g/tau dt + sigma sqrt(2/tau) dW), per axis. Normal draws
// come from the project's seeded stream (shelfcross/random.hpp, StreamId::wind), bit-identical
// across standard libraries. wind(t) is the sample of the grid interval that holds t.

#include <cstdint>

#include <Eigen/Core>

#include "plant/params.hpp"
#include "shelfcross/random.hpp"
#include "shelfcross/time.hpp"

namespace shelfcross::plant {

class WindModel {
 public:
  /// Throws std::invalid_argument unless gust_sample_period_s > 0 (at least 1 ns),
  /// gust_time_constant_s > 0 and gust_stddev_mps >= 0. Any seed.
  WindModel(const WindParams& params, std::uint64_t seed);
  /// Wind velocity in W at t_ns; requires t_ns >= 0 (asserted). Queries may go in any order
  /// (going back replays the stream from the seed). With gust_stddev_mps 0 the steady wind,
  /// drawing nothing.
  Eigen::Vector3d wind_W_mps(TimeNs t_ns);
  const WindParams& params() const { return params_; }

 private:
  void restart();
  WindParams params_;
  std::uint64_t seed_;
  TimeNs period_ns_;
  double a_ = 0.0, innovation_ = 0.0;
  RandomStream rng_;
  std::int64_t index_ = 0;
  Eigen::Vector3d gust_ = Eigen::Vector3d::Zero();
};

}  // namespace shelfcross::plant
