#include "verification/search/rare_event.hpp"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <limits>
#include <numeric>

#include <boost/math/distributions/normal.hpp>

#include "shelfcross/random.hpp"

namespace shelfcross::verification {
namespace {

constexpr double kMinusInfinity = -std::numeric_limits<double>::infinity();

/// Mixed into a run's seed for its selector stream (RoundProposal::sample): a stream apart
/// from the per-parameter dispersion streams, which mix the seed with a name's hash.
constexpr std::uint64_t kSelectorSalt = 0x5e1ec7020e5e1ec7ull;

/// log(exp(a) + exp(b)).
double log_sum_exp(double a, double b) {
  const double hi = std::max(a, b);
  if (hi == kMinusInfinity) return kMinusInfinity;
  return hi + std::log1p(std::exp(std::min(a, b) - hi));
}

/// Margins ordered with NaN (no margin) after every number.
bool margin_less(double a, double b) {
  if (std::isnan(a)) return false;
  if (std::isnan(b)) return true;
  return a < b;
}

/// The run count of the rounds so far.
std::int64_t runs_used(const std::vector<CeRound>& rounds) {
  return rounds.empty() ? 0 : rounds.back().first_run + rounds.back().runs;
}

}  // namespace

ParameterProposals nominal_proposals(const ParameterDistributions& nominal) {
  ParameterProposals q;
  for (const auto& [name, f] : nominal) q[name] = ProposalDistribution::of_nominal(f);
  return q;
}

double log_density(const ParameterDistributions& d, const DrawnValues& x) {
  double sum = 0.0;
  for (const auto& [name, distribution] : d) sum += distribution.log_pdf(x.at(name));
  return sum;
}

double log_density(const ParameterProposals& q, const DrawnValues& x) {
  double sum = 0.0;
  for (const auto& [name, proposal] : q) sum += proposal.log_pdf(x.at(name));
  return sum;
}

ParameterDistributions RoundProposal::nominal() const {
  ParameterDistributions f;
  for (const auto& [name, q] : parameters) f[name] = q.nominal;
  return f;
}

double RoundProposal::log_pdf(const DrawnValues& x) const {
  const double log_f = log_density(nominal(), x);
  if (nominal_share >= 1.0) return log_f;
  const double log_fit = log_density(parameters, x);
  if (nominal_share <= 0.0) return log_fit;
  return log_sum_exp(std::log(nominal_share) + log_f, std::log1p(-nominal_share) + log_fit);
}

double RoundProposal::least_ratio() const {
  const double s = std::clamp(nominal_share, 0.0, 1.0);
  double fitted = 1.0;
  for (const auto& [name, q] : parameters) fitted *= std::clamp(q.nominal_share, 0.0, 1.0);
  return s + (1.0 - s) * fitted;
}

DrawnValues RoundProposal::sample(std::uint64_t run_seed) const {
  bool from_nominal = nominal_share >= 1.0;
  if (nominal_share > 0.0 && nominal_share < 1.0) {
    RandomStream selector(mix64(run_seed ^ kSelectorSalt), StreamId::dispersion);
    from_nominal = selector.uniform01() < nominal_share;
  }
  return from_nominal ? draw_dispersions(nominal(), run_seed) : draw_dispersions(parameters, run_seed);
}

double mixture_log_weight(const ParameterDistributions& nominal, const std::vector<CeRound>& rounds,
                          const std::vector<std::int64_t>& runs_per_round, const DrawnValues& x) {
  assert(rounds.size() == runs_per_round.size());
  const double total = static_cast<double>(std::accumulate(runs_per_round.begin(), runs_per_round.end(), std::int64_t{0}));
  // log sum_k exp(a_k), a_k = log(n_k / N) + log q_k(x), shifted by the largest a_k.
  std::vector<double> a;
  for (size_t k = 0; k < rounds.size(); ++k) {
    if (runs_per_round[k] <= 0) continue;
    a.push_back(std::log(static_cast<double>(runs_per_round[k]) / total) + rounds[k].proposal.log_pdf(x));
  }
  const double top = a.empty() ? kMinusInfinity : *std::max_element(a.begin(), a.end());
  if (!std::isfinite(top)) return kMinusInfinity;  // outside every proposal
  double sum = 0.0;
  for (double v : a) sum += std::exp(v - top);
  return log_density(nominal, x) - (top + std::log(sum));
}

double nominal_worth(const std::vector<CeRound>& rounds, const std::vector<std::int64_t>& runs_per_round) {
  assert(rounds.size() == runs_per_round.size());
  double worth = 0.0;
  for (size_t k = 0; k < rounds.size(); ++k) {
    worth += rounds[k].proposal.least_ratio() * static_cast<double>(std::max<std::int64_t>(0, runs_per_round[k]));
  }
  return worth;
}

double zero_failure_upper_bound(const std::vector<CeRound>& rounds, const std::vector<std::int64_t>& runs_per_round,
                                double confidence) {
  assert(rounds.size() == runs_per_round.size());
  // c_k: the least ratio q_k / f anywhere (file comment).
  std::vector<std::pair<double, double>> c_n;  // (c_k, n_k)
  for (size_t k = 0; k < rounds.size(); ++k) {
    const double c = rounds[k].proposal.least_ratio();
    if (runs_per_round[k] > 0 && c > 0.0) c_n.emplace_back(c, static_cast<double>(runs_per_round[k]));
  }
  if (c_n.empty()) return 1.0;
  // log P(no failure | p) <= sum_k n_k log(1 - c_k p), decreasing in p; equal to log(alpha) at
  // the bound. Bisection on p in [0, 1].
  const double log_alpha = std::log(1.0 - confidence);
  const auto log_none = [&](double p) {
    double l = 0.0;
    for (const auto& [c, n] : c_n) l += n * std::log1p(-c * p);
    return l;
  };
  if (log_none(1.0) > log_alpha) return 1.0;
  double lo = 0.0, hi = 1.0;
  for (int i = 0; i < 100; ++i) {
    const double mid = 0.5 * (lo + hi);
    (log_none(mid) > log_alpha ? lo : hi) = mid;
  }
  return hi;
}

CeFit ce_refit(const ParameterDistributions& nominal, const RoundProposal& current,
               const std::vector<CeSample>& samples, const CeSettings& settings) {
  assert(!samples.empty());
  const auto n = static_cast<std::int64_t>(samples.size());
  const std::int64_t k = std::min(
      n, std::max(settings.min_elites, static_cast<std::int64_t>(std::ceil(settings.elite_fraction * static_cast<double>(n)))));
  std::vector<double> margins;
  for (const CeSample& s : samples) margins.push_back(s.margin);
  std::nth_element(margins.begin(), margins.begin() + (k - 1), margins.end(), margin_less);
  const double kth = margins[static_cast<size_t>(k - 1)];
  CeFit fit;
  // gamma = max(0, k-th smallest): once k runs fail, the elites are exactly the failures.
  // A NaN k-th margin (fewer than k runs with a margin): every run with a margin is an elite.
  fit.level = std::isnan(kth) ? kth : std::max(0.0, kth);
  std::vector<const CeSample*> elites;
  for (const CeSample& s : samples) {
    if (std::isnan(s.margin)) continue;
    if (std::isnan(fit.level) || s.margin <= fit.level) elites.push_back(&s);
  }
  fit.elites = static_cast<std::int64_t>(elites.size());
  if (elites.empty()) {  // no run says anything: keep the proposal
    fit.proposal = current;
    return fit;
  }
  // Weights: while the level is above 0 (no failure among the elites yet) all 1, so the search
  // moves toward failure as fast as the elites lead (CE as an optimiser); at level 0 (the
  // elites are failures) the likelihood ratios f / q_t, so the fit tends to the zero-variance
  // density f 1[fail] / p for the estimate. Scaled by the largest (only ratios matter).
  std::vector<double> log_w;
  for (const CeSample* s : elites) {
    log_w.push_back(fit.level > 0.0 ? 0.0 : log_density(nominal, s->drawn) - current.log_pdf(s->drawn));
  }
  const double log_w_max = *std::max_element(log_w.begin(), log_w.end());
  std::vector<double> w;
  for (double lw : log_w) w.push_back(std::exp(lw - log_w_max));
  const double w_sum = std::accumulate(w.begin(), w.end(), 0.0);
  const double alpha = settings.smoothing;

  fit.proposal.nominal_share = settings.nominal_share;
  for (const auto& [name, f_j] : nominal) {
    if (!settings.adapted.empty() && !settings.adapted.count(name)) {
      fit.proposal.parameters[name] = ProposalDistribution::of_nominal(f_j);
      continue;
    }
    // The current parameters are those of the shifted component (the nominal's in round 0).
    const ProposalDistribution& current_j = current.parameters.at(name);
    const Distribution& q_j = current_j.nominal_share >= 1.0 ? current_j.nominal : current_j.shifted;
    if (f_j.is_choice()) {
      // Weighted frequency of each value among the elites, smoothed with q_j's probabilities.
      const double q_total = std::accumulate(q_j.weights.begin(), q_j.weights.end(), 0.0);
      std::vector<double> p(f_j.values.size(), 0.0);
      for (size_t i = 0; i < elites.size(); ++i) {
        const double x = elites[i]->drawn.at(name);
        for (size_t v = 0; v < f_j.values.size(); ++v) {
          if (f_j.values[v] == x) {
            p[v] += w[i] / w_sum;
            break;
          }
        }
      }
      // Smoothed; a value no elite took keeps a share of q_j's probability (and the
      // defensive mixture keeps the nominal's).
      for (size_t v = 0; v < p.size(); ++v) p[v] = alpha * p[v] + (1.0 - alpha) * q_j.weights[v] / q_total;
      fit.proposal.parameters[name] = {choice_proposal(f_j, p), f_j, settings.parameter_share};
      continue;
    }
    double mean = 0.0;
    for (size_t i = 0; i < elites.size(); ++i) mean += w[i] / w_sum * elites[i]->drawn.at(name);
    double var = 0.0;
    for (size_t i = 0; i < elites.size(); ++i) {
      const double d = elites[i]->drawn.at(name) - mean;
      var += w[i] / w_sum * d * d;
    }
    // The current parameters: a uniform nominal (round 0) has no mean and stddev of its own;
    // its centre and its scale stand for them.
    const bool q_is_uniform = q_j.kind == Distribution::Kind::uniform;
    const double q_mean = q_is_uniform ? 0.5 * (q_j.min + q_j.max) : q_j.mean;
    const double q_stddev = q_is_uniform ? q_j.scale() : q_j.stddev;
    mean = alpha * mean + (1.0 - alpha) * q_mean;
    double stddev = alpha * std::sqrt(var) + (1.0 - alpha) * q_stddev;
    const bool unbounded = f_j.kind == Distribution::Kind::normal;
    stddev = std::max(stddev, (unbounded ? 1.0 : settings.min_stddev_fraction) * f_j.scale());
    if (!(stddev > 0.0)) stddev = settings.min_stddev_fraction * std::max(1.0, std::abs(mean));  // point-mass nominal
    if (!unbounded) mean = std::clamp(mean, f_j.min, f_j.max);
    fit.proposal.parameters[name] = {continuous_proposal(f_j, mean, stddev), f_j, settings.parameter_share};
  }
  return fit;
}

std::optional<CeRound> next_ce_round(const ParameterDistributions& nominal, const CeSettings& settings,
                                     std::int64_t budget, const std::vector<CeRound>& rounds,
                                     const std::vector<CeSample>& samples) {
  const std::int64_t used = runs_used(rounds);
  if (used >= budget) return std::nullopt;
  if (!rounds.empty() && rounds.back().estimation) return std::nullopt;
  const std::int64_t adaptation_budget = std::max<std::int64_t>(0, budget - settings.estimation_runs);
  CeRound next;
  next.index = static_cast<int>(rounds.size());
  next.first_run = used;
  if (rounds.empty()) {
    next.proposal = RoundProposal::of_nominal(nominal);
    next.level = std::numeric_limits<double>::quiet_NaN();  // no level before the first round
    next.estimation = adaptation_budget == 0;  // no adaptation asked for: plain Monte Carlo
    next.runs = next.estimation ? budget : std::min(settings.round_runs, adaptation_budget);
    return next;
  }
  const CeRound& last = rounds.back();
  assert(static_cast<std::int64_t>(samples.size()) >= used);
  const std::vector<CeSample> last_samples(samples.begin() + last.first_run, samples.begin() + used);
  const CeFit fit = ce_refit(nominal, last.proposal, last_samples, settings);
  next.proposal = fit.proposal;
  next.level = fit.level;
  next.elites = fit.elites;
  next.estimation = fit.level == 0.0 || used >= adaptation_budget;
  next.runs = next.estimation ? budget - used : std::min(settings.round_runs, adaptation_budget - used);
  return next;
}

std::string estimate_doubts(const IsEstimate& e) {
  std::string doubts;
  if (e.runs > 0 && (e.mean_weight < 0.5 || e.mean_weight > 2.0)) doubts = "uneven weights";
  if (e.failures > 0 && e.failure_ess < std::max(2.0, 0.3 * static_cast<double>(e.failures))) {
    doubts += (doubts.empty() ? "" : "; ") + std::string("few effective failures");
  }
  return doubts;
}

IsEstimate importance_estimate(const std::vector<double>& log_weights, const std::vector<bool>& failed,
                               double confidence) {
  assert(log_weights.size() == failed.size());
  IsEstimate e;
  e.confidence = confidence;
  e.runs = static_cast<std::int64_t>(log_weights.size());
  if (e.runs == 0) return e;
  std::vector<double> y(log_weights.size(), 0.0);
  double w_sum = 0.0, w2_sum = 0.0;
  for (size_t i = 0; i < y.size(); ++i) {
    if (!failed[i]) continue;
    ++e.failures;
    y[i] = std::exp(log_weights[i]);
    w_sum += y[i];
    w2_sum += y[i] * y[i];
  }
  const double n = static_cast<double>(e.runs);
  for (double lw : log_weights) e.mean_weight += std::exp(lw) / n;
  e.p_hat = std::accumulate(y.begin(), y.end(), 0.0) / n;
  if (e.failures == 0) return e;
  e.failure_ess = w_sum * w_sum / w2_sum;
  double ss = 0.0;
  for (double v : y) ss += (v - e.p_hat) * (v - e.p_hat);
  e.standard_error = e.runs > 1 ? std::sqrt(ss / (n - 1.0) / n) : std::numeric_limits<double>::infinity();
  const double z = boost::math::quantile(boost::math::normal_distribution<double>(), 0.5 + 0.5 * confidence);
  const double relative = e.standard_error / e.p_hat;
  e.lower = e.p_hat * std::exp(-z * relative);
  e.upper = e.p_hat * std::exp(z * relative);
  e.clt_lower = std::max(0.0, e.p_hat - z * e.standard_error);
  e.clt_upper = e.p_hat + z * e.standard_error;
  return e;
}

}  // namespace shelfcross::verification
