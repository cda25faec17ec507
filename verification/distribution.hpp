#pragma once
// Distributions of dispersed scenario parameters, as written in a scenario's `dispersions:`
// section, one mapping with exactly one kind:
//
//   start_distance_m: {uniform: {min: 2.5, max: 3.5}}
//   start_lateral_m:  {normal: {mean: 0.0, stddev: 0.10}}
//   start_yaw_rad:    {truncated_normal: {mean: 0.0, stddev: 0.05, min: -0.15, max: 0.15}}
//   light_scale:      {choice: {values: [0.6, 1.0, 1.4], weights: [1, 2, 1]}}
//
// Every draw takes a fixed number of uniforms from the stream (one, or two for normal), so
// the draws of one parameter never depend on the values of another.

#include <string>
#include <vector>

#include "config/strict_yaml.hpp"
#include "shelfcross/random.hpp"

namespace shelfcross::verification {

struct Distribution {
  enum class Kind { uniform, normal, truncated_normal, choice };
  Kind kind = Kind::uniform;
  double min = 0.0, max = 0.0;        ///< uniform, truncated_normal
  double mean = 0.0, stddev = 0.0;    ///< normal, truncated_normal
  std::vector<double> values;         ///< choice
  std::vector<double> weights;        ///< choice, same length, > 0

  /// One draw. truncated_normal by the inverse CDF of one uniform in [Phi(min), Phi(max)].
  double sample(RandomStream& stream) const;
  /// The support's bounds (for range checks of what a dispersion may produce).
  double lowest() const;
  double highest() const;
  bool operator==(const Distribution&) const = default;
};

/// Reads `parent[key]` as a distribution; refuses unknown kinds, bad parameters (min > max,
/// stddev < 0, empty or negative-weight choices) with file:line.
Distribution parse_distribution(const config::Map& parent, const std::string& key);

}  // namespace shelfcross::verification
