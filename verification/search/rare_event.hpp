#pragma once
// Rare-event search and estimation over a scenario's dispersion space, apart from any
// simulation: the cross-entropy (CE) method (Rubinstein & Kroese, "The Cross-Entropy Method",
// 2004, ch. 3) and the importance-sampling (IS) estimate of a failure probability.
//
// The space: x = one value per dispersed parameter, nominal density f(x) = prod_j f_j(x_j)
// (the scenario's own distributions, distribution.hpp). A run at x has a margin g(x) (margin.hpp;
// negative = failed); the failure probability is p = P_f(g(X) < 0).
//
// CE, as planned here round by round (so that a caller can run each round's simulations in
// parallel, store them, and resume):
//   round 0 draws from q_0 = f (plain Monte Carlo);
//   after round t, with its runs x_1..x_n drawn from q_t:
//     level       gamma_t = max(0, the k-th smallest margin), k = max(ceil(rho n), min_elites)
//     elites      the runs with g <= gamma_t
//     weights     while gamma_t > 0, all 1 (falsification: the fit follows the elites toward
//                 failure as fast as they lead, CE as an optimiser); at gamma_t = 0 (the elites
//                 are failures) w_i = f(x_i) / q_t(x_i), the likelihood ratio, so that the final
//                 fit tends to the zero-variance density f(x) 1[g(x) < 0] / p of the estimate
//                 (Rubinstein & Kroese weight every round; with rounds of ten runs that moved
//                 the proposal into a 3-sigma tail too slowly for a budget of tens of runs)
//     fit         per continuous parameter: the weighted mean and standard deviation of the
//                 elites (the moment fit of the Gaussian; for a truncated Gaussian it is the
//                 moment fit of the parent, an approximation of its maximum-likelihood fit);
//                 per choice parameter: the weighted frequency of each value
//     smoothing   theta_{t+1} = alpha theta_fit + (1 - alpha) theta_t (means, stddevs, weights)
//     floors      stddev >= min_stddev_fraction x the nominal's scale() on a bounded support,
//                 stddev >= the nominal's stddev for a normal nominal (on the real line a ratio
//                 f / q of Gaussians has a finite variance only for stddev_q^2 > stddev_f^2 / 2,
//                 and the elites' spread can fall below that: an unbounded parameter is searched
//                 by shifting its mean); a mean kept inside a bounded support;
//     defence     two nominal shares (Hesterberg 1995, defensive mixtures). The round's
//                 proposal is q_k(x) = s f(x) + (1 - s) prod_j q_kj(x_j): with probability s
//                 (nominal_share) the whole run is drawn from the nominal, else each parameter
//                 from q_kj = (1 - s_j) fit_kj + s_j f_j (s_j = parameter_share; s_j = 1 for a
//                 parameter kept at its nominal). So q_k >= s f everywhere: no run's weight
//                 f / q_k exceeds 1 / s, however many parameters are adapted and wherever their
//                 fits went (RoundProposal). The per-parameter share is a floor inside the
//                 fitted component: it keeps one parameter's ratio f_j / q_kj within 1 / s_j
//                 there. Without it, a parameter that does not matter drifts with the few elites
//                 to one end of its support, and a failure the fitted component draws at the
//                 other end carries a weight up to 1 / s while the others carry f / q ~ p: one
//                 run carries the estimate, which looks precise while it is not (seen on the toy
//                 of rare_event_test.cpp, whose coverage test measures the two shares together);
//   adaptation stops when gamma_t = 0 (failures fill the elite set: "failures dominate") or when
//   only the estimation runs remain of the budget; the last fit is frozen, and every remaining
//   run of the budget is drawn from it (the estimation round).
// The proposal families: a truncated Gaussian on [min, max] for uniform and truncated-normal
// nominals, a Gaussian for a normal one, reweighted values for a choice (distribution.hpp),
// each mixed with its nominal, and the product of them mixed with the joint nominal.
//
// The estimate (importance_estimate): from the n runs of the estimation round, i.i.d. from the
// frozen q, terms y_i = 1[g(x_i) < 0] f(x_i) / q(x_i); p_hat = mean(y), unbiased for any q that
// keeps f's support. Its standard error se = s_y / sqrt(n) (s_y the sample standard deviation).
// The interval is the CLT interval on the log scale (delta method: var(log p_hat) ~ (se /
// p_hat)^2): p_hat exp(-+ z se / p_hat), z the normal quantile of the two-sided level. It
// keeps the bounds positive and follows the right skew of an IS estimate better than p_hat -+
// z se at the small run counts a simulation allows; like every CLT interval it is only as good
// as s_y, which under-reports the variance when the few failures sampled all carry small
// weights (check the failures' effective sample size). With no failure sampled there is no
// estimate (p_hat = 0, no interval), but there is a bound (zero_failure_upper_bound).
//
// The zero-failure bound: the search's round k drew its n_k runs from q_k = s_k f + (1 - s_k)
// prod_j q_kj, q_kj = (1 - s_kj) fit_kj + s_kj f_j (round 0: s_0 = 1, the nominal itself). So
// q_k(x) >= c_k f(x) for every x, c_k = s_k + (1 - s_k) prod_j s_kj (RoundProposal::least_ratio;
// about s_k once a few parameters are adapted), and a failure region F of nominal probability
// p = P_f(F) has P_qk(F) >= c_k p, wherever F lies. A run's failure may also depend on the rest
// of its seed (the simulation's own noise), pi(x) = P(fail | x): then P_qk(fail) = int q_k pi >=
// c_k int f pi = c_k p all the same. Given the runs before it, each run fails with probability at
// least c p, c its round's c_k, so M_t = prod_{i <= t} 1[run i did not fail] / (1 - c_i p) is
// a nonnegative supermartingale with M_0 = 1, and by Ville's inequality
//   P(for some t: runs 1..t did not fail and prod_{i <= t} (1 - c_i p) <= alpha) <= alpha,
// however the proposals and round sizes were chosen from the runs before them (CE fits each
// round to the last, and ends adaptation early when failures fill the elites), and at whatever
// run the search is stopped or read. With n_k runs of round k, prod_i (1 - c_i p) = prod_k
// (1 - c_k p)^n_k (<= exp(-p sum_k c_k n_k)). The one-sided upper confidence bound at level
// 1 - alpha is the p at which it equals alpha (found by bisection; decreasing in p): a class
// probability above it would have shown a failure with probability at least 1 - alpha. For a
// plain campaign (every c_k = 1) it is the exact binomial bound 1 - alpha^(1/n) (about 3 / n at
// 95 %, the "rule of three").
// sum_k c_k n_k is the search's worth in nominal runs (nominal_worth): round 0's n_0 plus about
// s times the adapted runs. With per-parameter shares alone (s = 0) c_k = prod_j s_kj, 0.1^18 on
// a scenario of 18 adapted parameters: an adapted run was worth nothing.
// What it assumes: the runs' outcomes are what the simulation says (the bound is about the
// model under the scenario's dispersions, not the world); a run's outcome is a function of its
// draws and its seed, whose streams behave as independent uniforms; a run without the class's
// margin counts as no failure of it (a run never near a shelf, and a crashed or hung worker:
// the bound trusts that a crash hides no contact), and a run lost to a worker error (no draws,
// not counted) was not lost because it failed. It assumes nothing about where the failures lie:
// it holds for a region the fitted components never draw, which is also why it is no sharper
// than the nominal share allows.

