#pragma once
// A campaign's results: one SQLite database (WAL journal), one transaction per finished run.
//
// Tables
//   campaign(key TEXT PRIMARY KEY, value TEXT)   format_version, scenario_yaml (fully
//                                                resolved), campaign_seed, runs_requested
//   runs(run_index INTEGER PRIMARY KEY, seed TEXT, dispersion_json TEXT, outcome TEXT,
//        metrics_json TEXT, run_hash TEXT, wall_s REAL, trace_json TEXT,
//        cpu_s REAL)                             NULL: no CPU figure (RunRecord::cpu_s)
//
// Format versions: 3 added runs.cpu_s. A version-2 database (campaigns stored before it) is
// migrated when a writer opens it (open_or_create): ALTER TABLE runs ADD COLUMN cpu_s REAL and
// format_version 3, in one transaction; its old runs keep cpu_s NULL. Readers (open_existing:
// report, replay, merge's sources) read a version-2 database as it is, without CPU figures,
// and leave it unchanged.
//
// Durability: WAL with synchronous=FULL, so a committed run survives SIGKILL (and power loss);
// a run killed mid-way left nothing, and is simply run again on resume. Reopening a database
// made for a different scenario or seed is refused, so two campaigns never mix.
// Not thread-safe: one thread (the campaign's collector) owns a store.
// One writer per database: open_or_create takes an exclusive flock on DB.lock (ResultsBusy).

#include <cstdint>
#include <filesystem>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

namespace SQLite {
class Database;
}

namespace shelfcross::verification {

struct CampaignMeta {
  std::string scenario_yaml;        ///< the fully resolved scenario the runs used
  std::uint64_t campaign_seed = 0;
  std::int64_t runs_requested = 0;
  bool operator==(const CampaignMeta&) const = default;
};

struct RunRecord {
  std::int64_t index = 0;
  std::uint64_t seed = 0;
  std::string dispersion_json;  ///< drawn values, {"name": value, ...}; typed: stored_draws()
  std::string outcome;          ///< one of known_run_outcomes()
  std::string metrics_json;     ///< StoredMetrics as JSON; read it typed with stored_metrics() (run_metrics_json.hpp)
  std::string run_hash;         ///< 32 hex digits (run_hash.hpp)
  double wall_s = 0.0;          ///< wall time the run took (informative, not hashed)
  std::string trace_json;       ///< a compact trajectory for the report's plots
  /// CPU seconds (user + system) the run itself took where it ran: its worker process's, or
  /// its worker thread's (run_process.cpp, campaign.cpp). Informative, not hashed, like
  /// wall_s. None (not 0) where nothing measured it: a run lost with its worker process
  /// (crashed, hung), a worker error, a run stored before format 3.
  std::optional<double> cpu_s;
  /// Every field, wall_s and cpu_s included: compare runs for determinism with both cleared.
  bool operator==(const RunRecord&) const = default;
};

/// Every outcome a stored run can have: the co-simulation's (verification::RunOutcome by
/// outcome_name) and the campaign's own: crashed and hung (a worker process that died or was
/// killed, run_process.hpp), worker_error (a worker that threw). insert() refuses any other,
/// so a misspelt outcome fails loudly instead of landing in the report as a class of its own.
const std::vector<std::string>& known_run_outcomes();

/// A run record as one line of JSON (no raw newline), and back: the message that carries a
/// finished run from a worker process or rank to the store. decode throws
/// std::invalid_argument on a malformed message; cpu_s may be null or absent (none).
std::string encode_run_record(const RunRecord& record);
RunRecord decode_run_record(const std::string& message);

/// The database does not belong to this campaign (other scenario or seed), or is not one.
class ResultsMismatch : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// Another process is writing the same results database (a second campaign, search or merge
/// into the same folder). Nothing was written.
class ResultsBusy : public ResultsMismatch {
 public:
  using ResultsMismatch::ResultsMismatch;
};

class ResultsStore {
 public:
  /// Opens `db_path`, creating it with `meta` if absent. An existing database must hold the
  /// same scenario and seed; its runs_requested is raised to meta's if larger. The writer
  /// holds an exclusive lock on `db_path` + ".lock" (flock, released when the process ends,
  /// even by SIGKILL) for the store's lifetime: a second writer is refused with ResultsBusy,
  /// naming the holder's pid, instead of racing the first to the same run indices. A
  /// version-2 database is migrated to version 3 (see the file comment). Throws ResultsMismatch
  /// on a database of another scenario, seed or format version.
  static ResultsStore open_or_create(const std::filesystem::path& db_path, const CampaignMeta& meta);
  /// Opens an existing database read-write (report, replay, merge), version 2 or 3 as it is.
  /// Throws ResultsMismatch when there is none or its format version is unknown.
  static ResultsStore open_existing(const std::filesystem::path& db_path);

  ResultsStore(ResultsStore&&) noexcept;
  ResultsStore& operator=(ResultsStore&&) noexcept;
  ~ResultsStore();

  const CampaignMeta& meta() const { return meta_; }
  std::vector<std::int64_t> finished_indices() const;
  /// Commits one run in its own transaction; a run index already present is refused, and so
  /// is any run into a version-2 database (open_existing's, not migrated): throws
  /// ResultsMismatch; std::invalid_argument on an unknown outcome.
  void insert(const RunRecord& run);
  /// Commits several runs in one transaction (all or none); a run index already present is refused.
  void insert(const std::vector<RunRecord>& runs);
  /// Every stored run, by index.
  std::vector<RunRecord> runs() const;

 private:
  struct WriterLock;
  explicit ResultsStore(std::unique_ptr<SQLite::Database> db);
  void read_meta();
  std::unique_ptr<WriterLock> lock_;  ///< held by open_or_create's stores; readers take none
  std::unique_ptr<SQLite::Database> db_;
  CampaignMeta meta_;
  int format_version_ = 0;  ///< 2 (no runs.cpu_s: a reader's, not yet migrated) or 3
};

}  // namespace shelfcross::verification
