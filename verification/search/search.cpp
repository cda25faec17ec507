#include "verification/search/search.hpp"

#include <cmath>
#include <limits>
#include <map>

#include <SQLiteCpp/SQLiteCpp.h>

#include "verification/campaign/campaign.hpp"
#include "verification/campaign/results_store.hpp"
#include "verification/campaign/stored_run.hpp"

namespace shelfcross::verification {
namespace {

/// "2": a round's proposal mixes the joint nominal (RoundProposal, rare_event.hpp). "1" mixed
/// each parameter with its own nominal only: such a search still reads (its rounds with a joint
/// share of 0, its bound as it was), but is not resumed.
constexpr const char* kSearchFormatVersion = "2";

const char* kind_name(Distribution::Kind k) {
  switch (k) {
    case Distribution::Kind::uniform: return "uniform";
    case Distribution::Kind::normal: return "normal";
    case Distribution::Kind::truncated_normal: return "truncated_normal";
    case Distribution::Kind::choice: return "choice";
  }
  return "?";
}

}  // namespace

bool SearchSettings::operator==(const SearchSettings& o) const {
  return search_settings_json(*this) == search_settings_json(o);
}

nlohmann::json search_settings_json(const SearchSettings& s) {
  return {{"format_version", kSearchFormatVersion},
          {"seed", std::to_string(s.seed)},
          {"budget", s.budget},
          {"target", failure_class_name(s.target)},
          {"round_runs", s.ce.round_runs},
          {"elite_fraction", s.ce.elite_fraction},
          {"min_elites", s.ce.min_elites},
          {"smoothing", s.ce.smoothing},
          {"min_stddev_fraction", s.ce.min_stddev_fraction},
          {"nominal_share", s.ce.nominal_share},
          {"parameter_share", s.ce.parameter_share},
          {"estimation_runs", s.ce.estimation_runs},
          {"adapted", s.ce.adapted}};
}

nlohmann::json distribution_json(const Distribution& d) {
  nlohmann::json j{{"kind", kind_name(d.kind)}};
  switch (d.kind) {
    case Distribution::Kind::uniform:
      j["min"] = d.min;
      j["max"] = d.max;
      break;
    case Distribution::Kind::normal:
      j["mean"] = d.mean;
      j["stddev"] = d.stddev;
      break;
    case Distribution::Kind::truncated_normal:
      j["mean"] = d.mean;
      j["stddev"] = d.stddev;
      j["min"] = d.min;
      j["max"] = d.max;
      break;
    case Distribution::Kind::choice:
      j["values"] = d.values;
      j["weights"] = d.weights;
      break;
  }
  return j;
}

Distribution distribution_from_json(const nlohmann::json& j) {
  Distribution d;
  const std::string kind = j.at("kind").get<std::string>();
  for (auto k : {Distribution::Kind::uniform, Distribution::Kind::normal, Distribution::Kind::truncated_normal,
                 Distribution::Kind::choice}) {
    if (kind == kind_name(k)) d.kind = k;
  }
  d.min = j.value("min", 0.0);
  d.max = j.value("max", 0.0);
  d.mean = j.value("mean", 0.0);
  d.stddev = j.value("stddev", 0.0);
  d.values = j.value("values", std::vector<double>{});
  d.weights = j.value("weights", std::vector<double>{});
  return d;
}

// ---------------------------------------------------------------------------------------------
// SearchStore

struct SearchStore::Impl {
  SQLite::Database db;
  explicit Impl(const std::filesystem::path& p) : db(p.string(), SQLite::OPEN_READWRITE) {
    db.exec("PRAGMA busy_timeout=10000");
  }
};

SearchStore::SearchStore(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
SearchStore::SearchStore(SearchStore&&) noexcept = default;
SearchStore& SearchStore::operator=(SearchStore&&) noexcept = default;
SearchStore::~SearchStore() = default;

SearchStore SearchStore::open_or_create(const std::filesystem::path& db_path, const SearchSettings& settings) {
  if (!std::filesystem::exists(db_path)) throw ResultsMismatch(db_path.string() + ": no such results database");
  SearchStore store(std::make_unique<Impl>(db_path));
  SQLite::Database& db = store.impl_->db;
  const nlohmann::json wanted = search_settings_json(settings);
  if (!db.tableExists("search")) {
    SQLite::Transaction tx(db);
    db.exec("CREATE TABLE search(key TEXT PRIMARY KEY, value TEXT NOT NULL)");
    db.exec(
        "CREATE TABLE search_rounds(round INTEGER PRIMARY KEY, first_run INTEGER NOT NULL, runs INTEGER NOT NULL,"
        " estimation INTEGER NOT NULL, level REAL, elites INTEGER NOT NULL, proposal_json TEXT NOT NULL)");
    SQLite::Statement q(db, "INSERT INTO search(key, value) VALUES('settings', ?)");
    q.bind(1, wanted.dump());
    q.exec();
    tx.commit();
  }
  SQLite::Statement q(db, "SELECT value FROM search WHERE key = 'settings'");
  if (!q.executeStep()) throw ResultsMismatch(db_path.string() + ": search settings missing");
  store.settings_ = nlohmann::json::parse(q.getColumn(0).getString());
  if (const auto version = store.settings_.value("format_version", std::string("?")); version != kSearchFormatVersion) {
    throw ResultsMismatch(db_path.string() + " holds a search of format " + version + " (this version writes " +
                          kSearchFormatVersion + ": each round also draws whole runs from the nominal); it cannot be "
                          "resumed: use another --out");
  }
  if (store.settings_ != wanted) {
    throw ResultsMismatch(db_path.string() + " holds a search with other settings (" + store.settings_.dump() +
                          "); use another --out");
  }
  return store;
}

SearchStore SearchStore::open_existing(const std::filesystem::path& db_path) {
  if (!is_search_database(db_path)) throw ResultsMismatch(db_path.string() + " holds no search");
  SearchStore store(std::make_unique<Impl>(db_path));
  SQLite::Statement q(store.impl_->db, "SELECT value FROM search WHERE key = 'settings'");
  if (!q.executeStep()) throw ResultsMismatch(db_path.string() + ": search settings missing");
  store.settings_ = nlohmann::json::parse(q.getColumn(0).getString());
  return store;
}

bool is_search_database(const std::filesystem::path& db_path) {
  if (!std::filesystem::exists(db_path)) return false;
  const SQLite::Database db(db_path.string(), SQLite::OPEN_READONLY);
  return db.tableExists("search_rounds");
}

std::vector<CeRound> SearchStore::rounds() const {
  std::vector<CeRound> out;
  SQLite::Statement q(impl_->db,
                      "SELECT round, first_run, runs, estimation, level, elites, proposal_json FROM search_rounds"
                      " ORDER BY round");
  while (q.executeStep()) {
    CeRound r;
    r.index = q.getColumn(0).getInt();
    r.first_run = q.getColumn(1).getInt64();
    r.runs = q.getColumn(2).getInt64();
    r.estimation = q.getColumn(3).getInt() != 0;
    r.level = q.getColumn(4).isNull() ? std::numeric_limits<double>::quiet_NaN() : q.getColumn(4).getDouble();
    r.elites = q.getColumn(5).getInt64();
    r.proposal = proposals_from_json(nlohmann::json::parse(q.getColumn(6).getString()));
    out.push_back(std::move(r));
  }
  return out;
}

nlohmann::json proposals_json(const RoundProposal& q) {
  nlohmann::json parameters = nlohmann::json::object();
  for (const auto& [name, d] : q.parameters) {
    parameters[name] = {{"shifted", distribution_json(d.shifted)}, {"nominal", distribution_json(d.nominal)},
                        {"nominal_share", d.nominal_share}};
  }
  return {{"nominal_share", q.nominal_share}, {"parameters", parameters}};
}

RoundProposal proposals_from_json(const nlohmann::json& j) {
  // Format 1 stored the parameters' proposals alone, one object per parameter name.
  const bool joint = j.contains("parameters") && j.at("parameters").is_object() && j.contains("nominal_share") &&
                     j.at("nominal_share").is_number();
  RoundProposal q;
  q.nominal_share = joint ? j.at("nominal_share").get<double>() : 0.0;
  for (const auto& [name, d] : (joint ? j.at("parameters") : j).items()) {
    q.parameters[name] = {distribution_from_json(d.at("shifted")), distribution_from_json(d.at("nominal")),
                          d.at("nominal_share").get<double>()};
  }
  return q;
}

void SearchStore::insert_round(const CeRound& r) {
  SQLite::Statement q(impl_->db,
                      "INSERT INTO search_rounds(round, first_run, runs, estimation, level, elites, proposal_json)"
                      " VALUES(?, ?, ?, ?, ?, ?, ?)");
  q.bind(1, r.index);
  q.bind(2, static_cast<std::int64_t>(r.first_run));
  q.bind(3, static_cast<std::int64_t>(r.runs));
  q.bind(4, r.estimation ? 1 : 0);
  if (std::isfinite(r.level)) {
    q.bind(5, r.level);
  } else {
    q.bind(5);  // NULL
  }
  q.bind(6, static_cast<std::int64_t>(r.elites));
  q.bind(7, proposals_json(r.proposal).dump());
  q.exec();
}

// ---------------------------------------------------------------------------------------------

DrawFunction round_draws(RoundProposal proposal) {
  auto q = std::make_shared<const RoundProposal>(std::move(proposal));
  return [q](std::uint64_t seed) { return q->sample(seed); };
}

RunMargins record_margins(const Scenario& nominal, const RunRecord& record) {
  if (record.outcome == "worker_error") {
    const double nan = std::numeric_limits<double>::quiet_NaN();
    return {nan, nan, nan};
  }
  return run_margins(nominal, record.outcome, stored_metrics(record).run);
}

SearchRunResult run_search(std::shared_ptr<const Scenario> nominal, const SearchSettings& settings,
                           const std::filesystem::path& out, const SearchRunOptions& options) {
  std::filesystem::create_directories(out);
  const std::filesystem::path db_path = out / "results.sqlite";
  ResultsStore store =
      ResultsStore::open_or_create(db_path, CampaignMeta{write_scenario(*nominal), settings.seed, settings.budget});
  SearchStore search = SearchStore::open_or_create(db_path, settings);
  const ParameterDistributions nominal_d(nominal->dispersions.begin(), nominal->dispersions.end());
  std::vector<CeRound> rounds = search.rounds();
  SearchRunResult result;
  for (;;) {
    // The stored runs, by index, as CE samples.
    std::map<std::int64_t, RunRecord> stored;
    for (RunRecord& r : store.runs()) stored.emplace(r.index, std::move(r));
    std::optional<CeRound> round;
    if (!rounds.empty()) {
      const CeRound& last = rounds.back();
      for (std::int64_t k = last.first_run; k < last.first_run + last.runs; ++k) {
        if (!stored.count(k)) {
          round = last;  // resume the last round
          break;
        }
      }
    }
    if (!round) {
      std::vector<CeSample> samples;
      for (std::int64_t k = 0; k < (rounds.empty() ? 0 : rounds.back().first_run + rounds.back().runs); ++k) {
        const RunRecord& r = stored.at(k);
        samples.push_back({nlohmann::json::parse(r.dispersion_json).get<DrawnValues>(),
                           record_margins(*nominal, r).of(settings.target)});
      }
      round = next_ce_round(nominal_d, settings.ce, settings.budget, rounds, samples);
      if (!round) {
        result.complete = true;
        return result;
      }
      search.insert_round(*round);
      rounds.push_back(*round);
    }
    if (options.on_round) options.on_round(*round);
    const std::int64_t round_end = round->first_run + round->runs;
    if (options.run_round) {
      result.committed += options.run_round(store, round_end, *round);
    } else {
      const DrawFunction draw = round_draws(round->proposal);
      const WorkerFactory factory =
          options.make_workers ? options.make_workers(nominal, draw)
                               : [nominal, draw](int) { return std::make_unique<CampaignWorker>(nominal, draw); };
      result.committed += run_pending(store, settings.seed, round_end, factory,
                                      {.jobs = options.jobs, .on_progress = options.on_progress, .stop = options.stop, .shard = {}});
    }
    if (options.stop && options.stop->load()) return result;
  }
}

}  // namespace shelfcross::verification
