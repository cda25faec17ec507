// Paired comparisons of two campaigns on the same runs (shelfcross diff): the exact McNemar test
// against its closed forms, Wilson's and Newcombe's intervals against published values and their
// coverage of known differences, the Wilcoxon signed-rank test and the Hodges-Lehmann interval.
#include <cmath>
#include <vector>

#include <gtest/gtest.h>

#include "shelfcross/random.hpp"
#include "verification/statistics/statistics.hpp"

namespace shelfcross::verification {
namespace {

double binomial_coefficient(int n, int k) {
  return std::round(std::exp(std::lgamma(n + 1.0) - std::lgamma(k + 1.0) - std::lgamma(n - k + 1.0)));
}

TEST(PairedStatistics, McNemarEqualsTheBinomialClosedForms) {
  // 6 pairs worse in NEW, none better: P(X >= 6 | 6, 1/2) = 1/64, two-sided 2/64.
  McNemarTest t = mcnemar_exact({.both = 3, .base_only = 0, .new_only = 6, .neither = 291});
  EXPECT_EQ(t.discordant, 6);
  EXPECT_DOUBLE_EQ(t.p_new_worse, 1.0 / 64.0);
  EXPECT_DOUBLE_EQ(t.p_two_sided, 2.0 / 64.0);
  // 2 better, 8 worse: one-sided P(X >= 8 | 10) = (45 + 10 + 1) / 1024; two-sided
  // 2 P(X <= 2) = 2 (1 + 10 + 45) / 1024.
  t = mcnemar_exact({.both = 0, .base_only = 2, .new_only = 8, .neither = 90});
  EXPECT_NEAR(t.p_new_worse, 56.0 / 1024.0, 1e-15);
  EXPECT_NEAR(t.p_two_sided, 112.0 / 1024.0, 1e-15);
  // The same table the other way round: NEW better, so "NEW worse" is all but certain.
  t = mcnemar_exact({.both = 0, .base_only = 8, .new_only = 2, .neither = 90});
  EXPECT_NEAR(t.p_new_worse, 1.0 - 11.0 / 1024.0, 1e-15);  // P(X >= 2) = 1 - P(X <= 1)
  EXPECT_NEAR(t.p_two_sided, 112.0 / 1024.0, 1e-15);
  // 13 worse, 4 better: the general sum, term by term.
  double tail = 0.0, lower = 0.0;
  for (int x = 13; x <= 17; ++x) tail += binomial_coefficient(17, x);
  for (int x = 0; x <= 4; ++x) lower += binomial_coefficient(17, x);
  t = mcnemar_exact({.both = 1, .base_only = 4, .new_only = 13, .neither = 500});
  EXPECT_NEAR(t.p_new_worse, tail / 131072.0, 1e-14);
  EXPECT_NEAR(t.p_two_sided, 2.0 * lower / 131072.0, 1e-14);
  // No discordant pair (two identical campaigns): nothing to test, both p = 1.
  t = mcnemar_exact({.both = 12, .base_only = 0, .new_only = 0, .neither = 288});
  EXPECT_EQ(t.discordant, 0);
  EXPECT_EQ(t.p_new_worse, 1.0);
  EXPECT_EQ(t.p_two_sided, 1.0);
  // As many either way: two-sided 1 (capped), one-sided above 1/2.
  t = mcnemar_exact({.both = 0, .base_only = 5, .new_only = 5, .neither = 0});
  EXPECT_EQ(t.p_two_sided, 1.0);
  EXPECT_GT(t.p_new_worse, 0.5);
  EXPECT_THROW(mcnemar_exact({.both = -1}), std::invalid_argument);
}

TEST(PairedStatistics, WilsonIntervalMatchesItsClosedForm) {
  // k = 0: [0, z^2 / (n + z^2)].
  const double z = 1.959963984540054;
  const Interval none = wilson_interval(0, 300);
  EXPECT_EQ(none.lower, 0.0);
  EXPECT_NEAR(none.upper, z * z / (300.0 + z * z), 1e-12);
  // k = n mirrors k = 0.
  const Interval all = wilson_interval(300, 300);
  EXPECT_NEAR(all.lower, 1.0 - none.upper, 1e-12);
  EXPECT_EQ(all.upper, 1.0);
  // 23 of 60: the limits are the two roots pi of the score equation (p - pi)^2 = z^2 pi (1 - pi) / n.
  const Interval w = wilson_interval(23, 60);
  const double p = 23.0 / 60.0;
  for (double pi : {w.lower, w.upper}) EXPECT_NEAR((p - pi) * (p - pi), z * z * pi * (1.0 - pi) / 60.0, 1e-14);
  EXPECT_NEAR(w.lower, 0.27088, 1e-5);
  EXPECT_NEAR(w.upper, 0.50982, 1e-5);
  EXPECT_THROW(wilson_interval(3, 2), std::invalid_argument);
}

TEST(PairedStatistics, NewcombeIntervalMatchesThePublishedExample) {
  // Fagerland, Lydersen & Laake, Statistical Analysis of Contingency Tables (2017), ch. 8: the
  // complete responses before and after consolidation therapy (Cavo et al. 2012), 161 patients,
  // 59 both, 6 before only, 16 after only, 80 neither: difference -0.0621, Newcombe's
  // square-and-add (method 10) interval -0.1186 to -0.0046. Here "before" is NEW.
  const PairedTable cavo{.both = 59, .base_only = 16, .new_only = 6, .neither = 80};
  const Interval i = newcombe_paired_difference(cavo);
  EXPECT_NEAR(i.lower, -0.1186, 5e-5);
  EXPECT_NEAR(i.upper, -0.0046, 5e-5);
  // Swapping BASE and NEW mirrors the interval.
  const Interval swapped = newcombe_paired_difference({.both = 59, .base_only = 6, .new_only = 16, .neither = 80});
  EXPECT_NEAR(swapped.lower, -i.upper, 1e-12);
  EXPECT_NEAR(swapped.upper, -i.lower, 1e-12);
  // Identical campaigns: difference 0 inside an interval that stays strictly around it.
  const Interval same = newcombe_paired_difference({.both = 12, .base_only = 0, .new_only = 0, .neither = 288});
  EXPECT_LT(same.lower, 0.0);
  EXPECT_GT(same.upper, 0.0);
  EXPECT_THROW(newcombe_paired_difference({}), std::invalid_argument);
}

// Coverage: paired yes/no outcomes drawn with known rates (a correlated pair: NEW fails whenever
// BASE does, and besides on 3 % of the runs), 300 pairs a table, 2,000 tables from a fixed seed:
// the interval covers the true difference (+0.0291) in about 95 % of them.
TEST(PairedStatistics, NewcombeIntervalCoversAKnownDifference) {
  RandomStream stream(20261126, StreamId::dispersion);
  const double p_base = 0.03, p_extra = 0.03;
  const double true_difference = (1.0 - p_base) * p_extra;  // P(NEW fails) - P(BASE fails)
  int covered = 0, rejected_not_worse = 0;
  constexpr int kTables = 2000;
  for (int k = 0; k < kTables; ++k) {
    PairedTable t;
    for (int run = 0; run < 300; ++run) {
      const bool base_fails = stream.bernoulli(p_base);
      const bool new_fails = base_fails || stream.bernoulli(p_extra);
      if (base_fails && new_fails) ++t.both;
      else if (base_fails) ++t.base_only;
      else if (new_fails) ++t.new_only;
      else ++t.neither;
    }
    covered += newcombe_paired_difference(t).contains(true_difference);
    rejected_not_worse += mcnemar_exact(t).p_new_worse <= 0.05;
  }
  const double coverage = static_cast<double>(covered) / kTables;
  EXPECT_GT(coverage, 0.93);
  EXPECT_LT(coverage, 0.985);
  // 8.7 extra failures in 300 expected, none the other way: the one-sided test needs 5 of them
  // (1/32 <= 0.05) and sees the change in about 93 % of the tables.
  EXPECT_GT(rejected_not_worse, kTables * 85 / 100);
}

TEST(PairedStatistics, SignedRankTestAndHodgesLehmannOnSmallSamples) {
  // Five positive, untied differences: W+ = 15, the largest of 2^5 equally likely sums:
  // two-sided p = 2 / 32. The Walsh averages of {1..5} are symmetric about 3.
  SignedRankResult r = wilcoxon_signed_rank({1.0, 2.0, 3.0, 4.0, 5.0});
  EXPECT_EQ(r.nonzero, 5);
  EXPECT_DOUBLE_EQ(r.p_two_sided, 2.0 / 32.0);
  EXPECT_DOUBLE_EQ(r.hodges_lehmann, 3.0);
  EXPECT_DOUBLE_EQ(r.median, 3.0);
  // With 5 differences no interval reaches 95 %: the whole range of the Walsh averages.
  EXPECT_DOUBLE_EQ(r.interval.lower, 1.0);
  EXPECT_DOUBLE_EQ(r.interval.upper, 5.0);
  // n = 10, one negative of rank 1: W+ = 54, P(W+ >= 54) = P(W+ <= 1) = 2 / 1024.
  r = wilcoxon_signed_rank({-0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8, 0.9, 1.0});
  EXPECT_DOUBLE_EQ(r.p_two_sided, 4.0 / 1024.0);
  // n = 10 at 95 %: the critical count is 9 (P(W+ <= 8) = 25 / 1024 <= 0.025 < P(W+ <= 9)
  // = 33 / 1024), so the interval runs from the 9th to the 47th of 55 Walsh averages.
  std::vector<double> walsh;
  const std::vector<double> d{-0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8, 0.9, 1.0};
  for (size_t i = 0; i < d.size(); ++i) {
    for (size_t j = i; j < d.size(); ++j) walsh.push_back(0.5 * (d[i] + d[j]));
  }
  std::sort(walsh.begin(), walsh.end());
  EXPECT_DOUBLE_EQ(r.interval.lower, walsh[8]);
  EXPECT_DOUBLE_EQ(r.interval.upper, walsh[46]);
  EXPECT_DOUBLE_EQ(r.hodges_lehmann, walsh[27]);
  // Every difference 0 (a build that changes nothing): estimate and interval 0, p 1.
  r = wilcoxon_signed_rank(std::vector<double>(300, 0.0));
  EXPECT_EQ(r.nonzero, 0);
  EXPECT_EQ(r.p_two_sided, 1.0);
  EXPECT_EQ(r.hodges_lehmann, 0.0);
  EXPECT_EQ(r.interval.lower, 0.0);
  EXPECT_EQ(r.interval.upper, 0.0);
  EXPECT_THROW(wilcoxon_signed_rank({}), std::invalid_argument);
  EXPECT_THROW(wilcoxon_signed_rank({1.0, NAN}), std::invalid_argument);
}

TEST(PairedStatistics, SignedRankNormalApproximationWithTies) {
  // 60 nonzero differences, tied in |d| by threes (values +-1..+-20): the normal approximation
  // with the tie correction, computed here from its closed form.
  std::vector<double> d;
  for (int v = 1; v <= 20; ++v) {
    d.push_back(v);
    d.push_back(v);
    d.push_back(v % 4 == 0 ? -v : v);
  }
  const SignedRankResult r = wilcoxon_signed_rank(d);
  // Ranks: |d| = v holds ranks 3v-2 .. 3v, mid-rank 3v - 1. W+ = sum over all minus the
  // negatives' mid-ranks (v = 4, 8, ..., 20).
  double w_plus = 60.0 * 61.0 / 2.0;
  for (int v = 4; v <= 20; v += 4) w_plus -= 3.0 * v - 1.0;
  const double mean = 60.0 * 61.0 / 4.0;
  const double variance = 60.0 * 61.0 * 121.0 / 24.0 - 20.0 * (27.0 - 3.0) / 48.0;
  const double z = (std::abs(w_plus - mean) - 0.5) / std::sqrt(variance);
  EXPECT_NEAR(r.p_two_sided, std::erfc(z / std::sqrt(2.0)), 1e-12);
}

// Coverage of the Hodges-Lehmann interval: differences = 0.5 + symmetric noise (Laplace-like:
// a normal scaled by a random factor), 80 pairs, 1,000 samples: covers 0.5 in about 95 %.
TEST(PairedStatistics, HodgesLehmannIntervalCoversAKnownShift) {
  RandomStream stream(7, StreamId::dispersion);
  int covered = 0;
  constexpr int kSamples = 1000;
  for (int k = 0; k < kSamples; ++k) {
    std::vector<double> d;
    for (int i = 0; i < 80; ++i) d.push_back(0.5 + stream.normal() * (0.5 + stream.uniform01()));
    covered += wilcoxon_signed_rank(d).interval.contains(0.5);
  }
  EXPECT_GT(covered, kSamples * 93 / 100);
  EXPECT_LT(covered, kSamples * 985 / 1000);
}

}  // namespace
}  // namespace shelfcross::verification
