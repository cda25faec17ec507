// shelfcross search --scenario FILE --budget N --seed S --jobs J --out DIR: cross-entropy
// search for failures over the scenario's dispersions and the importance-sampling estimate of
// each failure class's probability (verification/search/search.hpp, docs/search.md); resumable (the
// same command again runs only what is missing). Runs happen in worker processes, as a
// campaign's do (verification/campaign/run_process.hpp). Under mpirun (built with SHELFCROSS_MPI), rank
// 0 plans the rounds and stores, and each round's runs go to the other ranks as a campaign's
// would (distributed/mpi_campaign.hpp), the round's proposal broadcast before them. No shards:
// a round's proposal depends on every run of the rounds before it.
#include <atomic>
#include <chrono>
#include <csignal>
#include <iostream>
#include <optional>

#include "command_registry.hpp"
#include "verification/campaign/run_process.hpp"
#include "verification/search/search.hpp"
#include "verification/search/search_report.hpp"
#include "stop_signal.hpp"
#include "worker_options.hpp"
#ifdef SHELFCROSS_WITH_MPI
#include "distributed/mpi_campaign.hpp"
#endif

namespace shelfcross::app {
namespace {

struct SearchOptions {
  std::string scenario = verification::kDefaultScenarioFile;
  std::int64_t budget = 40;
  std::uint64_t seed = 1;
  int jobs = 1;
  std::string out = "out/search";
  std::string failure_class = "contact";
  std::int64_t round_runs = 10;
  std::int64_t estimation_runs = -1;  ///< -1: half the budget
  double elite_fraction = 0.1;
  std::int64_t min_elites = 3;
  double smoothing = 0.8;
  double min_stddev_fraction = 0.5;
  double nominal_share = verification::CeSettings{}.nominal_share;
  double parameter_share = verification::CeSettings{}.parameter_share;
  std::string campaign;
  std::vector<std::string> parameters;
  double rank_timeout_s = 60.0;
  verification::WorkerLimits limits;
};

/// Announces each round on stderr.
void print_round(const verification::CeRound& round) {
  std::cerr << "round " << round.index << ": runs " << round.first_run << ".." << round.first_run + round.runs - 1
            << (round.index == 0       ? " from the nominal dispersions"
                : round.estimation     ? " from the final proposal (estimation)"
                                       : " from the refitted proposal")
            << "\n";
}

void print_progress(const verification::CampaignProgress& p) {
  std::cerr << "  " << p.done << "/" << p.total << " runs stored\n";
}

/// The options every way of running a search shares; `run_round` and `make_workers` are the
/// caller's.
verification::SearchRunOptions run_options(const SearchOptions& o) {
  verification::SearchRunOptions r;
  r.jobs = o.jobs;
  r.stop = &stop_requested();
  r.on_round = print_round;
  r.on_progress = print_progress;
  return r;
}

/// Each run in a worker process of this program, with the round's draws.
verification::WorkerFactory worker_factory(std::shared_ptr<const verification::Scenario> nominal,
                                           verification::DrawFunction draw, const SearchOptions& o) {
  return verification::process_worker_factory(std::move(nominal), o.limits, "/proc/self/exe", std::move(draw));
}

verification::SearchRunResult run_in_this_process(std::shared_ptr<const verification::Scenario> nominal,
                                                  const verification::SearchSettings& settings,
                                                  const SearchOptions& o) {
  verification::SearchRunOptions r = run_options(o);
  r.make_workers = [&o](std::shared_ptr<const verification::Scenario> scenario, verification::DrawFunction draw) {
    return worker_factory(std::move(scenario), std::move(draw), o);
  };
  return verification::run_search(std::move(nominal), settings, o.out, r);
}

#ifdef SHELFCROSS_WITH_MPI
/// Rank 0 plans and stores; before each round it broadcasts the round's proposal, then hands
/// the round's runs out as a campaign (coordinate_campaign), which ends with the ranks leaving
/// their serve loop; an empty broadcast ends the search. Ranks 1..N-1 serve round after round.
/// A lost rank ends the search (no collective can complete without it): the same command
/// resumes it. Returns nullopt on the worker ranks.
std::optional<verification::SearchRunResult> run_under_mpi(std::shared_ptr<const verification::Scenario> nominal,
                                                           const verification::SearchSettings& settings,
                                                           const SearchOptions& o) {
  distributed::MpiSession mpi;
  if (mpi.size() == 1) return run_in_this_process(std::move(nominal), settings, o);
  // As for a campaign: the launcher ends the job with SIGTERM; every rank goes at once.
  die_on_signals();
  const auto rank_timeout = std::chrono::milliseconds(static_cast<std::int64_t>(o.rank_timeout_s * 1000.0));
  distributed::CampaignSetup setup{verification::write_scenario(*nominal), settings.seed, ""};
  distributed::share_setup(mpi, setup);  // every rank loaded the same file; rank 0's text rules
  if (mpi.rank() != 0) {
    auto scenario = std::make_shared<const verification::Scenario>(
        verification::parse_scenario(setup.scenario_yaml, "scenario from rank 0"));
    for (;;) {
      std::string round;
      distributed::broadcast_text(mpi, round);
      if (round.empty()) break;
      const verification::DrawFunction draw =
          verification::round_draws(verification::proposals_from_json(nlohmann::json::parse(round)));
      distributed::serve_campaign(mpi, setup.campaign_seed, o.jobs, worker_factory(scenario, draw, o), rank_timeout);
      if (!mpi.intact()) break;
    }
    return std::nullopt;
  }
  std::cerr << "search on " << mpi.size() - 1 << " worker ranks x " << o.jobs << " workers\n";
  verification::SearchRunOptions r = run_options(o);
  bool serving = false;  // the worker ranks are in serve_campaign, not waiting for a round
  r.run_round = [&](verification::ResultsStore& store, std::int64_t runs, const verification::CeRound& round) {
    std::string text = verification::proposals_json(round.proposal).dump();
    distributed::broadcast_text(mpi, text);
    serving = true;
    const distributed::CoordinatorResult c = distributed::coordinate_campaign(
        mpi, store, runs, {.on_progress = print_progress, .stop = &stop_requested(), .shard = {}, .rank_timeout = rank_timeout});
    serving = false;
    if (!mpi.intact()) {
      std::cerr << c.ranks_lost << " worker rank(s) lost: the search stops here; run the same command to resume\n";
      stop_requested() = true;
    }
    return c.committed;
  };
  const auto release_workers = [&] {
    std::string done;
    if (!serving && mpi.intact()) distributed::broadcast_text(mpi, done);
  };
  try {
    const verification::SearchRunResult result = verification::run_search(std::move(nominal), settings, o.out, r);
    release_workers();
    return result;
  } catch (...) {
    // E.g. another search's settings in --out: the worker ranks, waiting for a round, leave.
    // (Inside a round they give up on a silent rank 0 after --rank-timeout.)
    release_workers();
    throw;
  }
}
#endif

// The command's options, into `o`.
void add_search_options(CLI::App& sub, SearchOptions& o) {
  sub.add_option("--scenario", o.scenario, "scenario file (its dispersions are the nominal distributions)")
      ->capture_default_str();
  sub.add_option("--budget", o.budget, "runs in all")->capture_default_str()->check(CLI::Range(1, 10000000));
  sub.add_option("--seed", o.seed, "search seed; run k's seed is a fixed hash of (seed, k), as in a campaign")
      ->capture_default_str();
  sub.add_option("--jobs", o.jobs, "worker processes (per worker rank under mpirun)")
      ->capture_default_str()
      ->check(CLI::Range(1, 1024));
  sub.add_option("--out", o.out, "output folder: results.sqlite, report.md, search_summary.json, margins.csv, PNGs")
      ->capture_default_str();
  sub.add_option("--class", o.failure_class, "failure class searched for: contact, crossing, mission or near_miss")
      ->capture_default_str();
  sub.add_option("--round-runs", o.round_runs, "runs per adaptation round")
      ->capture_default_str()
      ->check(CLI::Range(2, 1000000));
  sub.add_option("--estimation-runs", o.estimation_runs,
                 "runs kept for the final proposal's estimate (default: half the budget)")
      ->check(CLI::Range(1, 10000000));
  sub.add_option("--elite-fraction", o.elite_fraction, "rho: the fraction of a round kept as elites")
      ->capture_default_str()
      ->check(CLI::Range(0.01, 0.5));
  sub.add_option("--min-elites", o.min_elites, "at least this many elites per round, whatever rho says")
      ->capture_default_str()
      ->check(CLI::Range(1, 1000000));
  sub.add_option("--smoothing", o.smoothing,
                 "alpha: the next proposal's parameters are alpha x the elites' fit + (1 - alpha) x the current")
      ->capture_default_str()
      ->check(CLI::Range(0.01, 1.0));
  sub.add_option("--min-stddev-fraction", o.min_stddev_fraction,
                 "a proposal's stddev floor on a bounded support, times the nominal's scale (stddev, or "
                 "width / sqrt 12 when smaller)")
      ->capture_default_str()
      ->check(CLI::Range(0.01, 10.0));
  sub.add_option("--nominal-share", o.nominal_share,
                 "s: the share of each adapted round's runs drawn wholly from the nominal dispersions (bounds "
                 "every weight by 1/s; each adapted run counts as s nominal runs in the zero-failure bound; 0: "
                 "none, with --parameter-share above 0)")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 1.0));
  sub.add_option("--parameter-share", o.parameter_share,
                 "s_j: each adapted parameter's fit mixed with its own nominal at this share (keeps a parameter's "
                 "ratio within 1/s_j inside the fitted component; 0: none)")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 1.0));
  sub.add_option("--parameters", o.parameters,
                 "the dispersed parameters the search adapts (comma-separated; default: all); the others keep "
                 "their nominal distribution")
      ->delimiter(',');
  sub.add_option("--campaign", o.campaign,
                 "a campaign folder of the same scenario: its plain Monte Carlo estimates go beside the search's");
  sub.add_option("--rank-timeout", o.rank_timeout_s,
                 "under `mpirun --enable-recovery`: seconds of silence after which a worker rank counts as lost "
                 "(the search then stops, to be resumed)")
      ->capture_default_str()
      ->check(CLI::Range(1.0, 86400.0));
  add_worker_limit_options(sub, o.limits);
}

