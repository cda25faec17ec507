#pragma once
// The report of a paired comparison (`shelfcross diff`, paired_diff.hpp), in the campaign
// report's style:
//   OUT/diff.md    the verdict (identical runs, mission success and contacts with their paired
//                  tests), the 2 x 2 tables, every metric's paired difference, the flipped runs
//                  with their draws and replay commands, the scenario keys and draws that differ
//   OUT/diff.json  the same as data
//   OUT/clearance_base_vs_new.png   least clearance per run, BASE against NEW, with the diagonal
//   OUT/difference_<metric>.png     histograms of NEW - BASE for the main metrics

#include <filesystem>
#include <optional>

#include <nlohmann/json.hpp>

#include "verification/report/paired_diff.hpp"

namespace shelfcross::verification {

/// The gate's level when `--fail-if-worse` was given: the report states its verdict.
struct DiffReportOptions {
  std::optional<double> fail_if_worse_alpha;
};

/// diff.json's content.
nlohmann::json diff_json(const PairedDiff& diff, const DiffReportOptions& options = {});

/// The `shelfcross replay` command of a side's run, with the picture video.
std::string replay_command(const DiffSide& side, std::int64_t run);

/// Writes everything listed above into `out_dir` (created); returns diff.json's content.
/// Throws std::runtime_error when a file cannot be written.
nlohmann::json write_diff_report(const PairedDiff& diff, const std::filesystem::path& out_dir,
                                 const DiffReportOptions& options = {});

}  // namespace shelfcross::verification
