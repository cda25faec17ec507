// shelfcross campaign --scenario FILE --runs N --seed S --jobs J --out DIR [--shard I/N]: a
// Monte Carlo crossing campaign; resumable (the same command again runs only what is missing).
// Under mpirun (built with SHELFCROSS_MPI), rank 0 coordinates and stores, the other ranks
// run simulations on J threads each (distributed/mpi_campaign.hpp).
#include <unistd.h>

#include <chrono>
#include <csignal>
#include <cstdio>
#include <iostream>
#include <optional>
#include <thread>

#include "command_registry.hpp"
#include "verification/campaign/campaign.hpp"
#include "verification/campaign/run_process.hpp"
#include "verification/report/report.hpp"
#include "stop_signal.hpp"
#include "worker_options.hpp"
#ifdef SHELFCROSS_WITH_MPI
#include "distributed/mpi_campaign.hpp"
#endif

namespace shelfcross::app {
namespace {

struct CampaignOptions {
  std::string scenario = verification::kDefaultScenarioFile;
  std::int64_t runs = 100;
  std::uint64_t seed = 1;
  int jobs = static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  std::string out = "out/campaign";
  std::string shard;       ///< "I/N", empty for the whole campaign
  double rank_timeout_s = 60.0;
  verification::WorkerLimits limits;
};

std::string duration(double s) {
  char text[32];
  std::snprintf(text, sizeof text, "%d:%02d:%02d", static_cast<int>(s) / 3600, static_cast<int>(s) / 60 % 60,
                static_cast<int>(s) % 60);
  return text;
}

/// The progress bar on stderr: redrawn in place on a terminal, every 10 % otherwise.
std::function<void(const verification::CampaignProgress&)> progress_printer() {
  const bool tty = isatty(STDERR_FILENO);
  auto last_line = std::make_shared<std::int64_t>(-1);
  return [tty, last_line](const verification::CampaignProgress& p) {
    const int width = 30;
    const int filled = static_cast<int>(width * p.done / std::max<std::int64_t>(1, p.total));
    char line[160];
    std::snprintf(line, sizeof line, "[%s%s] %lld/%lld runs, %lld successes, %s left", std::string(filled, '#').c_str(),
                  std::string(width - filled, '.').c_str(), static_cast<long long>(p.done),
                  static_cast<long long>(p.total), static_cast<long long>(p.successes), duration(p.remaining_s).c_str());
    if (tty) {
      std::cerr << '\r' << line << (p.done == p.total ? "\n" : "") << std::flush;
    } else if (p.done * 10 / std::max<std::int64_t>(1, p.total) != *last_line || p.done == p.total) {
      *last_line = p.done * 10 / std::max<std::int64_t>(1, p.total);
      std::cerr << line << '\n';
    }
  };
}

/// The campaign's store, opened (or created) with the fully resolved scenario.
struct OpenedCampaign {
  std::shared_ptr<const verification::Scenario> nominal;
  verification::ResultsStore store;
};

OpenedCampaign open_campaign(const CampaignOptions& o) {
  auto nominal = std::make_shared<const verification::Scenario>(verification::load_scenario(o.scenario));
  std::filesystem::create_directories(o.out);
  const verification::CampaignMeta meta{verification::write_scenario(*nominal), o.seed, o.runs};
  return {nominal, verification::ResultsStore::open_or_create(std::filesystem::path(o.out) / "results.sqlite", meta)};
}

/// Each run in a worker process of this program (verification/campaign/run_process.hpp).
verification::WorkerFactory worker_factory(std::shared_ptr<const verification::Scenario> nominal,
                                           const CampaignOptions& o) {
  return verification::process_worker_factory(std::move(nominal), o.limits);
}

/// Writes the report and prints the outcome; 0 when every run (of the shard) is stored.
int finish(const CampaignOptions& o, const verification::Shard& shard, verification::ResultsStore& store,
           const std::string& name, std::int64_t added, double elapsed_s) {
  const verification::CampaignSummary summary = verification::write_campaign_report(o.out);
  verification::CampaignCollector::Options only_shard;
  only_shard.shard = shard;
  const verification::CampaignCollector stored(store, o.runs, only_shard);
  const auto& p = stored.progress();
  std::cout << "campaign " << name << ": " << added << " runs this time";
  if (added > 0 && elapsed_s > 0) {
    char rate[96];
    std::snprintf(rate, sizeof rate, " in %.1f s (%.0f runs per hour)", elapsed_s,
                  3600.0 * static_cast<double>(added) / elapsed_s);
    std::cout << rate;
  }
  if (shard.count > 1) {
    std::cout << "; shard " << shard.index << "/" << shard.count << ": " << p.done << " of its " << p.total
              << " runs stored (merge the shards with `shelfcross merge`)\n";
  } else {
    // Rates as JSON writes them: the shortest text that reads back to the same double.
    std::cout << ", " << summary.runs << " of " << o.runs << " stored; " << summary.successes
              << " successes, success rate " << nlohmann::json(summary.success_rate) << ", 95 % lower bound "
              << nlohmann::json(summary.success_lower_95) << "\n";
    if (p.done == p.total) std::cout << "campaign hash " << summary.campaign_hash << "\n";
  }
  if (const verification::CostSummary& cost = summary.cost; cost.cpu_s_per_run.count > 0) {
    char line[160];
    std::snprintf(line, sizeof line, "CPU per run %.2f s (mean of %lld runs with a figure)", cost.cpu_s_per_run.mean,
                  static_cast<long long>(cost.cpu_s_per_run.count));
    std::cout << line;
    if (cost.cpu_s_per_simulated_s) {
      std::snprintf(line, sizeof line, ", %.3f s per simulated second", *cost.cpu_s_per_simulated_s);
      std::cout << line;
    }
    std::cout << "\n";
  }
  std::cout << "wrote " << o.out << "/results.sqlite, summary.json, report.md\n";
  if (p.done < p.total) {
    std::cout << "interrupted: run the same command again to resume\n";
    return 130;
  }
  return 0;
}

int run_in_this_process(const CampaignOptions& o, const verification::Shard& shard) {
  OpenedCampaign c = open_campaign(o);
  const auto t0 = std::chrono::steady_clock::now();  // informative: runs per hour
  const std::int64_t added = verification::run_pending(
      c.store, o.seed, o.runs, worker_factory(c.nominal, o),
      {.jobs = o.jobs, .on_progress = progress_printer(), .stop = &stop_requested(), .shard = shard});
  const double elapsed_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return finish(o, shard, c.store, c.nominal->name, added, elapsed_s);
}

#ifdef SHELFCROSS_WITH_MPI
std::chrono::milliseconds rank_timeout(const CampaignOptions& o) {
  return std::chrono::milliseconds(static_cast<std::int64_t>(o.rank_timeout_s * 1000.0));
}

int run_under_mpi(const CampaignOptions& o, const verification::Shard& shard) {
  distributed::MpiSession mpi;
  if (mpi.size() == 1) return run_in_this_process(o, shard);
  // The launcher ends the job with SIGTERM (Ctrl-C on mpirun, a rank that died): every rank
  // goes at once; committed runs are safe and the same command resumes.
  die_on_signals();
  distributed::CampaignSetup setup;
  if (mpi.rank() != 0) {
    distributed::share_setup(mpi, setup);
    if (!setup.error.empty()) return 2;  // rank 0 reports it
    auto nominal = std::make_shared<const verification::Scenario>(
        verification::parse_scenario(setup.scenario_yaml, "scenario from rank 0"));
    distributed::serve_campaign(mpi, setup.campaign_seed, o.jobs, worker_factory(nominal, o), rank_timeout(o));
    return 0;
  }
  std::optional<OpenedCampaign> c;
  try {
    c.emplace(open_campaign(o));
    setup = {c->store.meta().scenario_yaml, o.seed, ""};
  } catch (const std::exception& e) {
    setup.error = e.what();
    distributed::share_setup(mpi, setup);  // the other ranks leave; main reports the error
    throw;
  }
  distributed::share_setup(mpi, setup);
  std::cerr << "campaign on " << mpi.size() - 1 << " worker ranks x " << o.jobs << " threads\n";
  const auto t0 = std::chrono::steady_clock::now();  // informative: runs per hour
  const distributed::CoordinatorResult r = distributed::coordinate_campaign(
      mpi, c->store, o.runs,
      {.on_progress = progress_printer(), .stop = &stop_requested(), .shard = shard,
       .rank_timeout = rank_timeout(o)});
  const double elapsed_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  if (r.ranks_lost > 0) std::cerr << r.ranks_lost << " worker rank(s) lost; their runs were handed out again\n";
  if (r.ranks_failed > 0) std::cerr << r.ranks_failed << " worker rank(s) could not start their workers\n";
  return finish(o, shard, c->store, c->nominal->name, r.committed, elapsed_s);
}
#endif

const CommandRegistration kCampaign{
    "campaign", "Run a Monte Carlo crossing campaign over the scenario's dispersions (resumable; mpirun-able)",
    [](CLI::App& sub) {
      auto o = std::make_shared<CampaignOptions>();
      sub.add_option("--scenario", o->scenario, "scenario file")->capture_default_str();
      sub.add_option("--runs", o->runs, "number of runs")->capture_default_str()->check(CLI::Range(1, 10000000));
      sub.add_option("--seed", o->seed, "campaign seed; run k's seed is a fixed hash of (seed, k)")->capture_default_str();
      sub.add_option("--jobs", o->jobs, "worker processes, one run each at a time (per worker rank under mpirun; default: all cores)")
          ->capture_default_str()
          ->check(CLI::Range(1, 1024));
      sub.add_option("--out", o->out, "output folder: results.sqlite, summary.json, report.md")->capture_default_str();
      sub.add_option("--shard", o->shard,
                     "I/N: run only slice I (0..N-1) of N, the runs k with k % N == I, into --out; "
                     "combine the slices with `shelfcross merge`");
      sub.add_option("--rank-timeout", o->rank_timeout_s,
                     "under `mpirun --enable-recovery`: seconds of silence after which a worker rank counts as lost "
                     "and its runs are handed out again (and workers give up on a silent rank 0)")
          ->capture_default_str()
          ->check(CLI::Range(1.0, 86400.0));
      add_worker_limit_options(sub, o->limits);
      return [o]() -> int {
        verification::Shard shard;
        if (!o->shard.empty()) {
          try {
            shard = verification::parse_shard(o->shard);
          } catch (const std::invalid_argument& e) {
            throw UsageError(e.what());
          }
        }
        stop_on_signals();
#ifdef SHELFCROSS_WITH_MPI
        if (distributed::launched_by_mpi()) return run_under_mpi(*o, shard);
#endif
        return run_in_this_process(*o, shard);
      };
    }};

}  // namespace
}  // namespace shelfcross::app
