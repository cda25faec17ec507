#include "verification/statistics/statistics.hpp"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <numeric>
#include <sstream>
#include <stdexcept>

#include <boost/math/distributions/beta.hpp>
#include <boost/math/distributions/binomial.hpp>
#include <boost/math/distributions/normal.hpp>

namespace shelfcross::verification {

std::string fixed_text(double v, int decimals) {
  std::ostringstream s;
  s << std::fixed << std::setprecision(decimals) << v;
  return s.str();
}

double clopper_pearson_lower(std::int64_t successes, std::int64_t trials, double confidence) {
  if (trials <= 0 || successes < 0 || successes > trials || !(confidence > 0.0 && confidence < 1.0)) {
    throw std::invalid_argument("clopper_pearson_lower: need 0 <= successes <= trials, trials > 0");
  }
  if (successes == 0) return 0.0;
  const boost::math::beta_distribution<double> beta(static_cast<double>(successes),
                                                    static_cast<double>(trials - successes + 1));
  return boost::math::quantile(beta, 1.0 - confidence);
}

double clopper_pearson_upper(std::int64_t events, std::int64_t trials, double confidence) {
  if (trials <= 0 || events < 0 || events > trials || !(confidence > 0.0 && confidence < 1.0)) {
    throw std::invalid_argument("clopper_pearson_upper: need 0 <= events <= trials, trials > 0");
  }
  // By symmetry: the upper bound of p for `events` is 1 - the lower bound of 1 - p for the
  // trials - events non-events.
  if (events == trials) return 1.0;
  const boost::math::beta_distribution<double> beta(static_cast<double>(events + 1),
                                                    static_cast<double>(trials - events));
  return boost::math::quantile(beta, confidence);
}

RunSafetyClass classify_outcome(const std::string& outcome) {
  if (outcome == "success") return RunSafetyClass::success;
  if (outcome == "collision" || outcome == "left_arena") return RunSafetyClass::contact;
  if (outcome == "mission_aborted" || outcome == "no_crossing") return RunSafetyClass::safe_abort;
  if (outcome == "inventory_mismatch") return RunSafetyClass::inventory_error;
  return RunSafetyClass::other_failure;
}

SafetySummary summarize_safety(const std::vector<std::string>& outcomes) {
  SafetySummary s;
  s.runs = static_cast<std::int64_t>(outcomes.size());
  for (const std::string& o : outcomes) {
    switch (classify_outcome(o)) {
      case RunSafetyClass::success: break;
      case RunSafetyClass::contact:
        ++s.contacts;
        s.shelf_contacts += o == "collision";
        break;
      case RunSafetyClass::safe_abort: ++s.safe_aborts; break;
      case RunSafetyClass::inventory_error: ++s.inventory_errors; break;
      case RunSafetyClass::other_failure: ++s.other_failures; break;
    }
  }
  if (s.runs > 0) {
    s.contact_rate = static_cast<double>(s.contacts) / static_cast<double>(s.runs);
    s.contact_upper_95 = clopper_pearson_upper(s.contacts, s.runs, 0.95);
  }
  return s;
}

Summary summarize(std::vector<double> values) {
  Summary s;
  s.count = static_cast<std::int64_t>(values.size());
  if (values.empty()) return s;
  std::sort(values.begin(), values.end());
  const auto quantile = [&](double q) {
    const double rank = q * static_cast<double>(values.size() - 1);
    const auto lo = static_cast<size_t>(std::floor(rank));
    const size_t hi = std::min(lo + 1, values.size() - 1);
    return values[lo] + (rank - static_cast<double>(lo)) * (values[hi] - values[lo]);
  };
  s.mean = std::accumulate(values.begin(), values.end(), 0.0) / static_cast<double>(values.size());
  s.min = values.front();
  s.max = values.back();
  s.p50 = quantile(0.50);
  s.p95 = quantile(0.95);
  s.p99 = quantile(0.99);
  return s;
}

McNemarTest mcnemar_exact(const PairedTable& t) {
  if (t.both < 0 || t.base_only < 0 || t.new_only < 0 || t.neither < 0) {
    throw std::invalid_argument("mcnemar_exact: negative count");
  }
  McNemarTest out;
  out.discordant = t.base_only + t.new_only;
  if (out.discordant == 0) return out;
  const boost::math::binomial_distribution<double> x(static_cast<double>(out.discordant), 0.5);
  // P(X >= k) = 1 - P(X <= k - 1); boost's complement keeps the small tail exact.
  out.p_new_worse = t.new_only == 0 ? 1.0 : boost::math::cdf(boost::math::complement(x, static_cast<double>(t.new_only - 1)));
  const double smaller = static_cast<double>(std::min(t.base_only, t.new_only));
  out.p_two_sided = std::min(1.0, 2.0 * boost::math::cdf(x, smaller));
  return out;
}

namespace {
double normal_quantile_two_sided(double confidence) {
  if (!(confidence > 0.0 && confidence < 1.0)) throw std::invalid_argument("confidence must be in (0, 1)");
  return boost::math::quantile(boost::math::normal_distribution<double>(), 0.5 * (1.0 + confidence));
}
}  // namespace

Interval wilson_interval(std::int64_t k, std::int64_t n, double confidence) {
  if (n <= 0 || k < 0 || k > n) throw std::invalid_argument("wilson_interval: need 0 <= k <= n, n > 0");
  const double z = normal_quantile_two_sided(confidence);
  const double nn = static_cast<double>(n), p = static_cast<double>(k) / nn, z2 = z * z;
  const double denominator = 1.0 + z2 / nn;
  const double centre = (p + z2 / (2.0 * nn)) / denominator;
  const double half = z * std::sqrt(p * (1.0 - p) / nn + z2 / (4.0 * nn * nn)) / denominator;
  // At k = 0 (k = n) the lower (upper) limit is exactly 0 (1): centre and half are equal there
  // but for rounding.
  return {k == 0 ? 0.0 : std::max(0.0, centre - half), k == n ? 1.0 : std::min(1.0, centre + half)};
}

Interval newcombe_paired_difference(const PairedTable& t, double confidence) {
  const std::int64_t n = t.pairs();
  if (n <= 0) throw std::invalid_argument("newcombe_paired_difference: empty table");
  // Newcombe's a, b, c, d with NEW the first classification: b = NEW only, c = BASE only.
  const double a = static_cast<double>(t.both), b = static_cast<double>(t.new_only),
               c = static_cast<double>(t.base_only), d = static_cast<double>(t.neither), nn = static_cast<double>(n);
  const double p_new = (a + b) / nn, p_base = (a + c) / nn, difference = p_new - p_base;
  const Interval w_new = wilson_interval(t.both + t.new_only, n, confidence);
  const Interval w_base = wilson_interval(t.both + t.base_only, n, confidence);
  const double margins = (a + b) * (c + d) * (a + c) * (b + d);
  double phi = 0.0;
  if (margins > 0.0) {
    const double cross = a * d - b * c;
    const double corrected = cross > nn / 2.0 ? cross - nn / 2.0 : (cross < 0.0 ? cross : 0.0);
    phi = corrected / std::sqrt(margins);
  }
  const auto root = [phi](double x, double y) { return std::sqrt(std::max(0.0, x * x - 2.0 * phi * x * y + y * y)); };
  return {difference - root(p_new - w_new.lower, w_base.upper - p_base),
          difference + root(w_new.upper - p_new, p_base - w_base.lower)};
}

namespace {

/// The null distribution of the signed-rank sum W+ of m untied nonzero differences: counts of
/// the subsets of {1..m} by their sum s (0..m(m+1)/2), each of probability 2^-m. Exact in
/// doubles up to m = 52.
std::vector<double> signed_rank_counts(std::int64_t m) {
  const auto total = static_cast<size_t>(m * (m + 1) / 2);
  std::vector<double> count(total + 1, 0.0);
  count[0] = 1.0;
  for (std::int64_t r = 1; r <= m; ++r) {
    for (size_t s = total; s >= static_cast<size_t>(r); --s) count[s] += count[s - static_cast<size_t>(r)];
  }
  return count;
}

constexpr std::int64_t kExactSignedRankMax = 50;

/// The critical count C of the Walsh-average interval for n differences: the largest C >= 1
/// with P(W+ <= C - 1) <= (1 - confidence) / 2 (1 when none is).
std::int64_t walsh_critical_count(std::int64_t n, double confidence) {
  const double tail = 0.5 * (1.0 - confidence);
  const std::int64_t walsh = n * (n + 1) / 2;
  if (n <= kExactSignedRankMax) {
    const std::vector<double> count = signed_rank_counts(n);
    const double all = std::ldexp(1.0, static_cast<int>(n));
    double cdf = 0.0;
    std::int64_t c = 0;  // P(W+ <= c - 1) so far, for c = 0, 1, ...
    while (c < walsh && (cdf + count[static_cast<size_t>(c)]) / all <= tail) cdf += count[static_cast<size_t>(c++)];
    return std::max<std::int64_t>(1, c);
  }
  const double nn = static_cast<double>(n);
  const double c = nn * (nn + 1.0) / 4.0 - normal_quantile_two_sided(confidence) *
                                               std::sqrt(nn * (nn + 1.0) * (2.0 * nn + 1.0) / 24.0);
  return std::clamp<std::int64_t>(static_cast<std::int64_t>(std::floor(c)), 1, walsh);
}

/// The two-sided signed-rank p-value of the nonzero differences (see the header).
double signed_rank_p(std::vector<double> nonzero) {
  const auto m = static_cast<std::int64_t>(nonzero.size());
  if (m == 0) return 1.0;
  std::sort(nonzero.begin(), nonzero.end(), [](double x, double y) { return std::abs(x) < std::abs(y); });
  double w_plus = 0.0, tie_term = 0.0;  // tie_term: sum over tied groups of t^3 - t
  for (size_t i = 0; i < nonzero.size();) {
    size_t j = i;
    while (j < nonzero.size() && std::abs(nonzero[j]) == std::abs(nonzero[i])) ++j;
    const double mid_rank = 0.5 * static_cast<double>(i + 1 + j);  // ranks i+1 .. j
    for (size_t k = i; k < j; ++k) w_plus += nonzero[k] > 0.0 ? mid_rank : 0.0;
    const double t = static_cast<double>(j - i);
    tie_term += t * t * t - t;
    i = j;
  }
  const double mm = static_cast<double>(m), mean = mm * (mm + 1.0) / 4.0;
  if (m <= kExactSignedRankMax && tie_term == 0.0) {
    const std::vector<double> count = signed_rank_counts(m);
    const double all = std::ldexp(1.0, static_cast<int>(m));
    const auto w = static_cast<size_t>(std::llround(w_plus));
    double lower = 0.0, upper = 0.0;
    for (size_t s = 0; s < count.size(); ++s) (s <= w ? lower : upper) += count[s];
    upper += count[w];  // P(W+ >= w) includes w
    return std::min(1.0, 2.0 * std::min(lower, upper) / all);
  }
  const double variance = mm * (mm + 1.0) * (2.0 * mm + 1.0) / 24.0 - tie_term / 48.0;
  if (variance <= 0.0) return 1.0;
  const double z = std::max(0.0, std::abs(w_plus - mean) - 0.5) / std::sqrt(variance);
  return std::min(1.0, 2.0 * boost::math::cdf(boost::math::complement(boost::math::normal_distribution<double>(), z)));
}

}  // namespace

SignedRankResult wilcoxon_signed_rank(const std::vector<double>& d, double confidence) {
  if (d.empty()) throw std::invalid_argument("wilcoxon_signed_rank: no differences");
  for (double v : d) {
    if (!std::isfinite(v)) throw std::invalid_argument("wilcoxon_signed_rank: a difference is not finite");
  }
  SignedRankResult r;
  r.n = static_cast<std::int64_t>(d.size());
  r.median = summarize(d).p50;
  std::vector<double> nonzero;
  for (double v : d) {
    if (v != 0.0) nonzero.push_back(v);
  }
  r.nonzero = static_cast<std::int64_t>(nonzero.size());
  r.p_two_sided = signed_rank_p(std::move(nonzero));
  // Walsh averages, i <= j: N = n(n+1)/2 (4.5 million for 3,000 runs).
  std::vector<double> walsh;
  walsh.reserve(d.size() * (d.size() + 1) / 2);
  for (size_t i = 0; i < d.size(); ++i) {
    for (size_t j = i; j < d.size(); ++j) walsh.push_back(0.5 * (d[i] + d[j]));
  }
  const auto order_statistic = [&walsh](std::int64_t rank) {  // 1-based
    const auto at = walsh.begin() + (rank - 1);
    std::nth_element(walsh.begin(), at, walsh.end());
    return *at;
  };
  const auto count = static_cast<std::int64_t>(walsh.size());
  r.hodges_lehmann = count % 2 == 1 ? order_statistic((count + 1) / 2)
                                    : 0.5 * (order_statistic(count / 2) + order_statistic(count / 2 + 1));
  const std::int64_t c = walsh_critical_count(r.n, confidence);
  r.interval = {order_statistic(c), order_statistic(count + 1 - c)};
  return r;
}

}  // namespace shelfcross::verification
