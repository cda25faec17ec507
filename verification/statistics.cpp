#include "verification/statistics.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <stdexcept>

#include <boost/math/distributions/beta.hpp>

namespace shelfcross::verification {

double clopper_pearson_lower(std::int64_t successes, std::int64_t trials, double confidence) {
  if (trials <= 0 || successes < 0 || successes > trials || !(confidence > 0.0 && confidence < 1.0)) {
    throw std::invalid_argument("clopper_pearson_lower: need 0 <= successes <= trials, trials > 0");
  }
  if (successes == 0) return 0.0;
  const boost::math::beta_distribution<double> beta(static_cast<double>(successes),
                                                    static_cast<double>(trials - successes + 1));
  return boost::math::quantile(beta, 1.0 - confidence);
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

}  // namespace shelfcross::verification
