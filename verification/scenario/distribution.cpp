#include "verification/scenario/distribution.hpp"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <limits>
#include <numbers>
#include <numeric>

#include <boost/math/distributions/normal.hpp>

#include "config/strict_yaml.hpp"

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

namespace {

constexpr double kMinusInfinity = -std::numeric_limits<double>::infinity();

/// log phi((x - mean) / stddev) / stddev, the normal's log density.
double normal_log_pdf(double x, double mean, double stddev) {
  const double z = (x - mean) / stddev;
  return -0.5 * z * z - std::log(stddev) - 0.5 * std::log(2.0 * std::numbers::pi);
}

/// log (Phi(b) - Phi(a)) for standardised bounds a < b, accurate in either tail: above the
/// mean through the complements (Phi(-a) - Phi(-b)), so a mass of 1e-20 far out is not lost
/// to 1 - 1 cancellation.
double log_normal_mass(double a, double b) {
  const boost::math::normal_distribution<double> unit;
  double mass = 0.0;
  if (a > 0.0) {
    mass = boost::math::cdf(boost::math::complement(unit, a)) - boost::math::cdf(boost::math::complement(unit, b));
  } else {
    mass = boost::math::cdf(unit, b) - boost::math::cdf(unit, a);
  }
  return std::log(mass);
}

}  // namespace

double Distribution::log_pdf(double x) const {
  switch (kind) {
    case Kind::uniform:
      if (x < min || x > max) return kMinusInfinity;
      return max > min ? -std::log(max - min) : 0.0;
    case Kind::normal:
      if (stddev == 0.0) return x == mean ? 0.0 : kMinusInfinity;
      return normal_log_pdf(x, mean, stddev);
    case Kind::truncated_normal: {
      if (x < min || x > max) return kMinusInfinity;
      if (min == max) return 0.0;
      if (stddev == 0.0) return x == std::clamp(mean, min, max) ? 0.0 : kMinusInfinity;
      return normal_log_pdf(x, mean, stddev) - log_normal_mass((min - mean) / stddev, (max - mean) / stddev);
    }
    case Kind::choice: {
      const double total = std::accumulate(weights.begin(), weights.end(), 0.0);
      double mass = 0.0;
      for (size_t i = 0; i < values.size(); ++i) {
        if (values[i] == x) mass += weights[i];
      }
      return mass > 0.0 ? std::log(mass / total) : kMinusInfinity;
    }
  }
  return kMinusInfinity;
}

double Distribution::scale() const {
  switch (kind) {
    case Kind::uniform:
      return (max - min) / std::sqrt(12.0);
    case Kind::normal:
      return stddev;
    case Kind::truncated_normal:
      return std::min(stddev, (max - min) / std::sqrt(12.0));
    case Kind::choice: {
      const double total = std::accumulate(weights.begin(), weights.end(), 0.0);
      double m1 = 0.0, m2 = 0.0;
      for (size_t i = 0; i < values.size(); ++i) {
        m1 += weights[i] / total * values[i];
        m2 += weights[i] / total * values[i] * values[i];
      }
      return std::sqrt(std::max(0.0, m2 - m1 * m1));
    }
  }
  return 0.0;
}

Distribution continuous_proposal(const Distribution& nominal, double mean, double stddev) {
  assert(!nominal.is_choice() && stddev > 0.0);
  Distribution d;
  d.mean = mean;
  d.stddev = stddev;
  if (nominal.kind == Distribution::Kind::normal) {
    d.kind = Distribution::Kind::normal;
  } else {
    d.kind = Distribution::Kind::truncated_normal;
    d.min = nominal.min;
    d.max = nominal.max;
  }
  return d;
}

Distribution choice_proposal(const Distribution& nominal, std::vector<double> weights) {
  assert(nominal.is_choice() && weights.size() == nominal.values.size());
  assert(std::all_of(weights.begin(), weights.end(), [](double w) { return w > 0.0; }));
  Distribution d = nominal;
  d.weights = std::move(weights);
  return d;
}

double ProposalDistribution::sample(RandomStream& stream) const {
  if (nominal_share >= 1.0) return nominal.sample(stream);
  return stream.uniform01() < nominal_share ? nominal.sample(stream) : shifted.sample(stream);
}

double ProposalDistribution::log_pdf(double x) const {
  if (nominal_share >= 1.0) return nominal.log_pdf(x);
  const double a = std::log1p(-nominal_share) + shifted.log_pdf(x);
  const double b = std::log(nominal_share) + nominal.log_pdf(x);
  const double hi = std::max(a, b);
  if (hi == kMinusInfinity) return kMinusInfinity;
  return hi + std::log1p(std::exp(std::min(a, b) - hi));
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
    d.max = p.required<double>("max", {.min = d.min, .max = std::nullopt, .min_exclusive = false, .max_exclusive = false});
    p.finish();
  } else if (spec.has("normal")) {
    const config::Map p = spec.map("normal");
    d.kind = Distribution::Kind::normal;
    d.mean = p.required<double>("mean");
    d.stddev = p.required<double>("stddev", {.min = 0.0, .max = std::nullopt, .min_exclusive = false, .max_exclusive = false});
    p.finish();
  } else if (spec.has("truncated_normal")) {
    const config::Map p = spec.map("truncated_normal");
    d.kind = Distribution::Kind::truncated_normal;
    d.mean = p.required<double>("mean");
    d.stddev = p.required<double>("stddev", {.min = 0.0, .max = std::nullopt, .min_exclusive = false, .max_exclusive = false});
    d.min = p.required<double>("min");
    d.max = p.required<double>("max", {.min = d.min, .max = std::nullopt, .min_exclusive = false, .max_exclusive = false});
    p.finish();
  } else {
    const config::Map p = spec.map("choice");
    d.kind = Distribution::Kind::choice;
    d.values = p.required_list<double>("values");
    if (d.values.empty()) p.fail("values", "a choice needs at least one value");
    d.weights = p.optional_list<double>("weights", std::vector<double>(d.values.size(), 1.0),
                                        {.min = 0.0, .max = std::nullopt, .min_exclusive = true, .max_exclusive = false},
                                        d.values.size());
    p.finish();
  }
  spec.finish();
  return d;
}

}  // namespace shelfcross::verification