#include <cstdint>
#include <map>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "verification/scenario/dispersion.hpp"
#include "verification/scenario/distribution.hpp"

namespace shelfcross::verification {

/// One distribution per dispersed parameter: the scenario's dispersions.
using ParameterDistributions = std::map<std::string, Distribution>;
/// One proposal per dispersed parameter.
using ParameterProposals = std::map<std::string, ProposalDistribution>;

/// The nominal as a proposal (every parameter's nominal_share 1).
ParameterProposals nominal_proposals(const ParameterDistributions& nominal);

/// log prod_j d_j(x_j) over d's parameters (each must be in x); -infinity outside the support.
double log_density(const ParameterDistributions& d, const DrawnValues& x);
double log_density(const ParameterProposals& q, const DrawnValues& x);

/// A round's proposal (file comment, "defence"): q(x) = s f(x) + (1 - s) prod_j q_j(x_j), f the
/// product of the parameters' nominals, q_j = parameters[j] (each already mixed with its own
/// nominal at its share), s = nominal_share in [0, 1]. q >= least_ratio() f everywhere, so
/// f / q <= 1 / least_ratio().
struct RoundProposal {
  ParameterProposals parameters;
  double nominal_share = 0.0;

  /// The nominal itself (round 0): s = 1, every parameter at its nominal.
  static RoundProposal of_nominal(const ParameterDistributions& nominal) { return {nominal_proposals(nominal), 1.0}; }
  /// f: the parameters' nominals.
  ParameterDistributions nominal() const;
  /// log q(x), by log-sum-exp of its two components.
  double log_pdf(const DrawnValues& x) const;
  /// c = s + (1 - s) prod_j s_j (s_j <= 1): the least q / f anywhere.
  double least_ratio() const;
  /// Run `run_seed`'s draws, reproducible from the seed alone. One uniform of the run's own
  /// selector stream picks the component (u < s: the nominal); the nominal component draws
  /// what a campaign's run of that seed draws (draw_dispersions of f, the per-parameter
  /// streams), the fitted one draws each parameter from q_j with the same streams. s = 1 or 0
  /// takes no selector: a round of the nominal draws exactly a campaign's values.
  DrawnValues sample(std::uint64_t run_seed) const;
  bool operator==(const RoundProposal&) const = default;
};

struct CeSettings {
  std::int64_t round_runs = 16;          ///< runs per adaptation round
  double elite_fraction = 0.1;           ///< rho
  std::int64_t min_elites = 3;           ///< at least this many elites, whatever rho n is
  double smoothing = 0.8;                ///< alpha
  double min_stddev_fraction = 0.5;      ///< stddev floor on a bounded support, times the nominal's scale()
  /// s: the whole run is drawn from the nominal with this probability; bounds every weight by
  /// 1 / s and makes each adapted run worth s nominal runs in the zero-failure bound. 0: the
  /// per-parameter shares alone (c_k = prod_j s_j).
  double nominal_share = 0.2;
  /// s_j: each adapted parameter's fit mixed with its own nominal at this share (the floor that
  /// keeps a drifting parameter's ratio within 1 / s_j inside the fitted component); 0: none.
  /// One of the two shares must be above 0, or nothing bounds the weights.
  double parameter_share = 0.1;
  std::int64_t estimation_runs = 0;      ///< at least this many runs for the final proposal
  /// The parameters CE adapts; empty: all. The others keep their nominal as proposal (ratio 1).
  /// The variance of an IS weight grows exponentially with the number of parameters whose
  /// proposal differs from the nominal (the fit of a parameter that does not matter is noise
  /// from a few elites): with tens of runs, adapt the few that matter.
  std::set<std::string> adapted;
};

/// One finished run as CE sees it. A NaN margin (the run says nothing about this failure
/// class) ranks after every number and never counts as a failure.
struct CeSample {
  DrawnValues drawn;
  double margin = 0.0;
};

/// A round: runs first_run .. first_run + runs - 1, drawn from `proposal`.
struct CeRound {
  int index = 0;
  std::int64_t first_run = 0;
  std::int64_t runs = 0;
  bool estimation = false;  ///< from the frozen final proposal, for the estimate
  /// gamma of the previous round, which this proposal was fitted to (NaN for round 0).
  double level = 0.0;
  std::int64_t elites = 0;  ///< of the previous round (0 for round 0)
  RoundProposal proposal;
};

struct CeFit {
  RoundProposal proposal;
  double level = 0.0;       ///< gamma
  std::int64_t elites = 0;
};

/// One CE update (see the file comment) from a round's samples drawn from `current`.
/// Precondition: samples not empty.
CeFit ce_refit(const ParameterDistributions& nominal, const RoundProposal& current,
               const std::vector<CeSample>& samples, const CeSettings& settings);

/// The next round after `rounds` (in order, the runs of all of them in `samples`, by run
/// index), or nullopt when the budget is spent or the estimation round is done. `samples` must
/// hold every run of `rounds` (asserted).
std::optional<CeRound> next_ce_round(const ParameterDistributions& nominal, const CeSettings& settings,
                                     std::int64_t budget, const std::vector<CeRound>& rounds,
                                     const std::vector<CeSample>& samples);

struct IsEstimate {
  std::int64_t runs = 0;
  std::int64_t failures = 0;
  double p_hat = 0.0;
  double standard_error = 0.0;
  double confidence = 0.95;
  double lower = 0.0, upper = 0.0;   ///< log-scale CLT interval; both 0 without failures
  double clt_lower = 0.0, clt_upper = 0.0;  ///< p_hat -+ z se (lower clamped at 0), for comparison
  /// Kish's effective sample size of the failures' weights, (sum w)^2 / sum w^2: near the
  /// failure count when the weights are even, near 1 when one failure dominates.
  double failure_ess = 0.0;
  /// mean(f(x_i) / q(x_i)) over all runs: an unbiased estimate of 1 for any q keeping f's
  /// support. Far from 1 (below 0.5 or above 2, say) the weights are too uneven for the runs at
  /// hand, and the interval is not to be trusted.
  double mean_weight = 0.0;
};

/// Why an estimate's interval is not to be trusted, empty when nothing speaks against it:
/// "uneven weights" when the mean weight is outside [0.5, 2] (it estimates 1); "few effective
/// failures" when the failures' Kish ESS is below max(2, 0.3 x failures), i.e. one or two
/// failures carry the estimate, so its variance, read off the same few weights, is itself
/// unreliable (gust_rare_ideal, docs/search.md: ESS 1.4 of 12 failures, p_hat 50 x below the
/// plain campaign's rate). Heuristics, not a test: both thresholds are rules of thumb.
std::string estimate_doubts(const IsEstimate& e);

/// The weight of a run drawn in any round, for the estimate from every run of the search
/// (multiple importance sampling with the balance heuristic, Veach & Guibas 1995; the
/// "deterministic mixture" weights of adaptive multiple importance sampling, Cornuet et al.
/// 2012): each run counts as a draw of the mixture of all the rounds' proposals, weighted by
/// their run counts n_k (N their sum):
///   log w(x) = log f(x) - log sum_k (n_k / N) q_k(x).
/// Each q_k >= c_k f, so w <= N / sum_k c_k n_k = N / nominal_worth everywhere (round 0 alone
/// gives N / n_0): no run carries a weight of hundreds, and the runs of the early rounds, near the nominal, cover the soft edge of a
/// failure region that the final proposal, fitted to its easiest failures, leaves out
/// (gust_rare_ideal, docs/search.md). With p_hat = mean of 1[failed] w over all N runs the
/// estimator is unbiased for fixed proposals; here each q_k was fitted to the runs before it,
/// which makes it consistent but not exactly unbiased (Cornuet et al.; the toy of
/// rare_event_test.cpp measures the coverage). `runs_per_round[k]` is round k's run count in
/// the estimate (its stored runs); the two must have one entry per round (asserted).
double mixture_log_weight(const ParameterDistributions& nominal, const std::vector<CeRound>& rounds,
                          const std::vector<std::int64_t>& runs_per_round, const DrawnValues& x);

/// sum_k c_k n_k, c_k = rounds[k].proposal.least_ratio(), n_k = runs_per_round[k]: the
/// search's worth in nominal runs for the zero-failure bound (file comment). One entry per
/// round in each (asserted).
double nominal_worth(const std::vector<CeRound>& rounds, const std::vector<std::int64_t>& runs_per_round);

/// The zero-failure upper bound on a class probability under the nominal (file comment) from
/// `rounds` with `runs_per_round[k]` runs each (stored runs with a result), at one-sided
/// `confidence`: 1 when no run was made. One entry per round in each (asserted).
double zero_failure_upper_bound(const std::vector<CeRound>& rounds, const std::vector<std::int64_t>& runs_per_round,
                                double confidence = 0.95);

/// The estimate from i.i.d. draws of one proposal: log_weight_i = log f(x_i) - log q(x_i),
/// failed_i = g(x_i) < 0. See the file comment for the interval. The two must be of one
/// length (asserted).
IsEstimate importance_estimate(const std::vector<double>& log_weights, const std::vector<bool>& failed,
                               double confidence = 0.95);

}  // namespace shelfcross::verification