// The search and its estimates, printed; 130 when interrupted (resumable).
int run_search_command(const SearchOptions& o) {
  const auto target = verification::parse_failure_class(o.failure_class);
  if (!target) throw UsageError("--class '" + o.failure_class + "': expected contact, crossing, mission or near_miss");
  verification::SearchSettings settings;
  settings.seed = o.seed;
  settings.budget = o.budget;
  settings.target = *target;
  settings.ce.round_runs = o.round_runs;
  settings.ce.elite_fraction = o.elite_fraction;
  settings.ce.min_elites = o.min_elites;
  settings.ce.smoothing = o.smoothing;
  settings.ce.min_stddev_fraction = o.min_stddev_fraction;
  settings.ce.nominal_share = o.nominal_share;
  settings.ce.parameter_share = o.parameter_share;
  if (o.nominal_share == 0.0 && o.parameter_share == 0.0) {
    throw UsageError("--nominal-share 0 with --parameter-share 0: nothing would bound the importance weights");
  }
  settings.ce.estimation_runs = o.estimation_runs < 0 ? o.budget / 2 : o.estimation_runs;
  if (settings.ce.estimation_runs > o.budget) {
    throw UsageError("--estimation-runs " + std::to_string(settings.ce.estimation_runs) + " exceeds --budget " +
                     std::to_string(o.budget));
  }
  std::optional<std::filesystem::path> campaign;
  if (!o.campaign.empty()) {
    campaign = o.campaign;
    if (!std::filesystem::exists(*campaign / "results.sqlite")) {
      throw UsageError("--campaign " + o.campaign + ": no results.sqlite there");
    }
  }
  auto nominal = std::make_shared<const verification::Scenario>(verification::load_scenario(o.scenario));
  if (nominal->dispersions.empty()) throw UsageError(o.scenario + ": no dispersions to search over");
  for (const std::string& name : o.parameters) {
    if (!nominal->dispersions.count(name)) {
      throw UsageError("--parameters: '" + name + "' is not dispersed in " + o.scenario);
    }
    settings.ce.adapted.insert(name);
  }
  stop_on_signals();
  std::optional<verification::SearchRunResult> ran;
#ifdef SHELFCROSS_WITH_MPI
  if (distributed::launched_by_mpi()) {
    ran = run_under_mpi(nominal, settings, o);
    if (!ran) return 0;  // a worker rank: rank 0 reports
  }
#endif
  if (!ran) ran = run_in_this_process(nominal, settings, o);
  const verification::SearchRunResult& r = *ran;
  const nlohmann::json summary = verification::write_search_report(o.out, campaign);
  const nlohmann::json& e = summary["estimates"][o.failure_class];
  std::cout << "search " << nominal->name << ": " << r.committed << " runs this time, " << summary["runs"]
            << " of " << o.budget << " stored; " << summary["failures"].size() << " " << o.failure_class
            << " failures";
  if (!summary["first_failure_run"].is_null()) std::cout << ", the first at run " << summary["first_failure_run"];
  // One estimate: its interval, or with no failure sampled the zero-failure bound (which
  // holds whatever the weights; their doubts concern an estimate only).
  const auto print_estimate = [](const nlohmann::json& x) {
    if (x["failures"].get<std::int64_t>() == 0) {
      std::cout << "none sampled: p <= " << x["zero_failure_upper_95"].get<double>()
                << " (one-sided 95 %, zero-failure bound; the runs are worth " << x["nominal_worth"].get<double>()
                << " nominal runs)";
      return;
    }
    std::cout << x["p_hat"].get<double>() << ", 95 % interval [" << x["lower"].get<double>() << ", "
              << x["upper"].get<double>() << "]";
    const std::string doubts = x["doubts"].get<std::string>();
    if (!doubts.empty()) std::cout << "; not to be trusted: " << doubts;
  };
  std::cout << "\nestimate of P(" << o.failure_class << " failure) from the " << e["runs"] << " runs of round "
            << e["round"] << ": ";
  print_estimate(e);
  std::cout << "\n  from every round (balance heuristic, " << e["every_round"]["runs"] << " runs): ";
  print_estimate(e["every_round"]);
  std::cout << "\nwrote " << o.out
            << "/results.sqlite, report.md, search_summary.json, margins.csv\n";
  if (!r.complete) {
    std::cout << "interrupted: run the same command again to resume\n";
    return 130;
  }
  return 0;
}

const CommandRegistration kSearch{
    "search",
    "Search the scenario's dispersions for failures (cross-entropy) and estimate their probability by importance "
    "sampling (resumable)",
    [](CLI::App& sub) {
      auto o = std::make_shared<SearchOptions>();
      add_search_options(sub, *o);
      return [o]() -> int { return run_search_command(*o); };
    }};

}  // namespace
}  // namespace shelfcross::app
