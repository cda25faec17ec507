#pragma once
// Campaign statistics: the success rate's confidence bound and percentile summaries.

#include <cstdint>
#include <string>
#include <vector>

namespace shelfcross::verification {

/// v with `decimals` digits after the point (std::fixed): how the reports print a figure.
std::string fixed_text(double v, int decimals);

/// One-sided lower confidence bound of a binomial success probability (Clopper-Pearson):
/// the largest p_L with P(X >= successes | p_L) <= 1 - confidence, i.e. the (1 - confidence)
/// quantile of Beta(successes, trials - successes + 1). 0 when successes == 0.
/// Example: 299 successes in 299 trials at 95 % gives 0.05^(1/299) = 0.99003. Throws
/// std::invalid_argument unless 0 <= successes <= trials, trials > 0.
double clopper_pearson_lower(std::int64_t successes, std::int64_t trials, double confidence = 0.95);

/// One-sided upper confidence bound of a binomial event probability (Clopper-Pearson): the
/// smallest p_U with P(X <= events | p_U) <= 1 - confidence, i.e. the confidence quantile of
/// Beta(events + 1, trials - events). 1 when events == trials; with no event it is
/// 1 - (1 - confidence)^(1 / trials): 0 contacts in 2,995 runs bound the contact probability
/// below 0.1 % at 95 %, 0 in 299 below 1 %. Throws std::invalid_argument unless
/// 0 <= events <= trials, trials > 0.
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

// ---- Paired comparisons: the same runs (same seeds, same draws) flown by two builds ----------
// Two campaigns on the same seeds are not independent samples: each run is a pair, and the
// tests below use the pairing (shelfcross diff, verification/report/paired_diff.hpp).

/// A paired 2 x 2 table of one yes/no event (a failed mission, a contact) in BASE and in NEW.
struct PairedTable {
  std::int64_t both = 0;      ///< the event in both
  std::int64_t base_only = 0; ///< in BASE only: NEW is better on this pair
  std::int64_t new_only = 0;  ///< in NEW only: NEW is worse on this pair
  std::int64_t neither = 0;
  std::int64_t pairs() const { return both + base_only + new_only + neither; }
};

/// The exact McNemar test: under "NEW no different from BASE" each of the n = base_only +
/// new_only discordant pairs is equally likely either way, so new_only ~ Binomial(n, 1/2).
///   one-sided "NEW worse":  p = P(X >= new_only) = sum_{x >= new_only} C(n, x) / 2^n
///   two-sided:              p = min(1, 2 P(X <= min(base_only, new_only)))
/// (no discordant pair: both 1). Example: 6 pairs worse, 0 better: one-sided 1/64, two-sided 1/32.
struct McNemarTest {
  std::int64_t discordant = 0;
  double p_two_sided = 1.0;
  double p_new_worse = 1.0;
};
/// Throws std::invalid_argument on a negative count.
McNemarTest mcnemar_exact(const PairedTable& table);

/// A two-sided confidence interval.
struct Interval {
  double lower = 0.0;
  double upper = 0.0;
  bool contains(double v) const { return lower <= v && v <= upper; }
};

/// Wilson's score interval for a binomial proportion k / n (no continuity correction):
/// (p + z^2/2n -+ z sqrt(p(1-p)/n + z^2/4n^2)) / (1 + z^2/n), z the normal (1+confidence)/2 quantile.
/// Throws std::invalid_argument unless 0 <= k <= n, n > 0 and 0 < confidence < 1.
Interval wilson_interval(std::int64_t k, std::int64_t n, double confidence = 0.95);

/// The difference of the event's rates, NEW - BASE = (new_only - base_only) / n, with Newcombe's
/// hybrid score interval for paired proportions (Newcombe 1998, Stat. Med. 17:2635, method 10):
/// the Wilson intervals (l_B, u_B), (l_N, u_N) of the two marginal rates combined as
///   lower = d - sqrt((p_N - l_N)^2 - 2 phi (p_N - l_N)(u_B - p_B) + (u_B - p_B)^2)
///   upper = d + sqrt((u_N - p_N)^2 - 2 phi (u_N - p_N)(p_B - l_B) + (p_B - l_B)^2)
/// with phi the table's correlation (ad - bc) / sqrt of the four margins' product, ad - bc taken
/// as max(ad - bc - n/2, 0) when positive (Newcombe's correction) and phi 0 when a margin is 0.
/// Throws std::invalid_argument on an empty table.
Interval newcombe_paired_difference(const PairedTable& table, double confidence = 0.95);

/// Paired differences of a metric (NEW - BASE over the pairs where both have it): the Wilcoxon
/// signed-rank test of "symmetric about 0" and the Hodges-Lehmann estimate of the shift with its
/// confidence interval.
///   test: the zero differences dropped (Wilcoxon's convention), mid-ranks for ties of |d|; the
///     exact null distribution of W+ when at most 50 differences remain and none are tied, else
///     the normal approximation with the tie correction and a continuity correction of 1/2.
///   estimate: the median of the n(n+1)/2 Walsh averages (d_i + d_j)/2, i <= j, over every
///     difference, zeros included (so runs that did not move pull the estimate toward 0);
///     interval: the Walsh averages of ranks C and N + 1 - C, C the signed-rank critical count
///     (exact for n <= 50, normal beyond), as in Hollander & Wolfe, Nonparametric Statistical
///     Methods, section 3.2.
struct SignedRankResult {
  std::int64_t n = 0;           ///< differences
  std::int64_t nonzero = 0;     ///< of which not 0 (the test's)
  double median = 0.0;          ///< the plain median of the differences
  double hodges_lehmann = 0.0;  ///< the shift estimate
  Interval interval;            ///< for the shift, at the confidence asked
  double p_two_sided = 1.0;     ///< 1 when every difference is 0
};
/// Throws std::invalid_argument on an empty input or a non-finite difference.
SignedRankResult wilcoxon_signed_rank(const std::vector<double>& differences, double confidence = 0.95);

}  // namespace shelfcross::verification
