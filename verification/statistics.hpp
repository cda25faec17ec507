#pragma once
// Campaign statistics: the success rate's confidence bound and percentile summaries.

#include <cstdint>
#include <string>
#include <vector>

namespace shelfcross::verification {

/// One-sided lower confidence bound of a binomial success probability (Clopper-Pearson):
/// the largest p_L with P(X >= successes | p_L) <= 1 - confidence, i.e. the (1 - confidence)
/// quantile of Beta(successes, trials - successes + 1). 0 when successes == 0.
/// Example: 299 successes in 299 trials at 95 % gives 0.05^(1/299) = 0.99003.
double clopper_pearson_lower(std::int64_t successes, std::int64_t trials, double confidence = 0.95);

/// One-sided upper confidence bound of a binomial event probability (Clopper-Pearson): the
/// smallest p_U with P(X <= events | p_U) <= 1 - confidence, i.e. the confidence quantile of
/// Beta(events + 1, trials - events). 1 when events == trials; with no event it is
/// 1 - (1 - confidence)^(1 / trials): 0 contacts in 2,995 runs bound the contact probability
/// below 0.1 % at 95 %, 0 in 299 below 1 %.
double clopper_pearson_upper(std::int64_t events, std::int64_t trials, double confidence = 0.95);

/// Safety apart from mission success: what each run outcome (cosim.hpp's names)
/// means for the hardware. A contact (the vehicle touched a shelf, "collision", or a wall,
/// "left_arena") is the safety failure; a safe abort ("mission_aborted", "no_crossing": the
/// flight software gave up and landed without touching anything) is only a lost mission; an
/// inventory error ("inventory_mismatch") is a mission flown safely with a wrong inventory;
/// other failures ("timeout", "numerical_failure", "flight_software_exception", anything
/// unknown) say nothing either way and are counted apart.
enum class RunSafetyClass { success, contact, safe_abort, inventory_error, other_failure };
RunSafetyClass classify_outcome(const std::string& outcome);

struct SafetySummary {
  std::int64_t runs = 0;
  std::int64_t contacts = 0;
  std::int64_t shelf_contacts = 0;  ///< of which with a shelf ("collision")
  std::int64_t safe_aborts = 0;
  std::int64_t inventory_errors = 0;
  std::int64_t other_failures = 0;
  double contact_rate = 0.0;
  double contact_upper_95 = 1.0;  ///< one-sided Clopper-Pearson upper bound at 95 %
};
SafetySummary summarize_safety(const std::vector<std::string>& outcomes);

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
