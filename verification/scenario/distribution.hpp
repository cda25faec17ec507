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
//
// Densities (log_pdf) are those of the draws: uniform 1 / (max - min) on [min, max]; normal
// phi((x - mean) / stddev) / stddev; truncated normal the same divided by its mass on the
// support, Z = Phi((max - mean) / stddev) - Phi((min - mean) / stddev); choice the summed
// normalised weights of the values equal to x (a probability mass). A zero-width support
// (min == max, stddev == 0) is a point mass: log density 0 at the point. Outside the
// support: -infinity.
//
// Proposals (rare-event search, rare_event.hpp) draw from another member of the same family
// on the nominal's support: continuous_proposal gives a truncated normal on [min, max] for a
// uniform or truncated-normal nominal (a normal on the real line for a normal nominal);
// choice_proposal reweights the same values. A ProposalDistribution mixes such a member with
// the nominal itself (a defensive mixture, Hesterberg 1995), so that the likelihood ratio
// nominal / proposal of one parameter never exceeds 1 / nominal_share.

#include <string>
#include <vector>

#include "shelfcross/random.hpp"

namespace shelfcross::config {
class Map;  // config/strict_yaml.hpp: read only where a scenario is parsed
}  // namespace shelfcross::config

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
  /// Log density at x (log probability mass for choice); -infinity outside the support.
  double log_pdf(double x) const;
  /// A spread of the distribution, for scaling proposals: the standard deviation of the draws
  /// (uniform: (max - min) / sqrt(12); truncated normal: its parent's stddev capped at the
  /// uniform's on the same support; choice: of the values under the weights).
  double scale() const;
  bool is_choice() const { return kind == Kind::choice; }
  bool operator==(const Distribution&) const = default;
};

/// A proposal of `nominal`'s family on its support (see the file comment): truncated normal
/// (mean, stddev) on [min, max] for uniform and truncated-normal nominals, normal (mean,
/// stddev) for a normal one. Preconditions: nominal is continuous, stddev > 0.
Distribution continuous_proposal(const Distribution& nominal, double mean, double stddev);
/// The nominal choice's values with other weights (same length, every weight > 0).
Distribution choice_proposal(const Distribution& nominal, std::vector<double> weights);

/// The defensive mixture q_mix = (1 - s) q + s f of a proposal q (`shifted`, of f's family on
/// f's support) and the nominal f, s = nominal_share in [0, 1]: q_mix >= s f, f / q_mix <= 1 / s (s = 0: q).
/// A draw takes one uniform to pick the component (u < s: the nominal), then that component's
/// draw; with s = 1 it is the nominal's draw alone (no selector), so a proposal equal to the
/// nominal draws exactly the nominal's values from the same stream.
struct ProposalDistribution {
  Distribution shifted;
  Distribution nominal;
  double nominal_share = 1.0;

  /// The nominal itself, as a proposal.
  static ProposalDistribution of_nominal(const Distribution& nominal) { return {nominal, nominal, 1.0}; }
  double sample(RandomStream& stream) const;
  /// log((1 - s) q(x) + s f(x)), by log-sum-exp.
  double log_pdf(double x) const;
  bool operator==(const ProposalDistribution&) const = default;
};

/// Reads `parent[key]` as a distribution; refuses unknown kinds, bad parameters (min > max,
/// stddev < 0, empty or negative-weight choices) with file:line.
Distribution parse_distribution(const config::Map& parent, const std::string& key);

}  // namespace shelfcross::verification
