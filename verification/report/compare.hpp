#pragma once
// The paper's Table 2 and Fig. 21 for a scenario: one Monte Carlo campaign per guidance
// strategy of the flight software (through the cells, over the tops, around the ends) with the
// same campaign seed, hence the same run seeds and the same dispersion draws run by run (a
// run's draws depend on its seed and the scenario's dispersions only, never on cosim.strategy).
//
//   OUT/<strategy>/results.sqlite, summary.json, report.md   one campaign each (resumable)
//   OUT/compare.md, OUT/compare.json                         the table beside the paper's numbers,
//                                                            and the strategies run by run
//   OUT/compare_top_view.png, OUT/compare_side_view.png      the three paths of one run (Fig. 21)

#include <atomic>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "verification/campaign/campaign_pool.hpp"
#include "verification/campaign/results_store.hpp"
#include "verification/scenario/scenario.hpp"
#include "verification/statistics/statistics.hpp"

namespace shelfcross::verification {

/// through_cells, over_tops, around_ends (Table 2's rows, in its order).
const std::vector<std::string>& compared_strategies();

/// One row of the table.
struct StrategyRow {
  std::string strategy;
  std::int64_t runs = 0;
  std::int64_t successes = 0;
  double success_rate = 0.0;
  double success_lower_95 = 0.0;            ///< one-sided Clopper-Pearson
  std::int64_t contacts = 0;                ///< runs that touched a shelf or a wall (statistics.hpp)
  double contact_upper_95 = 1.0;            ///< one-sided Clopper-Pearson upper bound
  std::int64_t safe_aborts = 0;             ///< gave up and landed without contact
  std::int64_t inventory_errors = 0;
  std::optional<double> mean_distance_m;    ///< over the successful runs (a failed run stops early)
  std::optional<double> mean_time_s;        ///< over the successful runs
  std::optional<double> mean_recall;        ///< inventory recall over every run
  double paper_distance_m = 0.0;            ///< docs/method.md section 6, Table 2
  double paper_time_s = 0.0;
};

/// The row of one strategy's campaign (runs 0..runs_requested-1; other indices are ignored).
/// Throws std::invalid_argument for a strategy not in compared_strategies() or a run whose
/// stored metrics do not read (stored_metrics.hpp's rules).
StrategyRow summarize_strategy(const std::string& strategy, const std::vector<RunRecord>& runs,
                               std::int64_t runs_requested);

/// Table 2's shape in Markdown, the paper's numbers beside the measured ones. Throws
/// std::invalid_argument for a row of an unknown strategy.
std::string comparison_table_markdown(const std::vector<StrategyRow>& rows);

/// Table 2 run by run: the method's claim is that through the cells is the shortest and the
/// fastest path, and a mean can hide the runs where it was not. Over the runs that every
/// strategy flew successfully (the same seed and draws in each), how often the first strategy
/// (through the cells) was strictly the shortest and strictly the fastest of all, with
/// one-sided 95 % Clopper-Pearson lower bounds, and against each other strategy the paired
/// differences (other - first) of time and distance: how many runs it lost, the Hodges-Lehmann
/// shift with its 95 % interval and the Wilcoxon signed-rank p-value (statistics.hpp).
struct RunByRun {
  struct Against {
    std::string strategy;
    std::int64_t pairs = 0;                ///< runs both flew successfully
    std::int64_t shorter = 0, faster = 0;  ///< of them, runs where the first strategy was strictly
    SignedRankResult time_s, distance_m;   ///< of other - first; n 0 when there are no pairs
  };
  std::string first;                     ///< the strategy judged (compared_strategies()'s first)
  std::int64_t runs = 0;                 ///< runs every strategy flew successfully
  std::int64_t shortest = 0, fastest = 0;
  double shortest_lower_95 = 0.0, fastest_lower_95 = 0.0;
  std::vector<Against> against;          ///< the other strategies, in order
  std::vector<std::int64_t> not_fastest; ///< run indices where another strategy was as fast or faster
};

/// From each strategy's stored runs (runs_per_strategy[k] of strategies[k]; run indices below
/// runs_requested). Throws std::invalid_argument for fewer than two strategies or a
/// successful run whose stored metrics do not read.
RunByRun compare_run_by_run(const std::vector<std::string>& strategies,
                            const std::vector<std::vector<RunRecord>>& runs_per_strategy, std::int64_t runs_requested);

/// The section of compare.md; empty text when no run succeeded for every strategy.
std::string run_by_run_markdown(const RunByRun& r);

/// Top (x, y) and side (x, z) views of the mission's shelves with one run's path per strategy:
/// the lowest run index that succeeded for every strategy, else run 0. Returns that index
/// (-1 when some strategy has no run 0). Requires out_dir to exist; throws std::runtime_error
/// when a PNG cannot be written.
std::int64_t write_comparison_plots(const Scenario& nominal,
                                    const std::vector<std::vector<RunRecord>>& runs_per_strategy,
                                    const std::filesystem::path& out_dir);

struct CompareOptions {
  int jobs = 1;
  std::function<void(const std::string& strategy, const CampaignProgress&)> on_progress;
  const std::atomic<bool>* stop = nullptr;  ///< see PoolOptions::stop
  /// The workers of one strategy's campaign; unset: CampaignWorker threads in this process
  /// (`shelfcross compare` runs them in worker processes, verification/campaign/run_process.hpp).
  std::function<WorkerFactory(std::shared_ptr<const Scenario>)> make_workers;
};

/// Runs (or resumes) the three campaigns and writes everything listed above. Returns
/// compare.json's content: {"scenario", "seed", "runs", "plotted_run", "rows": [...],
/// "run_by_run": {...} (RunByRun), "complete": every campaign has all its runs}. Creates
/// out_dir. Throws what a campaign throws (campaign.hpp, results_store.hpp) and
/// std::runtime_error when a file cannot be written; a stop request returns early with
/// "complete": false.
nlohmann::json run_comparison(const Scenario& nominal, std::int64_t runs, std::uint64_t seed,
                              const std::filesystem::path& out_dir, const CompareOptions& options);

}  // namespace shelfcross::verification
