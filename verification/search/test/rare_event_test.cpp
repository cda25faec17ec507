// The cross-entropy search and the importance-sampling estimate on toy margin functions with a
// known failure probability (no simulation).
#include "verification/search/rare_event.hpp"

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <numbers>

#include <gtest/gtest.h>

#include "shelfcross/random.hpp"
#include "verification/scenario/test/distribution_builders.hpp"

namespace shelfcross::verification {
namespace {

using test::normal;
using test::uniform;

/// Phi(-b), the standard normal's upper tail.
double upper_tail(double b) { return 0.5 * std::erfc(b / std::numbers::sqrt2); }

TEST(CrossEntropy, RefitByHand) {
  // Ten runs x = 0..9, margin 9 - x, from the nominal itself: k = max(ceil(0.1 x 10), 3) = 3
  // elites, x = 7, 8, 9, level max(0, 2) = 2 (> 0: unweighted); their mean 8, stddev sqrt(2/3);
  // smoothed with alpha 0.8 against the nominal N(0, 2) truncated to [-100, 100]: mean 6.4,
  // stddev 0.8 sqrt(2/3) + 0.4 (above the floor, 0.5 x 2).
  Distribution x = normal(0.0, 2.0);
  x.kind = Distribution::Kind::truncated_normal;
  x.min = -100.0;
  x.max = 100.0;
  const ParameterDistributions nominal{{"x", x}};
  std::vector<CeSample> samples;
  for (int x = 0; x < 10; ++x) samples.push_back({{{"x", double(x)}}, 9.0 - x});
  const CeFit fit = ce_refit(nominal, RoundProposal::of_nominal(nominal), samples, CeSettings{});
  EXPECT_EQ(fit.elites, 3);
  EXPECT_DOUBLE_EQ(fit.level, 2.0);
  EXPECT_NEAR(fit.proposal.parameters.at("x").shifted.mean, 6.4, 1e-12);
  EXPECT_NEAR(fit.proposal.parameters.at("x").shifted.stddev, 0.8 * std::sqrt(2.0 / 3.0) + 0.4, 1e-12);
  // The refitted proposal mixes the whole nominal at s and each parameter's at s_j.
  EXPECT_EQ(fit.proposal.nominal_share, CeSettings{}.nominal_share);
  EXPECT_EQ(fit.proposal.parameters.at("x").nominal_share, CeSettings{}.parameter_share);
  // Four failures among ten: the level is 0 and the elites are the failures (x = 6..9),
  // weighted by f / q = 1 here.
  for (CeSample& s : samples) s.margin -= 3.5;
  const CeFit failing = ce_refit(nominal, RoundProposal::of_nominal(nominal), samples, CeSettings{});
  EXPECT_EQ(failing.level, 0.0);
  EXPECT_EQ(failing.elites, 4);
  EXPECT_NEAR(failing.proposal.parameters.at("x").shifted.mean, 0.8 * 7.5, 1e-12);
}

TEST(CrossEntropy, EstimateOfOneProposalByHand) {
  // Weights e^0 = 1 and e^-1 on the two failures of four runs: p_hat = (1 + e^-1) / 4.
  const IsEstimate e = importance_estimate({0.0, -1.0, 5.0, 5.0}, {true, true, false, false});
  EXPECT_EQ(e.failures, 2);
  const double y1 = 1.0, y2 = std::exp(-1.0), p = (y1 + y2) / 4.0;
  EXPECT_DOUBLE_EQ(e.p_hat, p);
  const double s2 = ((y1 - p) * (y1 - p) + (y2 - p) * (y2 - p) + 2 * p * p) / 3.0;
  EXPECT_NEAR(e.standard_error, std::sqrt(s2 / 4.0), 1e-15);
  EXPECT_NEAR(e.lower * e.upper, p * p, 1e-15);  // symmetric on the log scale
  EXPECT_NEAR(e.failure_ess, (y1 + y2) * (y1 + y2) / (y1 * y1 + y2 * y2), 1e-12);
  EXPECT_NEAR(e.mean_weight, (y1 + y2 + 2.0 * std::exp(5.0)) / 4.0, 1e-12);
  const IsEstimate none = importance_estimate({0.0, 0.0}, {false, false});
  EXPECT_EQ(none.p_hat, 0.0);
  EXPECT_EQ(none.upper, 0.0);
}

/// The toy: x1, x2 ~ N(0, 1); u ~ U(0, 1) (no effect on the margin); c ~ choice {0: 0.9,
/// 0.5: 0.1}. Margin g = beta - (x1 + x2) / sqrt(2) - c: (x1 + x2) / sqrt(2) is N(0, 1), so
/// p = 0.9 Phi(-beta) + 0.1 Phi(-(beta - 0.5)) = 1.5433e-4 for beta = 3.719.
struct Toy {
  static constexpr double kBeta = 3.719;
  ParameterDistributions nominal;
  double p = 0.9 * upper_tail(kBeta) + 0.1 * upper_tail(kBeta - 0.5);
  Toy() {
    nominal["x1"] = normal(0.0, 1.0);
    nominal["x2"] = normal(0.0, 1.0);
    nominal["u"] = uniform(0.0, 1.0);
    Distribution c;
    c.kind = Distribution::Kind::choice;
    c.values = {0.0, 0.5};
    c.weights = {0.9, 0.1};
    nominal["c"] = c;
  }
  static double margin(const DrawnValues& x) {
    return kBeta - (x.at("x1") + x.at("x2")) / std::numbers::sqrt2 - x.at("c");
  }
};

struct SearchResult {
  IsEstimate estimate;  ///< from the estimation round (importance_estimate of its proposal)
  IsEstimate mixture;   ///< from every round's runs (mixture_log_weight)
  std::int64_t first_failure = -1;  ///< run index of the first failure, -1 if none
  int rounds = 0;
};

/// A whole search as the driver does it: each round's runs drawn from the planned proposal with
/// run k's seed (the dispersion streams of search.cpp), margins, the next round planned.
template <class Toy>
SearchResult search(const Toy& toy, std::uint64_t seed, std::int64_t budget, const CeSettings& settings) {
  std::vector<CeRound> rounds;
  std::vector<CeSample> samples;
  SearchResult r;
  while (const auto round = next_ce_round(toy.nominal, settings, budget, rounds, samples)) {
    for (std::int64_t k = round->first_run; k < round->first_run + round->runs; ++k) {
      const DrawnValues x = round->proposal.sample(run_seed(seed, static_cast<std::uint64_t>(k)));
      samples.push_back({x, Toy::margin(x)});
      if (samples.back().margin < 0.0 && r.first_failure < 0) r.first_failure = k;
    }
    rounds.push_back(*round);
  }
  r.rounds = static_cast<int>(rounds.size());
  if (std::getenv("SHELFCROSS_TEST_VERBOSE")) for (const auto& rr : rounds) { std::printf(" round %d level %.3f elites %lld:", rr.index, rr.level, (long long)rr.elites); for (const auto& [n, d] : rr.proposal.parameters) std::printf(" %s(%.3f,%.3f)", n.c_str(), d.shifted.is_choice() ? d.shifted.weights[1] : d.shifted.mean, d.shifted.stddev); std::printf("\n"); }
  const CeRound& last = rounds.back();
  EXPECT_TRUE(last.estimation);
  std::vector<double> log_w;
  std::vector<bool> failed;
  for (std::int64_t k = last.first_run; k < last.first_run + last.runs; ++k) {
    const DrawnValues& x = samples[static_cast<size_t>(k)].drawn;
    log_w.push_back(log_density(toy.nominal, x) - last.proposal.log_pdf(x));
    failed.push_back(samples[static_cast<size_t>(k)].margin < 0.0);
  }
  r.estimate = importance_estimate(log_w, failed);
  std::vector<std::int64_t> runs_per_round;
  for (const CeRound& round : rounds) runs_per_round.push_back(round.runs);
  std::vector<double> mixture_log_w;
  std::vector<bool> mixture_failed;
  for (const CeSample& sample : samples) {
    mixture_log_w.push_back(mixture_log_weight(toy.nominal, rounds, runs_per_round, sample.drawn));
    mixture_failed.push_back(sample.margin < 0.0);
  }
  r.mixture = importance_estimate(mixture_log_w, mixture_failed);
  return r;
}

/// A soft failure region, as the gust scenario's (docs/search.md): x ~ N(0.1, 0.1) truncated to
/// [0, 2] (the gust, m/s), u ~ U(0, 1) the run's own luck, never adapted (the seed's noise in a
/// simulation). A run fails when u < pi(x) = min(1, ((x - 0.2) / 0.6)^2) for x > 0.2: rarely
/// at 0.3, half the time at 0.62, always past 0.8. Margin g = u - pi(x). p = int f pi, by
/// quadrature (about 3.3e-3).
struct SoftToy {
  ParameterDistributions nominal;
  double p = 0.0;
  SoftToy() {
    Distribution x = normal(0.1, 0.1);
    x.kind = Distribution::Kind::truncated_normal;
    x.min = 0.0;
    x.max = 2.0;
    nominal["x"] = x;
    nominal["u"] = uniform(0.0, 1.0);
    constexpr int kSteps = 200000;  // midpoint rule on [0, 2]
    for (int i = 0; i < kSteps; ++i) {
      const double xi = (i + 0.5) * 2.0 / kSteps;
      p += std::exp(x.log_pdf(xi)) * failure_chance(xi) * 2.0 / kSteps;
    }
  }
  static double failure_chance(double x) { return x <= 0.2 ? 0.0 : std::min(1.0, std::pow((x - 0.2) / 0.6, 2)); }
  static double margin(const DrawnValues& v) { return v.at("u") - failure_chance(v.at("x")); }
};

// The marks the report puts on an estimate not to be trusted (rare_event.hpp).
TEST(CrossEntropy, DoubtsOnUnevenWeightsAndFewEffectiveFailures) {
  IsEstimate e;
  e.runs = 30;
  e.failures = 12;
  e.mean_weight = 0.84;
  e.failure_ess = 11.0;
  EXPECT_EQ(estimate_doubts(e), "");
  e.failure_ess = 1.4;  // gust_rare_ideal, docs/search.md: one failure carries the estimate
  EXPECT_EQ(estimate_doubts(e), "few effective failures");
  e.mean_weight = 2.5;
  EXPECT_EQ(estimate_doubts(e), "uneven weights; few effective failures");
  e.failures = 2;  // two failures of equal weight: ESS 2, as even as two can be
  e.failure_ess = 2.0;
  e.mean_weight = 1.0;
  EXPECT_EQ(estimate_doubts(e), "");
  e.failures = 0;  // nothing sampled: no interval to doubt
  e.failure_ess = 0.0;
  EXPECT_EQ(estimate_doubts(e), "");
  // From weights: one failure of weight 1 among failures of weight 0.01 gives ESS near 1.
  std::vector<double> log_w(30, 0.0);
  std::vector<bool> failed(30, false);
  for (int i = 0; i < 6; ++i) {
    failed[static_cast<size_t>(i)] = true;
    log_w[static_cast<size_t>(i)] = i == 0 ? 0.0 : std::log(0.01);
  }
  const IsEstimate skewed = importance_estimate(log_w, failed);
  EXPECT_LT(skewed.failure_ess, 1.3);
  EXPECT_NE(estimate_doubts(skewed).find("few effective failures"), std::string::npos);
}

TEST(CrossEntropy, EstimateCoversTheKnownProbabilityIn19Of20Seeds) {
  const Toy toy;
  ASSERT_NEAR(toy.p, 1.5433e-4, 0.0001e-4);
  CeSettings settings;
  settings.round_runs = 200;
  settings.estimation_runs = 1000;
  int covered = 0, mixture_covered = 0;
  double sum_p_hat = 0.0, sum_mixture_p_hat = 0.0;
  for (std::uint64_t seed = 1; seed <= 20; ++seed) {
    const SearchResult r = search(toy, seed, 2000, settings);
    EXPECT_GT(r.estimate.failures, 100) << "seed " << seed;  // the final proposal meets failures often
    covered += r.estimate.lower <= toy.p && toy.p <= r.estimate.upper;
    mixture_covered += r.mixture.lower <= toy.p && toy.p <= r.mixture.upper;
    sum_mixture_p_hat += r.mixture.p_hat;
    if (std::getenv("SHELFCROSS_TEST_VERBOSE")) std::printf("seed %d rounds %d fails %lld p_hat %.4g [%.4g, %.4g] re %.3f ess %.1f\n", (int)seed, r.rounds, (long long)r.estimate.failures, r.estimate.p_hat, r.estimate.lower, r.estimate.upper, r.estimate.standard_error / r.estimate.p_hat, r.estimate.failure_ess);
    sum_p_hat += r.estimate.p_hat;
    // The diagnostic (rare_event.hpp) does not flag these good estimates: mean weight in [0.5, 2]
    // (it is noisier than the estimate, as the bulk of f lies where q draws mostly through its
    // defensive share).
    EXPECT_GE(r.estimate.mean_weight, 0.5) << "seed " << seed;
    EXPECT_LE(r.estimate.mean_weight, 2.0) << "seed " << seed;
    // A relative standard error of 10 % on average, 31 % at most, from 1000 runs (measured;
    // the nominal share's fifth of the runs rarely fails, which costs about sqrt(1 / 0.8) =
    // 1.12 times the fitted component's); plain Monte Carlo's would be
    // sqrt((1 - p) / (1000 p)) = 250 %.
    EXPECT_LT(r.estimate.standard_error / r.estimate.p_hat, 0.35) << "seed " << seed;
  }
  // Measured with the default shares (s = 0.2, s_j = 0.1): 20 of 20, and 185 of 200 seeds.
  // Without the per-parameter floor (s_j = 0) 177 of 200: the joint share caps a drifted
  // parameter's weight at 1 / s, still thousands of times a well-placed failure's (file comment
  // of rare_event.hpp); with per-parameter shares alone (s = 0), 188 of 200.
  EXPECT_GE(covered, 19);
  // The mean of 20 unbiased estimates, each within ~10 %: within 5 % of p.
  EXPECT_NEAR(sum_p_hat / 20.0 / toy.p, 1.0, 0.05);
  // The estimate from every round (mixture_log_weight) on this sharp region: within 10 % of p
  // on average; its interval covers p in 20 of these 20 seeds, 184 of 200 (measured; 179 of
  // 200 with per-parameter shares alone). The adapted proposals were fitted to the very runs it
  // reuses (consistent, not unbiased: rare_event.hpp), and with hundreds of failures its
  // interval is narrow enough to show it. The report gives both estimates; the soft region
  // below is where the mixture is needed.
  EXPECT_GE(mixture_covered, 18);
  EXPECT_NEAR(sum_mixture_p_hat / 20.0 / toy.p, 1.0, 0.1);
}

// The soft toy with the gust search's settings (docs/search.md: 2 elites at least, rho 0.25,
// alpha 0.9, stddev floor 2 x the nominal's, x adapted) in 200 runs (rounds of 20, 100 for the
// estimate) and a share of 0.3 of x's nominal (x is the only adapted parameter, so a joint
// share and a per-parameter one give the same distribution; the per-parameter one keeps these
// draws). The final round, fitted where failures are easy, misses the soft edge where most of p
// lies: measured, its interval covers p in 10 of 20 seeds (geometric mean of p_hat / p 0.46);
// every round together in 19 (0.98). Over 200 seeds both cover less, 119 and 150 of 200
// (and 117 and 152 with the joint share's draws, s = 0.3, s_j = 0): 19 of these 20 is a lucky
// draw of a coverage near 75 %. With the gust demo's 60 runs (rounds of 6, share 0.1) neither
// works (5 and 8 of 20; ESS near 1): the soft edge needs runs, and a share of the nominal large
// enough to sample it.
TEST(CrossEntropy, OnASoftFailureRegionEveryRoundTogetherEstimatesWhatTheFinalRoundMisses) {
  const SoftToy toy;
  ASSERT_GT(toy.p, 1e-3);
  ASSERT_LT(toy.p, 1e-2);
  CeSettings settings;
  settings.round_runs = 20;
  settings.elite_fraction = 0.25;
  settings.min_elites = 2;
  settings.smoothing = 0.9;
  settings.min_stddev_fraction = 2.0;
  settings.estimation_runs = 100;
  settings.nominal_share = 0.0;
  settings.parameter_share = 0.3;
  settings.adapted = {"x"};
  int final_covered = 0, mixture_covered = 0;
  double log_ratio_final = 0.0, log_ratio_mixture = 0.0;
  int n = 0;
  for (std::uint64_t seed = 1; seed <= 20; ++seed) {
    const SearchResult r = search(toy, seed, 200, settings);
    final_covered += r.estimate.failures > 0 && r.estimate.lower <= toy.p && toy.p <= r.estimate.upper;
    mixture_covered += r.mixture.failures > 0 && r.mixture.lower <= toy.p && toy.p <= r.mixture.upper;
    if (r.estimate.failures > 0 && r.mixture.failures > 0) {
      log_ratio_final += std::log(r.estimate.p_hat / toy.p);
      log_ratio_mixture += std::log(r.mixture.p_hat / toy.p);
      ++n;
    }
    if (std::getenv("SHELFCROSS_TEST_VERBOSE")) std::printf("p %.4g seed %d final %.4g [%.4g, %.4g] ess %.1f/%lld | mixture %.4g [%.4g, %.4g] ess %.1f/%lld\n", toy.p, (int)seed, r.estimate.p_hat, r.estimate.lower, r.estimate.upper, r.estimate.failure_ess, (long long)r.estimate.failures, r.mixture.p_hat, r.mixture.lower, r.mixture.upper, r.mixture.failure_ess, (long long)r.mixture.failures);
  }
  if (std::getenv("SHELFCROSS_TEST_VERBOSE")) std::printf("covered: final %d mixture %d of 20; geometric mean ratio final %.3g mixture %.3g\n", final_covered, mixture_covered, std::exp(log_ratio_final / n), std::exp(log_ratio_mixture / n));
  EXPECT_GE(mixture_covered, 19);
  EXPECT_LT(final_covered, mixture_covered);
  EXPECT_NEAR(std::exp(log_ratio_mixture / n), 1.0, 0.1);
}

TEST(CrossEntropy, FindsFailuresInFarFewerRunsThanPlainMonteCarlo) {
  // Plain Monte Carlo meets its first failure after 1 / p = 6,480 runs on average. The search
  // (rounds of 100) meets one within a tenth of that in every seed.
  const Toy toy;
  CeSettings settings;
  settings.round_runs = 100;
  settings.estimation_runs = 200;
  for (std::uint64_t seed = 1; seed <= 20; ++seed) {
    const SearchResult r = search(toy, seed, 1000, settings);
    ASSERT_GE(r.first_failure, 0) << "seed " << seed;
    EXPECT_LT(static_cast<double>(r.first_failure), 0.1 / toy.p) << "seed " << seed;
  }
}

// ---- The joint defensive component ----

/// The toy's parameters fitted far from the nominal: x1 at 4 sigma, u pressed to its upper end,
/// c at its rare value; x2 kept at its nominal. Nominal share s, parameter share s_j.
RoundProposal far_proposal(const Toy& toy, double s, double s_j) {
  RoundProposal q = RoundProposal::of_nominal(toy.nominal);
  q.nominal_share = s;
  q.parameters["x1"] = {continuous_proposal(toy.nominal.at("x1"), 4.0, 1.0), toy.nominal.at("x1"), s_j};
  q.parameters["u"] = {continuous_proposal(toy.nominal.at("u"), 0.95, 0.05), toy.nominal.at("u"), s_j};
  q.parameters["c"] = {choice_proposal(toy.nominal.at("c"), {0.01, 0.99}), toy.nominal.at("c"), s_j};
  return q;
}

// f / q <= 1 / s for any x, however far the fits went and with no per-parameter share at all;
// near 1 / s where the fitted component draws nothing (x1 far below its fit, u at 0).
TEST(JointDefence, NoWeightExceedsOneOverTheNominalShare) {
  const Toy toy;
  for (double s : {0.1, 0.2, 0.3}) {
    for (double s_j : {0.0, 0.1}) {
      const RoundProposal q = far_proposal(toy, s, s_j);
      EXPECT_DOUBLE_EQ(q.least_ratio(), s + (1.0 - s) * s_j * s_j * s_j);  // three adapted parameters
      double largest = -1e300;
      RandomStream stream(7, StreamId::dispersion);
      for (int i = 0; i < 20000; ++i) {  // x from a box far wider than either component
        const DrawnValues x{{"x1", stream.uniform(-9.0, 9.0)}, {"x2", stream.uniform(-9.0, 9.0)},
                            {"u", stream.uniform(0.0, 1.0)}, {"c", stream.uniform01() < 0.5 ? 0.0 : 0.5}};
        const double log_w = log_density(toy.nominal, x) - q.log_pdf(x);
        ASSERT_LE(log_w, -std::log(q.least_ratio()) + 1e-12) << "s " << s << " s_j " << s_j << " x1 " << x.at("x1");
        largest = std::max(largest, log_w);
      }
      // Without per-parameter shares the fitted component vanishes far below x1's fit and at
      // u = 0: the weight there is 1 / s.
      const DrawnValues corner{{"x1", -8.0}, {"x2", 0.0}, {"u", 0.0}, {"c", 0.0}};
      if (s_j == 0.0) {
        EXPECT_NEAR(log_density(toy.nominal, corner) - q.log_pdf(corner), -std::log(s), 1e-6);
      }
      EXPECT_GT(largest, -std::log(q.least_ratio()) - 0.1);
    }
  }
}

// A run's draws are a function of its seed; with probability s they are the campaign's draws
// for that seed (the nominal component), else the fitted component's; the nominal as a round
// proposal draws the campaign's values every time.
TEST(JointDefence, DrawsAreTheSeedsAndTheNominalComponentIsTheCampaigns) {
  const Toy toy;
  const RoundProposal q = far_proposal(toy, 0.2, 0.1);
  int nominal_runs = 0;
  const int runs = 4000;
  for (std::uint64_t k = 0; k < runs; ++k) {
    const std::uint64_t seed = run_seed(5, k);
    const DrawnValues x = q.sample(seed);
    EXPECT_EQ(x, q.sample(seed));
    EXPECT_EQ(RoundProposal::of_nominal(toy.nominal).sample(seed), draw_dispersions(toy.nominal, seed));
    const bool campaign = x == draw_dispersions(toy.nominal, seed);
    nominal_runs += campaign;
    if (!campaign) {
      EXPECT_EQ(x, draw_dispersions(q.parameters, seed));
    }
  }
  // Binomial(4000, 0.2): 800 +- 25.3; within 4 standard deviations.
  EXPECT_NEAR(nominal_runs, 800, 101);
}

// ---- The zero-failure bound ----

// Rounds of a search on one parameter u ~ U(0, 1): round 0 the nominal, the others drawing the
// whole run from the nominal with probability `share`, else u from U(0, 0.5), a fit far from
// the failures (no per-parameter share).
std::vector<CeRound> bound_rounds(double share, int adapted_rounds) {
  std::vector<CeRound> rounds(1 + static_cast<size_t>(adapted_rounds));
  for (size_t k = 0; k < rounds.size(); ++k) {
    rounds[k].index = static_cast<int>(k);
    rounds[k].proposal.parameters["u"] = k == 0 ? ProposalDistribution::of_nominal(uniform(0.0, 1.0))
                                                : ProposalDistribution{uniform(0.0, 0.5), uniform(0.0, 1.0), 0.0};
    rounds[k].proposal.nominal_share = k == 0 ? 1.0 : share;
  }
  return rounds;
}

// By hand: a plain campaign of n runs gives the binomial bound 1 - 0.05^(1/n) (about 3 / n); a
// search of 20 nominal runs and 180 from a proposal with a nominal share of 0.1 is worth 20 +
// 18 nominal runs, and its bound solves 20 log(1 - p) + 180 log(1 - 0.1 p) = log 0.05.
TEST(ZeroFailureBound, ByHand) {
  EXPECT_NEAR(zero_failure_upper_bound(bound_rounds(0.1, 0), {100}), 1.0 - std::pow(0.05, 1.0 / 100.0), 1e-12);
  EXPECT_NEAR(zero_failure_upper_bound(bound_rounds(0.1, 0), {400}), 3.0 / 400.0, 0.0002);
  EXPECT_DOUBLE_EQ(nominal_worth(bound_rounds(0.1, 0), {400}), 400.0);
  const double p = zero_failure_upper_bound(bound_rounds(0.1, 1), {20, 180});
  EXPECT_NEAR(20.0 * std::log1p(-p) + 180.0 * std::log1p(-0.1 * p), std::log(0.05), 1e-9);
  EXPECT_NEAR(p, 3.0 / 38.0, 0.004);
  EXPECT_NEAR(nominal_worth(bound_rounds(0.1, 1), {20, 180}), 38.0, 1e-12);
  // No run: nothing is known.
  EXPECT_EQ(zero_failure_upper_bound({}, {}), 1.0);
  EXPECT_EQ(zero_failure_upper_bound(bound_rounds(0.1, 0), {0}), 1.0);
}

// A 400-run search as `shelfcross search` plans it by default on a scenario of 18 dispersed
// parameters, all adapted (beyond_gusts.yaml): rounds of 10, half the budget for the estimate;
// a margin that never fails, so round 0 (10 nominal runs), 19 adapted rounds of 10 and the
// estimation round of 200. Each adapted run is worth c = s + (1 - s) 0.1^18 nominal runs: the
// search 10 + 390 c, and its 95 % bound solves 10 log(1 - p) + 390 log(1 - c p) = log 0.05.
// Per-parameter shares alone (s = 0) leave round 0's ten: 1 - 0.05^(1/10) = 25.9 %.
TEST(ZeroFailureBound, WorthOfA400RunSearchOf18AdaptedParameters) {
  ParameterDistributions nominal;
  for (char j = 'a'; j < 'a' + 18; ++j) nominal[std::string(1, j)] = uniform(0.0, 1.0);
  const auto plan = [&](double s) {
    CeSettings settings;
    settings.round_runs = 10;
    settings.estimation_runs = 200;
    settings.nominal_share = s;
    std::vector<CeRound> rounds;
    std::vector<CeSample> samples;
    while (const auto round = next_ce_round(nominal, settings, 400, rounds, samples)) {
      for (std::int64_t k = 0; k < round->runs; ++k) samples.push_back({round->proposal.sample(run_seed(1, k)), 1.0});
      rounds.push_back(*round);
    }
    return rounds;
  };
  for (double s : {0.1, 0.2, 0.3}) {
    const std::vector<CeRound> rounds = plan(s);
    ASSERT_EQ(rounds.size(), 21u);
    std::vector<std::int64_t> runs;
    for (const CeRound& r : rounds) runs.push_back(r.runs);
    EXPECT_EQ(runs.front(), 10);
    EXPECT_EQ(runs.back(), 200);
    const double c = s + (1.0 - s) * std::pow(0.1, 18);
    EXPECT_DOUBLE_EQ(rounds.back().proposal.least_ratio(), c);
    EXPECT_NEAR(nominal_worth(rounds, runs), 10.0 + 390.0 * c, 1e-9);
    const double bound = zero_failure_upper_bound(rounds, runs);
    EXPECT_NEAR(10.0 * std::log1p(-bound) + 390.0 * std::log1p(-c * bound), std::log(0.05), 1e-9);
    // A little above a plain campaign of as many runs as the search's worth W (log(1 - c p) >=
    // c log(1 - p)), below -log(0.05) / W (prod_k (1 - c_k p)^n_k <= exp(-p W)).
    const double worth = 10.0 + 390.0 * c;
    EXPECT_GE(bound, 1.0 - std::pow(0.05, 1.0 / worth));
    EXPECT_LE(bound, -std::log(0.05) / worth);
  }
  EXPECT_NEAR(nominal_worth(plan(0.1), std::vector<std::int64_t>(21, 0)), 0.0, 1e-12);
  // The bound of these settings (quoted in docs/search.md): 6.06 %, 3.39 %, 2.35 %.
  const auto bound_of = [&](double s) {
    const std::vector<CeRound> rounds = plan(s);
    std::vector<std::int64_t> runs;
    for (const CeRound& r : rounds) runs.push_back(r.runs);
    return zero_failure_upper_bound(rounds, runs);
  };
  EXPECT_NEAR(bound_of(0.1), 0.06060, 0.00001);
  EXPECT_NEAR(bound_of(0.2), 0.03387, 0.00001);
  EXPECT_NEAR(bound_of(0.3), 0.02349, 0.00001);
}

// Coverage where the proposal is as bad as it may be: the failure region F = {u > 1 - p} lies
// wholly where the fitted component draws nothing, so a run of an adapted round fails with
// probability exactly s p. With p 10 % above the bound, a search finds no failure in at most
// 5 % of 4000 seeded repetitions (3.5 % expected); with p at half the bound, in far more (the
// bound is not a point estimate). Each run draws as the search does (RoundProposal::sample).
TEST(ZeroFailureBound, CoversTheWorstPlacedFailureRegion) {
  const std::vector<CeRound> rounds = bound_rounds(0.1, 1);
  const std::vector<std::int64_t> runs = {20, 180};
  const double bound = zero_failure_upper_bound(rounds, runs);
  auto none_failed_share = [&](double p) {
    int none = 0;
    const int trials = 4000;
    for (int trial = 0; trial < trials; ++trial) {
      bool failed = false;
      std::uint64_t run = 0;
      for (size_t k = 0; k < rounds.size() && !failed; ++k) {
        for (std::int64_t i = 0; i < runs[k] && !failed; ++i) {
          const double u = rounds[k].proposal.sample(run_seed(static_cast<std::uint64_t>(trial) + 1, run++)).at("u");
          failed = u > 1.0 - p;
        }
      }
      none += !failed;
    }
    return static_cast<double>(none) / trials;
  };
  EXPECT_LE(none_failed_share(1.1 * bound), 0.05);
  EXPECT_GT(none_failed_share(0.5 * bound), 0.15);
}

TEST(CrossEntropy, PlansRoundsWithinTheBudget) {
  const Toy toy;
  CeSettings settings;
  settings.round_runs = 30;
  settings.estimation_runs = 50;
  std::vector<CeRound> rounds;
  std::vector<CeSample> samples;
  // A margin that never fails: adaptation runs until only the estimation runs remain.
  while (const auto round = next_ce_round(toy.nominal, settings, 125, rounds, samples)) {
    for (std::int64_t k = 0; k < round->runs; ++k) samples.push_back({{{"x1", 0.0}, {"x2", 0.0}, {"u", 0.5}, {"c", 0.0}}, 1.0});
    rounds.push_back(*round);
  }
  ASSERT_EQ(rounds.size(), 4u);  // 30 + 30 + 15 adaptation runs, 50 for the estimate
  EXPECT_EQ(rounds[2].runs, 15);
  EXPECT_TRUE(rounds[3].estimation);
  EXPECT_EQ(rounds[3].first_run, 75);
  EXPECT_EQ(rounds[3].runs, 50);
  // Every proposal keeps the nominal's support: a uniform becomes a truncated normal on [0, 1].
  EXPECT_EQ(rounds[1].proposal.parameters.at("u").shifted.kind, Distribution::Kind::truncated_normal);
  EXPECT_EQ(rounds[1].proposal.parameters.at("u").shifted.min, 0.0);
  EXPECT_EQ(rounds[1].proposal.parameters.at("u").shifted.max, 1.0);
  // No budget left for adaptation: plain Monte Carlo in one estimation round.
  settings.estimation_runs = 200;
  const auto plain = next_ce_round(toy.nominal, settings, 125, {}, {});
  ASSERT_TRUE(plain);
  EXPECT_TRUE(plain->estimation);
  EXPECT_EQ(plain->runs, 125);
}

}  // namespace
}  // namespace shelfcross::verification
