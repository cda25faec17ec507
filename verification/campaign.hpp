#pragma once
// Monte Carlo campaigns over a scenario's dispersions: the per-thread worker that runs the
// co-simulation, the records it stores, and the campaign's summary statistics.

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "render/renderer.hpp"
#include "verification/campaign_pool.hpp"
#include "verification/cosim.hpp"
#include "verification/results_store.hpp"
#include "verification/scenario.hpp"

namespace shelfcross::verification {

/// One worker thread: its own renderer (EGL context), re-targeted at each run's dispersed
/// warehouse; everything else is built per run.
class CampaignWorker : public RunWorker {
 public:
  explicit CampaignWorker(std::shared_ptr<const Scenario> nominal);
  RunRecord run(std::int64_t index, std::uint64_t seed) override;

 private:
  std::shared_ptr<const Scenario> nominal_;
  std::unique_ptr<render::Renderer> renderer_;
};

/// The renderer options a scenario asks for (noise, blur).
render::RenderOptions render_options_for(const Scenario& scenario);

/// The record a run leaves in the results database.
RunRecord make_run_record(std::int64_t index, const RunSetup& setup, const RunResult& result, double wall_s);

/// A compact trajectory (10 Hz: t, x, y, z, yaw; approach and crossing start times) as JSON.
std::string trace_json(const RunResult& result);

/// Campaign statistics over the stored runs 0..runs_requested-1 (summary.json):
/// runs, successes, success_rate, success_lower_95 (one-sided Clopper-Pearson), outcomes,
/// per-metric statistics (mean, p50, p95, p99, max), campaign_hash (over the run hashes in
/// run order; empty while runs are missing).
nlohmann::json summarize_campaign(const std::vector<RunRecord>& runs, std::int64_t runs_requested);

}  // namespace shelfcross::verification
