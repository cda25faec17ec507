#include "verification/distribution.hpp"

#include <algorithm>
#include <numeric>

#include <boost/math/distributions/normal.hpp>

namespace shelfcross::verification {

double Distribution::sample(RandomStream& stream) const {
  switch (kind) {
    case Kind::uniform:
      return stream.uniform(min, max);
    case Kind::normal:
      return stream.normal(mean, stddev);
    case Kind::truncated_normal: {
      if (stddev == 0.0) return std::clamp(mean, min, max);
      const boost::math::normal_distribution<double> n(mean, stddev);
      const double c_lo = boost::math::cdf(n, min);
      const double c_hi = boost::math::cdf(n, max);
      const double u = stream.uniform01();
      const double c = c_lo + u * (c_hi - c_lo);
      // Far in a tail the CDF saturates at 0 or 1; the quantile is then the bound itself.
      if (!(c > 0.0)) return min;
      if (!(c < 1.0)) return max;
      return std::clamp(boost::math::quantile(n, c), min, max);
    }
    case Kind::choice: {
      const double total = std::accumulate(weights.begin(), weights.end(), 0.0);
      double u = stream.uniform01() * total;
      for (size_t i = 0; i < values.size(); ++i) {
        if (u < weights[i]) return values[i];
        u -= weights[i];
      }
      return values.back();
    }
  }
  return mean;
}

double Distribution::lowest() const {
  switch (kind) {
    case Kind::normal: return -std::numeric_limits<double>::infinity();
    case Kind::choice: return *std::min_element(values.begin(), values.end());
    default: return min;
  }
}

double Distribution::highest() const {
  switch (kind) {
    case Kind::normal: return std::numeric_limits<double>::infinity();
    case Kind::choice: return *std::max_element(values.begin(), values.end());
    default: return max;
  }
}

Distribution parse_distribution(const config::Map& parent, const std::string& key) {
  const config::Map spec = parent.map(key);
  static const char* kKinds[] = {"uniform", "normal", "truncated_normal", "choice"};
  int found = 0;
  for (const char* k : kKinds) found += spec.has(k);
  if (found != 1) {
    parent.fail(key, "expected exactly one of uniform, normal, truncated_normal, choice");
  }
  Distribution d;
  if (spec.has("uniform")) {
    const config::Map p = spec.map("uniform");
    d.kind = Distribution::Kind::uniform;
    d.min = p.required<double>("min");
    d.max = p.required<double>("max", {.min = d.min});
    p.finish();
  } else if (spec.has("normal")) {
    const config::Map p = spec.map("normal");
    d.kind = Distribution::Kind::normal;
    d.mean = p.required<double>("mean");
    d.stddev = p.required<double>("stddev", {.min = 0.0});
    p.finish();
  } else if (spec.has("truncated_normal")) {
    const config::Map p = spec.map("truncated_normal");
    d.kind = Distribution::Kind::truncated_normal;
    d.mean = p.required<double>("mean");
    d.stddev = p.required<double>("stddev", {.min = 0.0});
    d.min = p.required<double>("min");
    d.max = p.required<double>("max", {.min = d.min});
    p.finish();
  } else {
    const config::Map p = spec.map("choice");
    d.kind = Distribution::Kind::choice;
    d.values = p.required_list<double>("values");
    if (d.values.empty()) p.fail("values", "a choice needs at least one value");
    d.weights = p.optional_list<double>("weights", std::vector<double>(d.values.size(), 1.0),
                                        {.min = 0.0, .min_exclusive = true}, d.values.size());
    p.finish();
  }
  spec.finish();
  return d;
}

}  // namespace shelfcross::verification
