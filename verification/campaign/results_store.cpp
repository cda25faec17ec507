#include "verification/campaign/results_store.hpp"

#include <algorithm>
#include <fstream>

#include <fcntl.h>
#include <sys/file.h>
#include <unistd.h>

#include <SQLiteCpp/SQLiteCpp.h>
#include <nlohmann/json.hpp>

#include "config/strict_json.hpp"
#include "verification/cosim/run_result.hpp"

namespace shelfcross::verification {

using config::number_or_null;
namespace {

// 3: runs.cpu_s. A writer migrates a version-2 database (results_store.hpp); a reader reads it.
constexpr int kFormatVersion = 3;

void configure(SQLite::Database& db) {
  db.exec("PRAGMA journal_mode=WAL");
  db.exec("PRAGMA synchronous=FULL");
  db.exec("PRAGMA busy_timeout=10000");
}

std::string get_meta(SQLite::Database& db, const char* key) {
  SQLite::Statement q(db, "SELECT value FROM campaign WHERE key = ?");
  q.bind(1, key);
  if (!q.executeStep()) throw ResultsMismatch(std::string("results database lacks campaign key '") + key + "'");
  return q.getColumn(0).getString();
}

void set_meta(SQLite::Database& db, const char* key, const std::string& value) {
  SQLite::Statement q(db, "INSERT OR REPLACE INTO campaign(key, value) VALUES(?, ?)");
  q.bind(1, key);
  q.bind(2, value);
  q.exec();
}

}  // namespace

// An advisory flock on a file beside the database: the kernel drops it when the descriptor is
// closed or the process ends, however it ends, so a killed campaign never leaves a stale lock
// behind (a pid file would). O_CLOEXEC keeps it out of the worker processes the campaign
// execs, so only the writer itself holds it.
struct ResultsStore::WriterLock {
  int fd = -1;
  explicit WriterLock(const std::filesystem::path& db_path) {
    const std::filesystem::path lock_path = db_path.string() + ".lock";
    fd = ::open(lock_path.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
    if (fd < 0) throw ResultsMismatch(lock_path.string() + ": cannot open the lock file");
    if (::flock(fd, LOCK_EX | LOCK_NB) != 0) {
      std::string holder;
      std::getline(std::ifstream(lock_path), holder);
      ::close(fd);
      throw ResultsBusy(db_path.string() + " is being written by another process" +
                        (holder.empty() ? std::string() : " (pid " + holder + ")") +
                        "; wait for it to end, or use another --out");
    }
    // The holder's pid, for the message above; a failure to write it leaves the lock held.
    const std::string pid = std::to_string(::getpid()) + "\n";
    if (::ftruncate(fd, 0) == 0) (void)!::pwrite(fd, pid.data(), pid.size(), 0);
  }
  ~WriterLock() { ::close(fd); }
  WriterLock(const WriterLock&) = delete;
  WriterLock& operator=(const WriterLock&) = delete;
};

ResultsStore::ResultsStore(std::unique_ptr<SQLite::Database> db) : db_(std::move(db)) {}
ResultsStore::ResultsStore(ResultsStore&&) noexcept = default;
ResultsStore& ResultsStore::operator=(ResultsStore&&) noexcept = default;
ResultsStore::~ResultsStore() = default;

void ResultsStore::read_meta() {
  const std::string version = get_meta(*db_, "format_version");
  if (version != "2" && version != std::to_string(kFormatVersion)) {
    throw ResultsMismatch("results database has an unknown format version '" + version + "'");
  }
  format_version_ = std::stoi(version);
  meta_.scenario_yaml = get_meta(*db_, "scenario_yaml");
  meta_.campaign_seed = std::stoull(get_meta(*db_, "campaign_seed"));
  meta_.runs_requested = std::stoll(get_meta(*db_, "runs_requested"));
}

ResultsStore ResultsStore::open_or_create(const std::filesystem::path& db_path, const CampaignMeta& meta) {
  auto lock = std::make_unique<WriterLock>(db_path);  // before anything is read or created
  const bool exists = std::filesystem::exists(db_path);
  auto db = std::make_unique<SQLite::Database>(db_path.string(), SQLite::OPEN_READWRITE | SQLite::OPEN_CREATE);
  configure(*db);
  ResultsStore store(std::move(db));
  store.lock_ = std::move(lock);
  if (!exists) {
    SQLite::Transaction tx(*store.db_);
    store.db_->exec("CREATE TABLE campaign(key TEXT PRIMARY KEY, value TEXT NOT NULL)");
    store.db_->exec(
        "CREATE TABLE runs(run_index INTEGER PRIMARY KEY, seed TEXT NOT NULL, dispersion_json TEXT NOT NULL,"
        " outcome TEXT NOT NULL, metrics_json TEXT NOT NULL, run_hash TEXT NOT NULL, wall_s REAL NOT NULL,"
        " trace_json TEXT NOT NULL, cpu_s REAL)");  // cpu_s last, where a migration adds it
    set_meta(*store.db_, "format_version", std::to_string(kFormatVersion));
    set_meta(*store.db_, "scenario_yaml", meta.scenario_yaml);
    set_meta(*store.db_, "campaign_seed", std::to_string(meta.campaign_seed));
    set_meta(*store.db_, "runs_requested", std::to_string(meta.runs_requested));
    tx.commit();
  }
  store.read_meta();
  if (store.meta_.scenario_yaml != meta.scenario_yaml) {
    throw ResultsMismatch(db_path.string() + " holds a campaign of a different scenario; use another --out");
  }
  if (store.meta_.campaign_seed != meta.campaign_seed) {
    throw ResultsMismatch(db_path.string() + " holds a campaign with seed " +
                          std::to_string(store.meta_.campaign_seed) + ", not " + std::to_string(meta.campaign_seed));
  }
  if (meta.runs_requested > store.meta_.runs_requested) {
    set_meta(*store.db_, "runs_requested", std::to_string(meta.runs_requested));
    store.meta_.runs_requested = meta.runs_requested;
  }
  if (store.format_version_ == 2) {
    // Its runs were stored without a CPU figure: they keep cpu_s NULL.
    SQLite::Transaction tx(*store.db_);
    store.db_->exec("ALTER TABLE runs ADD COLUMN cpu_s REAL");
    set_meta(*store.db_, "format_version", std::to_string(kFormatVersion));
    tx.commit();
    store.format_version_ = kFormatVersion;
  }
  return store;
}

ResultsStore ResultsStore::open_existing(const std::filesystem::path& db_path) {
  if (!std::filesystem::exists(db_path)) throw ResultsMismatch(db_path.string() + ": no such results database");
  auto db = std::make_unique<SQLite::Database>(db_path.string(), SQLite::OPEN_READWRITE);
  configure(*db);
  ResultsStore store(std::move(db));
  store.read_meta();
  return store;
}

std::vector<std::int64_t> ResultsStore::finished_indices() const {
  std::vector<std::int64_t> out;
  SQLite::Statement q(*db_, "SELECT run_index FROM runs ORDER BY run_index");
  while (q.executeStep()) out.push_back(q.getColumn(0).getInt64());
  return out;
}

void ResultsStore::insert(const RunRecord& run) { insert(std::vector<RunRecord>{run}); }

const std::vector<std::string>& known_run_outcomes() {
  static const std::vector<std::string> names = [] {
    std::vector<std::string> v;
    for (RunOutcome o : {RunOutcome::success, RunOutcome::collision, RunOutcome::left_arena, RunOutcome::timeout,
                         RunOutcome::numerical_failure, RunOutcome::flight_software_exception,
                         RunOutcome::mission_aborted, RunOutcome::no_crossing, RunOutcome::inventory_mismatch}) {
      v.emplace_back(outcome_name(o));
    }
    v.insert(v.end(), {"crashed", "hung", "worker_error"});
    return v;
  }();
  return names;
}

void ResultsStore::insert(const std::vector<RunRecord>& runs) {
  for (const RunRecord& run : runs) {
    const auto& known = known_run_outcomes();
    if (std::find(known.begin(), known.end(), run.outcome) == known.end()) {
      throw std::invalid_argument("run " + std::to_string(run.index) + ": unknown outcome '" + run.outcome +
                                  "' (not stored; known: verification::known_run_outcomes)");
    }
  }
  if (format_version_ < kFormatVersion) {
    throw ResultsMismatch("a version-" + std::to_string(format_version_) +
                          " results database takes new runs only once a writer migrated it (open_or_create)");
  }
  SQLite::Transaction tx(*db_);
  SQLite::Statement q(*db_,
                      "INSERT INTO runs(run_index, seed, dispersion_json, outcome, metrics_json, run_hash, wall_s,"
                      " trace_json, cpu_s) VALUES(?, ?, ?, ?, ?, ?, ?, ?, ?)");
  for (const RunRecord& run : runs) {
    q.bind(1, static_cast<std::int64_t>(run.index));
    q.bind(2, std::to_string(run.seed));
    q.bind(3, run.dispersion_json);
    q.bind(4, run.outcome);
    q.bind(5, run.metrics_json);
    q.bind(6, run.run_hash);
    q.bind(7, run.wall_s);
    q.bind(8, run.trace_json);
    if (run.cpu_s) {
      q.bind(9, *run.cpu_s);
    } else {
      q.bind(9);  // NULL
    }
    q.exec();
    q.reset();
  }
  tx.commit();
}

std::vector<RunRecord> ResultsStore::runs() const {
  std::vector<RunRecord> out;
  // A version-2 database (a reader's) has no cpu_s column: none of its runs has a figure.
  SQLite::Statement q(*db_, std::string("SELECT run_index, seed, dispersion_json, outcome, metrics_json, run_hash,"
                                        " wall_s, trace_json, ") +
                                (format_version_ >= 3 ? "cpu_s" : "NULL") + " FROM runs ORDER BY run_index");
  while (q.executeStep()) {
    RunRecord r;
    r.index = q.getColumn(0).getInt64();
    r.seed = std::stoull(q.getColumn(1).getString());
    r.dispersion_json = q.getColumn(2).getString();
    r.outcome = q.getColumn(3).getString();
    r.metrics_json = q.getColumn(4).getString();
    r.run_hash = q.getColumn(5).getString();
    r.wall_s = q.getColumn(6).getDouble();
    r.trace_json = q.getColumn(7).getString();
    if (!q.getColumn(8).isNull()) r.cpu_s = q.getColumn(8).getDouble();
    out.push_back(std::move(r));
  }
  return out;
}

std::string encode_run_record(const RunRecord& r) {
  return nlohmann::json{{"index", r.index},
                        {"seed", r.seed},
                        {"dispersion_json", r.dispersion_json},
                        {"outcome", r.outcome},
                        {"metrics_json", r.metrics_json},
                        {"run_hash", r.run_hash},
                        {"wall_s", r.wall_s},
                        {"trace_json", r.trace_json},
                        {"cpu_s", number_or_null(r.cpu_s)}}
      .dump();
}

RunRecord decode_run_record(const std::string& message) {
  try {
    const auto j = nlohmann::json::parse(message);
    RunRecord r{j.at("index").get<std::int64_t>(),       j.at("seed").get<std::uint64_t>(),
                j.at("dispersion_json").get<std::string>(), j.at("outcome").get<std::string>(),
                j.at("metrics_json").get<std::string>(),    j.at("run_hash").get<std::string>(),
                j.at("wall_s").get<double>(),               j.at("trace_json").get<std::string>(),
                std::nullopt};
    // Required (every sender is this program's own build); null when nothing measured it.
    if (const auto& cpu = j.at("cpu_s"); !cpu.is_null()) {
      if (!cpu.is_number() || !(cpu.get<double>() >= 0.0)) {
        throw std::invalid_argument("malformed run record message: cpu_s is not a number >= 0");
      }
      r.cpu_s = cpu.get<double>();
    }
    return r;
  } catch (const nlohmann::json::exception& e) {
    throw std::invalid_argument(std::string("malformed run record message: ") + e.what());
  }
}

}  // namespace shelfcross::verification
