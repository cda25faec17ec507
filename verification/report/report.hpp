#pragma once
// The campaign report: DIR/report.md with its PNG plots beside it, from DIR/results.sqlite.
//   summary table (success rate and its 95 % lower bound, outcome counts, metric statistics),
//   safety apart from mission success (contacts and their 95 % upper bound, safe aborts,
//   inventory errors; also in summary.json under "safety"; near misses, under "near_misses"),
//   cost: CPU seconds per run and per simulated second, runs per core-hour (summary.json:
//   "cost"),
//   top and side views of every trajectory with the shelf and the crossed cells (paper Fig. 24),
//   altitude, heading and lateral errors against the target cell from the start of the
//   approach (Fig. 26-28), histograms of settling times and entry offsets, every failed run
//   with its outcome and the command that replays it, and likewise every near miss.

#include <filesystem>
#include <string>

#include "verification/campaign/campaign.hpp"

namespace shelfcross::verification {

/// Writes DIR/summary.json and DIR/report.md with its plots; returns the summary.
/// Throws ResultsMismatch when DIR holds no results database.
CampaignSummary write_campaign_report(const std::filesystem::path& dir);

/// The report's "Safety apart from mission success" section (markdown): contacts with their
/// rate and one-sided 95 % upper bound, safe aborts, inventory errors, other failures, and the
/// near misses apart from them (with how many of those succeeded).
std::string safety_section(const SafetySummary& safety, const NearMissSummary& near_misses);

/// The report's "Cost" section (markdown): runs with a CPU figure, CPU seconds per run (mean,
/// p50, p95, max) and per simulated second, runs per core-hour; "not recorded" without figures.
std::string cost_section(const CostSummary& cost, std::int64_t runs);

}  // namespace shelfcross::verification
