#pragma once
// The search's report (docs/search.md): DIR/report.md with its PNGs, DIR/search_summary.json
// and DIR/margins.csv, from DIR/results.sqlite of `shelfcross search`:
//   the rounds (runs, level, elites, failures of the target class, each proposal's parameters);
//   per failure class, the importance-sampling estimate of its probability under the nominal
//   dispersions with its interval (rare_event.hpp), next to the plain Monte Carlo estimate of
//   a campaign of the same scenario when one is given (its failures over its runs, with the
//   two-sided 95 % Clopper-Pearson interval);
//   the failures found, each with the command that replays it (with its video);
//   the most likely failure (highest nominal density among the target class's failures);
//   margin against draw, one plot per dispersed parameter (search_margin_<name>.png), and the
//   margin against run index (search_progress.png).

#include <filesystem>
#include <optional>

#include <nlohmann/json.hpp>

namespace shelfcross::verification {

/// Writes the report; returns the summary (search_summary.json). `campaign_dir`, when set,
/// holds a campaign (results.sqlite) of the same scenario for the plain Monte Carlo column;
/// a campaign of another scenario is refused (ResultsMismatch). Throws ResultsMismatch when
/// `dir` holds no search.
nlohmann::json write_search_report(const std::filesystem::path& dir,
                                   const std::optional<std::filesystem::path>& campaign_dir = std::nullopt);

}  // namespace shelfcross::verification
