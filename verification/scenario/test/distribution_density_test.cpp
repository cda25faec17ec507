// Densities and proposals of the dispersion distributions against their closed forms.
#include <cmath>
#include <limits>
#include <numbers>

#include <gtest/gtest.h>

#include "verification/scenario/distribution.hpp"
#include "verification/scenario/test/distribution_builders.hpp"

namespace shelfcross::verification {
namespace {

using test::normal;
using test::truncated;
using test::uniform;

/// Trapezoid integral of exp(log_pdf) over [lo, hi] on n intervals.
template <class LogPdf>
double integral_of(LogPdf log_pdf, double lo, double hi, int n = 20000) {
  const double h = (hi - lo) / n;
  double sum = 0.0;
  for (int i = 0; i <= n; ++i) sum += (i == 0 || i == n ? 0.5 : 1.0) * std::exp(log_pdf(lo + i * h));
  return sum * h;
}

/// The same of a distribution's density.
double integral(const Distribution& d, double lo, double hi, int n = 20000) {
  return integral_of([&d](double x) { return d.log_pdf(x); }, lo, hi, n);
}

constexpr double kInf = std::numeric_limits<double>::infinity();

TEST(DistributionDensity, UniformIsOneOverWidthOnItsSupport) {
  const Distribution u = uniform(2.0, 5.0);
  EXPECT_DOUBLE_EQ(u.log_pdf(3.0), -std::log(3.0));
  EXPECT_DOUBLE_EQ(u.log_pdf(2.0), -std::log(3.0));
  EXPECT_EQ(u.log_pdf(5.0001), -kInf);
  EXPECT_EQ(u.log_pdf(1.9), -kInf);
  EXPECT_DOUBLE_EQ(uniform(1.0, 1.0).log_pdf(1.0), 0.0);  // a point mass
}

TEST(DistributionDensity, NormalIsTheGaussianDensity) {
  const Distribution n = normal(1.0, 2.0);
  // log phi(-0.5) / 2 = -0.125 - ln 2 - ln(2 pi) / 2
  EXPECT_NEAR(n.log_pdf(0.0), -0.125 - std::log(2.0) - 0.5 * std::log(2.0 * std::numbers::pi), 1e-14);
  EXPECT_NEAR(integral(n, -19.0, 21.0), 1.0, 1e-9);
}

TEST(DistributionDensity, TruncatedNormalIsDividedByItsMass) {
  // phi(0.5) / (Phi(2) - Phi(-1)) = 0.43008507592322476 (Python's math.erf)
  const Distribution t = truncated(0.0, 1.0, -1.0, 2.0);
  EXPECT_NEAR(t.log_pdf(0.5), std::log(0.43008507592322476), 1e-12);
  EXPECT_EQ(t.log_pdf(2.01), -kInf);
  EXPECT_NEAR(integral(t, -1.0, 2.0), 1.0, 1e-8);
  // Far in the upper tail the mass is ~6e-16: computed through the complements, not lost.
  // phi(8.1) / (Q(8) - Q(9)), log = 1.28968006023247 (math.erfc)
  const Distribution far = truncated(0.0, 1.0, 8.0, 9.0);
  EXPECT_NEAR(far.log_pdf(8.1), 1.28968006023247, 1e-9);
  EXPECT_NEAR(integral(far, 8.0, 9.0), 1.0, 1e-6);
  // ... and in the lower tail.
  EXPECT_NEAR(integral(truncated(0.0, 1.0, -9.0, -8.0), -9.0, -8.0), 1.0, 1e-6);
}

TEST(DistributionDensity, ChoiceIsItsNormalisedWeight) {
  Distribution c;
  c.kind = Distribution::Kind::choice;
  c.values = {0.6, 1.0, 1.4};
  c.weights = {1.0, 2.0, 1.0};
  EXPECT_DOUBLE_EQ(c.log_pdf(1.0), std::log(0.5));
  EXPECT_DOUBLE_EQ(c.log_pdf(0.6), std::log(0.25));
  EXPECT_EQ(c.log_pdf(0.7), -kInf);
  // A value listed twice carries both weights.
  c.values = {1.0, 2.0, 1.0};
  EXPECT_DOUBLE_EQ(c.log_pdf(1.0), std::log(0.5));
  EXPECT_NEAR(c.scale(), 0.5, 1e-12);  // P(1) = P(2) = 1/2
}

TEST(DistributionDensity, ContinuousProposalKeepsTheSupportAndHasItsClosedFormMean) {
  const Distribution q = continuous_proposal(uniform(0.0, 1.0), 0.9, 0.1);
  EXPECT_EQ(q.kind, Distribution::Kind::truncated_normal);
  EXPECT_EQ(q.min, 0.0);
  EXPECT_EQ(q.max, 1.0);
  // Mean of the truncated normal: mu + sigma (phi(a) - phi(b)) / Z = 0.8712400029060822.
  RandomStream stream(11, StreamId::dispersion);
  double sum = 0.0;
  const int n = 200000;
  for (int i = 0; i < n; ++i) {
    const double x = q.sample(stream);
    ASSERT_GE(x, 0.0);
    ASSERT_LE(x, 1.0);
    sum += x;
  }
  // The mean's standard error is below 0.0002 (stddev < 0.1).
  EXPECT_NEAR(sum / n, 0.8712400029060822, 1e-3);
  EXPECT_EQ(continuous_proposal(normal(0.0, 1.0), 2.0, 0.5).kind, Distribution::Kind::normal);
  const Distribution tq = continuous_proposal(truncated(0.0, 1.0, -1.0, 3.0), 2.0, 0.5);
  EXPECT_EQ(tq.min, -1.0);
  EXPECT_EQ(tq.max, 3.0);
}

TEST(DistributionDensity, ChoiceProposalReweightsTheSameValues) {
  Distribution c;
  c.kind = Distribution::Kind::choice;
  c.values = {1.0, 2.0};
  c.weights = {1.0, 1.0};
  const Distribution q = choice_proposal(c, {1.0, 3.0});
  EXPECT_EQ(q.values, c.values);
  EXPECT_DOUBLE_EQ(q.log_pdf(2.0), std::log(0.75));
  RandomStream stream(3, StreamId::dispersion);
  int twos = 0;
  for (int i = 0; i < 40000; ++i) twos += q.sample(stream) == 2.0;
  EXPECT_NEAR(twos / 40000.0, 0.75, 0.01);  // 4.6 standard errors
}

TEST(DistributionDensity, DefensiveMixtureIsADensityWithABoundedRatio) {
  const Distribution f = truncated(0.0, 1.0, -2.0, 2.0);
  const ProposalDistribution q{continuous_proposal(f, 1.8, 0.1), f, 0.1};
  EXPECT_NEAR(integral_of([&](double x) { return q.log_pdf(x); }, -2.0, 2.0), 1.0, 1e-6);
  for (double x = -2.0; x <= 2.0; x += 0.01) ASSERT_LE(f.log_pdf(x) - q.log_pdf(x), -std::log(0.1) + 1e-12);
  // log((1 - s) q + s f) at a point by hand.
  EXPECT_NEAR(q.log_pdf(1.8), std::log(0.9 * std::exp(q.shifted.log_pdf(1.8)) + 0.1 * std::exp(f.log_pdf(1.8))), 1e-12);
  // The nominal as a proposal draws the nominal's values from the same stream.
  RandomStream a(9, StreamId::dispersion), b(9, StreamId::dispersion);
  const ProposalDistribution same = ProposalDistribution::of_nominal(f);
  for (int i = 0; i < 100; ++i) ASSERT_EQ(same.sample(a), f.sample(b));
}

}  // namespace
}  // namespace shelfcross::verification
