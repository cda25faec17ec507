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

}  // namespace shelfcross::verification
