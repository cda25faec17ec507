#pragma once
// The dispersion distributions that tests build by hand (uniform, normal, truncated normal),
// for the scenario's tests and for those of the rooms after it (search).

#include "verification/scenario/distribution.hpp"

namespace shelfcross::verification::test {

/// Uniform on [lo, hi].
inline Distribution uniform(double lo, double hi) {
  Distribution d;
  d.kind = Distribution::Kind::uniform;
  d.min = lo;
  d.max = hi;
  return d;
}

/// Normal of this mean and standard deviation (unbounded).
inline Distribution normal(double mean, double stddev) {
  Distribution d;
  d.kind = Distribution::Kind::normal;
  d.mean = mean;
  d.stddev = stddev;
  return d;
}

/// Normal of this mean and standard deviation, truncated to [lo, hi].
inline Distribution truncated(double mean, double stddev, double lo, double hi) {
  Distribution d = normal(mean, stddev);
  d.kind = Distribution::Kind::truncated_normal;
  d.min = lo;
  d.max = hi;
  return d;
}

}  // namespace shelfcross::verification::test
