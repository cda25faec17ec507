#pragma once
// Campaign statistics: the success rate's confidence bound and percentile summaries.

#include <cstdint>
#include <vector>

namespace shelfcross::verification {

/// One-sided lower confidence bound of a binomial success probability (Clopper-Pearson):
/// the largest p_L with P(X >= successes | p_L) <= 1 - confidence, i.e. the (1 - confidence)
/// quantile of Beta(successes, trials - successes + 1). 0 when successes == 0.
/// Example: 299 successes in 299 trials at 95 % gives 0.05^(1/299) = 0.99003.
double clopper_pearson_lower(std::int64_t successes, std::int64_t trials, double confidence = 0.95);

/// Distribution summary of one metric over a campaign's runs (values that exist).
struct Summary {
  std::int64_t count = 0;
  double mean = 0.0;
  double min = 0.0;
  double p50 = 0.0;
  double p95 = 0.0;
  double p99 = 0.0;
  double max = 0.0;
};

/// Percentiles by linear interpolation between order statistics (Hyndman & Fan type 7, the
/// default of R and NumPy): q-quantile at rank (n - 1) q. An empty input gives count 0.
Summary summarize(std::vector<double> values);

}  // namespace shelfcross::verification
