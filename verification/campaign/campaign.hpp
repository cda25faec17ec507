#pragma once
// Monte Carlo campaigns over a scenario's dispersions: the per-thread worker that runs the
// co-simulation, the records it stores, and the campaign's summary statistics.

#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "render/renderer.hpp"
#include "verification/campaign/campaign_pool.hpp"
#include "verification/campaign/results_store.hpp"
#include "verification/cosim/cosim.hpp"
#include "verification/scenario/dispersion.hpp"
#include "verification/scenario/scenario.hpp"
#include "verification/statistics/statistics.hpp"

namespace shelfcross::verification {

/// A run's dispersion draws from its seed. Unset in a campaign: the scenario's own
/// (draw_dispersions(nominal.dispersions, seed)); a rare-event search draws from its round's
/// proposal instead (search.hpp). Must be a pure function of the seed (runs replay).
using DrawFunction = std::function<DrawnValues(std::uint64_t run_seed)>;

/// Whose CPU time a run's RunRecord::cpu_s is: the worker thread's (a worker thread beside
/// others in one process), or the whole process's (a worker process serving one run at a time,
/// run_process.hpp, where any thread a driver adds is counted too).
enum class CpuClock { thread, process };

/// One worker thread: its own renderer (EGL context), re-targeted at each run's dispersed
/// warehouse; everything else is built per run.
class CampaignWorker : public RunWorker {
 public:
  explicit CampaignWorker(std::shared_ptr<const Scenario> nominal, DrawFunction draw = {},
                          CpuClock cpu_clock = CpuClock::thread);
  /// The run with draw(seed), or the scenario's own draws when no draw function was given.
  RunRecord run(std::int64_t index, std::uint64_t seed) override;
  /// The run with the given draws (what a worker process is sent by its parent).
  RunRecord run_drawn(std::int64_t index, std::uint64_t seed, const DrawnValues& drawn);

 private:
  RunRecord run_setup(std::int64_t index, const RunSetup& setup);
  std::shared_ptr<const Scenario> nominal_;
  DrawFunction draw_;
  CpuClock cpu_clock_;
  std::unique_ptr<render::Renderer> renderer_;
};


/// The record a run leaves in the results database (cpu_s none: the caller measures it).
RunRecord make_run_record(std::int64_t index, const RunSetup& setup, const RunResult& result, double wall_s);

/// A compact trajectory (10 Hz: t, x, y, z, yaw; approach and crossing start times) as JSON.
std::string trace_json(const RunResult& result);

/// The metrics a campaign summarizes, each a number or nothing per run: mission time, path,
/// clearance, |entry offsets|, the approach responses' settling times and overshoots, the
/// inventory's precision and recall, and the link's counts and loss fractions. Names and values
/// come from one list (campaign.cpp), so a summary key cannot drift from what is computed.
const std::vector<std::string>& summary_metric_names();
/// The run's value of each (aligned with summary_metric_names(); nullopt where it has none).
std::vector<std::optional<double>> summary_metric_values(const RunMetrics& m);

/// What a campaign's runs cost in CPU time (RunRecord::cpu_s), over the runs with a figure.
/// Informative: it depends on the machine and its load, unlike everything else in a summary.
struct CostSummary {
  Summary cpu_s_per_run;  ///< count 0: no run has a figure (a database from before cpu_s)
  std::optional<double> cpu_s_per_simulated_s;  ///< sum cpu_s / sum mission_time_s, runs with both
};

/// The near misses (is_near_miss, stored_run.hpp): runs that touched nothing but came closer
/// to a shelf than the scenario's cosim.near_miss_m, counted apart from contacts and success.
struct NearMissSummary {
  double near_miss_m = 0.0;        ///< the threshold they were judged at
  std::int64_t runs = 0;           ///< near misses
  std::int64_t successes = 0;      ///< of which the mission succeeded
  double rate = 0.0;               ///< runs / the campaign's stored runs
};

/// A campaign's summary (summary.json), over the stored runs 0..runs_requested-1.
struct CampaignSummary {
  std::int64_t runs = 0;            ///< stored runs counted
  std::int64_t runs_requested = 0;
  std::int64_t successes = 0;
  double success_rate = 0.0;
  double success_lower_95 = 0.0;    ///< one-sided Clopper-Pearson
  std::map<std::string, std::int64_t> outcomes;  ///< keys among known_run_outcomes()
  SafetySummary safety;             ///< contacts apart from safe aborts
  NearMissSummary near_misses;      ///< summary.json's "near_misses"
  std::map<std::string, Summary> metrics;        ///< keys among summary_metric_names()
  CostSummary cost;                 ///< summary.json's "cost"
  std::string campaign_hash;        ///< over the run hashes in run order; empty while runs are missing
};
void to_json(nlohmann::json& j, const CampaignSummary& s);
/// Strict like the run metrics: unknown outcome or metric names, missing keys and wrong types
/// throw std::invalid_argument naming the key.
void from_json(const nlohmann::json& j, CampaignSummary& s);

/// Campaign statistics over the stored runs 0..runs_requested-1, near misses judged at
/// `near_miss_m` (the scenario's cosim.near_miss_m). Throws std::invalid_argument on a stored
/// run whose metrics do not read back.
CampaignSummary summarize_campaign(const std::vector<RunRecord>& runs, std::int64_t runs_requested, double near_miss_m);

}  // namespace shelfcross::verification
