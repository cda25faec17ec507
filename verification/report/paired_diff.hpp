#pragma once
// Two campaigns on the same runs, compared pair by pair (`shelfcross diff BASE NEW`): did the
// change help, is NEW worse anywhere, and which runs flipped?
//
// Pairing. By default a run of BASE is paired with the run of NEW of the same index, and the two
// campaigns must be the same experiment: the same campaign seed (so the same run seeds), the same
// scenario (compared as parsed, so a key a later build added with its default does not count),
// and, run by run, the same drawn dispersions. Anything else is refused (PairingRefused, naming
// the first difference) before anything is written: a build comparison whose draws moved is not
// a paired comparison. With allow_different_scenarios (a link model, a scenario switch, a
// changed dispersion) runs are paired by their run seed, and the scenario keys and the draws that
// differ are listed instead. Only runs stored on both sides are paired, so a campaign still
// running, or resumed, is compared on what both have (counted in the report).
//
// Every value is read typed: outcomes by statistics.hpp's classes, metrics through
// stored_metrics() and summary_metric_values() (the campaign summary's one list), the crossing's
// push from the stored trace (crossing_push.hpp), draws through stored_draws(), CPU seconds from
// RunRecord::cpu_s.

#include <cstdint>
#include <filesystem>
#include <optional>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "verification/campaign/stored_run.hpp"
#include "verification/scenario/dispersion.hpp"
#include "verification/scenario/scenario.hpp"
#include "verification/statistics/statistics.hpp"

namespace shelfcross::verification {

/// The two campaigns cannot be paired as asked; nothing was written.
class PairingRefused : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// One side of a comparison: a campaign's results as stored.
struct DiffSide {
  std::filesystem::path db_path;
  std::filesystem::path dir;  ///< the folder `shelfcross replay` takes (the database's)
  CampaignMeta meta;
  Scenario scenario;
  std::vector<RunRecord> runs;
};

/// Reads a campaign folder (DIR/results.sqlite) or a results database itself, read-only in
/// effect (a campaign may still be writing it). Throws ResultsMismatch when there is none.
DiffSide load_diff_side(const std::filesystem::path& folder_or_database);

struct DiffOptions {
  bool allow_different_scenarios = false;
  double confidence = 0.95;  ///< of every interval
};

/// A scenario key (its YAML path, e.g. "cosim.link.model") whose value differs.
struct ScenarioDifference {
  std::string key;
  std::string base;  ///< "(absent)" where that side has no such key
  std::string next;
};

/// A dispersion whose draw differs in some pairs (allow_different_scenarios only).
struct DrawDifference {
  std::string name;
  std::int64_t pairs = 0;  ///< pairs where it differs (or is drawn on one side only)
  std::int64_t first_base_run = -1, first_new_run = -1;
  std::optional<double> first_base, first_new;  ///< none: not drawn on that side
};

/// One yes/no event over the pairs: its table, the exact McNemar test, and the difference of its
/// rates NEW - BASE with Newcombe's interval (statistics.hpp).
struct EventComparison {
  PairedTable table;
  McNemarTest mcnemar;
  double base_rate = 0.0, new_rate = 0.0;
  Interval difference;  ///< of new_rate - base_rate
};

/// One metric over the pairs where both sides have it: NEW - BASE.
struct MetricComparison {
  std::string name;
  double tolerance = 0.0;      ///< metric_tolerance(name)
  std::int64_t pairs = 0;
  SignedRankResult paired;     ///< meaningful when pairs > 0
  std::int64_t moved_up = 0;   ///< NEW - BASE > tolerance
  std::int64_t moved_down = 0; ///< NEW - BASE < -tolerance
  std::vector<double> base, next;  ///< the paired values, for the plots
  /// Each side's (run index, value) over every pair where that side has the metric, whether or
  /// not the other has it: a run that crossed on one side only still counts for its closest call.
  std::vector<std::pair<std::int64_t, double>> base_each, new_each;
};

/// A paired run whose outcome differs, or whose near-miss class (is_near_miss, stored_run.hpp,
/// each side at its own scenario's cosim.near_miss_m) does.
struct Flip {
  std::int64_t base_run = 0, new_run = 0;
  std::uint64_t seed = 0;
  std::string base_outcome, new_outcome, base_detail, new_detail;
  bool success_changed = false, contact_changed = false;
  bool near_miss_changed = false;
  bool new_near_miss = false;  ///< NEW's run is a near miss (meaningful where near_miss_changed)
  DrawnValues base_draws, new_draws;
};

struct PairedDiff {
  DiffSide base, next;
  bool paired_by_seed = false;        ///< allow_different_scenarios: by run seed, else by index
  double confidence = 0.95;
  std::int64_t pairs = 0;
  std::int64_t identical = 0;         ///< pairs with the same run hash
  std::vector<ScenarioDifference> scenario_differences;
  std::vector<DrawDifference> draw_differences;
  std::int64_t pairs_with_other_draws = 0;  ///< pairs with any draw differing
  EventComparison failures;           ///< the event: the mission did not succeed
  EventComparison contacts;           ///< the event: a contact (shelf or wall)
  EventComparison near_misses;        ///< the event: a near miss (no contact, closer than cosim.near_miss_m)
  std::vector<MetricComparison> metrics;  ///< summary_metric_names(), crossing_push_m, cpu_s
  std::vector<Flip> flips;            ///< in BASE's run order
};

/// Pairs the runs and computes everything above. Throws PairingRefused (see the file comment),
/// also when no run is stored on both sides; std::invalid_argument on a stored run whose
/// metrics or draws do not read back.
PairedDiff pair_campaigns(DiffSide base, DiffSide next, const DiffOptions& options);

/// The tolerance beyond which a run counts as moved, from the metric's unit (its name's suffix):
/// lengths (_m) 5 mm, times (_s) 0.1 s, CPU seconds (cpu_s) 0.5 s, fractions, ratios and
/// overshoots 0.01, link counts 0 (any change).
double metric_tolerance(const std::string& metric_name);

/// The gate: NEW is worse than BASE at level alpha, for mission success or for contacts (the
/// one-sided exact McNemar p-value at most alpha). Near misses are reported, not gated.
bool new_is_worse(const PairedDiff& diff, double alpha);

/// The differing keys of two resolved scenarios (write_scenario's YAML), flattened to paths;
/// empty when the scenarios are equal.
std::vector<ScenarioDifference> scenario_differences(const Scenario& base, const Scenario& next);

}  // namespace shelfcross::verification
