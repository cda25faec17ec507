#pragma once
// The rare-event search over a scenario's dispersions (`shelfcross search`, docs/search.md):
// cross-entropy rounds (rare_event.hpp) whose runs are co-simulated, stored and resumed like a
// campaign's, and the importance-sampling estimate of each failure class (margin.hpp).
//
// Runs: run k has the seed run_seed(search seed, k), as run k of a campaign with that seed;
// its dispersed values are drawn from its round's proposal with the same per-parameter
// streams (RoundProposal::sample), so round 0, which draws from the nominal dispersions,
// repeats a campaign's runs exactly (same records, same run hashes), and so does every later
// run whose selector picks the nominal component. The seed seeds everything else.
//
// Storage: DIR/results.sqlite is a campaign database (results_store.hpp; campaign_seed = the
// search seed, runs_requested = the budget; every run with its drawn values), plus
//   search(key TEXT PRIMARY KEY, value TEXT)         settings: the target class, the budget
//                                                    and the CE settings, as JSON
//   search_rounds(round INTEGER PRIMARY KEY, first_run INTEGER, runs INTEGER,
//                 estimation INTEGER, level REAL, elites INTEGER, proposal_json TEXT)
// proposal_json holds {"nominal_share": s, "parameters": {name: {"shifted", "nominal",
// "nominal_share"}}} (RoundProposal). A round is stored before its first run starts. Resume: the same command reads the rounds,
// runs what is missing of the last one, and plans the next ones from the stored runs; every
// plan is a function of the stored runs, so an interrupted search ends where an uninterrupted
// one does. Reopening with other settings is refused, and so is resuming a search of an older
// format (the settings' format_version); its rounds still read.
//
// Parallelism: the runs of a round go through run_pending (campaign_pool.hpp) on `jobs`
// workers, each with its own renderer; in `shelfcross search` each is a worker process
// (run_process.hpp), which is sent each run's draws, so a run that crashes or hangs is recorded
// as such (a mission failure of unknown margin: margin.hpp) and the search goes on. Under
// mpirun, `run_round` hands each round to the worker ranks instead (app/cmd_search.cpp).
// No shards: a round's proposal depends on every run before it.

#include <atomic>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "verification/campaign/campaign.hpp"
#include "verification/campaign/campaign_pool.hpp"
#include "verification/campaign/results_store.hpp"
#include "verification/scenario/scenario.hpp"
#include "verification/search/margin.hpp"
#include "verification/search/rare_event.hpp"

namespace shelfcross::verification {

struct SearchSettings {
  std::uint64_t seed = 1;
  std::int64_t budget = 40;
  FailureClass target = FailureClass::contact;
  CeSettings ce;
  bool operator==(const SearchSettings&) const;
};

/// The settings as stored (and compared on resume).
nlohmann::json search_settings_json(const SearchSettings& settings);

/// A distribution (a nominal or a proposal) as JSON {"kind": ..., parameters} and back.
nlohmann::json distribution_json(const Distribution& d);
Distribution distribution_from_json(const nlohmann::json& j);
/// A round's proposal as stored (search_rounds.proposal_json) and sent to MPI worker ranks:
/// {"nominal_share": s, "parameters": {parameter: {"shifted": ..., "nominal": ...,
/// "nominal_share": s_j}}}; and back, reading format 1's {parameter: {...}} as s = 0.
nlohmann::json proposals_json(const RoundProposal& q);
RoundProposal proposals_from_json(const nlohmann::json& j);

/// The search's tables in a results database (see the file comment).
class SearchStore {
 public:
  /// Opens DIR/results.sqlite's search tables, creating them with `settings` if absent;
  /// throws ResultsMismatch when they hold other settings.
  static SearchStore open_or_create(const std::filesystem::path& db_path, const SearchSettings& settings);
  /// Opens an existing search (report); throws ResultsMismatch when db_path holds none.
  static SearchStore open_existing(const std::filesystem::path& db_path);
  SearchStore(SearchStore&&) noexcept;
  SearchStore& operator=(SearchStore&&) noexcept;
  ~SearchStore();

  const nlohmann::json& settings_json() const { return settings_; }
  std::vector<CeRound> rounds() const;
  void insert_round(const CeRound& round);

 private:
  struct Impl;
  explicit SearchStore(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
  nlohmann::json settings_;
};

/// Whether db_path holds a search (its search tables).
bool is_search_database(const std::filesystem::path& db_path);

/// The margins of a stored run; a "worker_error" run has none (NaN in every class).
RunMargins record_margins(const Scenario& nominal, const RunRecord& record);

/// The draws of a round's runs: proposal.sample(seed).
DrawFunction round_draws(RoundProposal proposal);

struct SearchProgress {
  int round = 0;
  std::int64_t round_runs = 0;
  bool estimation = false;
  CampaignProgress runs;  ///< of the whole budget
};

struct SearchRunOptions {
  int jobs = 1;
  /// The workers of one round, drawing with `draw`; unset: CampaignWorker threads in this
  /// process (`shelfcross search` runs them in worker processes, run_process.hpp).
  std::function<WorkerFactory(std::shared_ptr<const Scenario> nominal, DrawFunction draw)> make_workers;
  const std::atomic<bool>* stop = nullptr;
  std::function<void(const CeRound&)> on_round;            ///< a round starts (or resumes)
  std::function<void(const CampaignProgress&)> on_progress; ///< after each committed run
  /// Runs what is missing of runs [0, runs) of `store` (a round's end) and returns how many it
  /// committed; unset: run_pending on this process's workers (make_workers). `shelfcross search`
  /// under mpirun hands the round to the worker ranks instead.
  std::function<std::int64_t(ResultsStore& store, std::int64_t runs, const CeRound& round)> run_round;
};

struct SearchRunResult {
  std::int64_t committed = 0;  ///< runs this session
  bool complete = false;       ///< the budget is spent (or the estimation round done)
};

/// Runs (or resumes) the search into `out`/results.sqlite. Throws ResultsMismatch for a
/// database of another scenario, seed or settings.
SearchRunResult run_search(std::shared_ptr<const Scenario> nominal, const SearchSettings& settings,
                           const std::filesystem::path& out, const SearchRunOptions& options);

}  // namespace shelfcross::verification
