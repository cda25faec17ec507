// Seeding, statistics, run hashes and the results store: the campaign's bookkeeping.
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <set>

#include <csignal>
#include <sys/wait.h>
#include <unistd.h>

#include <gtest/gtest.h>
#include <SQLiteCpp/SQLiteCpp.h>

#include "shelfcross/random.hpp"
#include "verification/campaign/campaign_merge.hpp"
#include "verification/campaign/results_store.hpp"
#include "verification/cosim/run_hash.hpp"
#include "verification/statistics/statistics.hpp"

namespace shelfcross::verification {
namespace {

TEST(Seeding, RunSeedsAreFixedDistinctAndReplayable) {
  // The hash is part of the replay contract: these values must never change.
  EXPECT_EQ(run_seed(42, 0), run_seed(42, 0));
  std::set<std::uint64_t> seeds;
  for (std::uint64_t i = 0; i < 10000; ++i) seeds.insert(run_seed(42, i));
  EXPECT_EQ(seeds.size(), 10000u);
  EXPECT_NE(run_seed(42, 1), run_seed(43, 1));
}

TEST(Seeding, StreamsAreIndependentAndReproducible) {
  RandomStream a(7, StreamId::wind), b(7, StreamId::wind), c(7, StreamId::frame_drop);
  for (int i = 0; i < 100; ++i) {
    const std::uint64_t x = a.next_u64();
    EXPECT_EQ(x, b.next_u64());
    EXPECT_NE(x, c.next_u64());
  }
}

TEST(Seeding, DrawsHaveTheRightMoments) {
  RandomStream r(123, StreamId::dispersion);
  const int n = 200000;
  double sum = 0, sum2 = 0, usum = 0;
  int below = 0;
  for (int i = 0; i < n; ++i) {
    const double z = r.normal(1.0, 2.0);
    sum += z;
    sum2 += (z - 1.0) * (z - 1.0);
    const double u = r.uniform01();
    ASSERT_GE(u, 0.0);
    ASSERT_LT(u, 1.0);
    usum += u;
    below += r.below(10) < 3;
  }
  EXPECT_NEAR(sum / n, 1.0, 0.02);
  EXPECT_NEAR(std::sqrt(sum2 / n), 2.0, 0.02);
  EXPECT_NEAR(usum / n, 0.5, 0.005);
  EXPECT_NEAR(static_cast<double>(below) / n, 0.3, 0.005);
}

TEST(Statistics, ClopperPearsonMatchesClosedFormsAndTables) {
  // All successes: p_L = alpha^(1/n) (the "rule of three" family).
  EXPECT_NEAR(clopper_pearson_lower(299, 299), std::pow(0.05, 1.0 / 299.0), 1e-12);
  EXPECT_GT(clopper_pearson_lower(299, 299), 0.99);
  EXPECT_GT(clopper_pearson_lower(2995, 2995), 0.999);
  EXPECT_EQ(clopper_pearson_lower(0, 10), 0.0);
  // One failure: 1 - p_L solves a closed form only numerically; check the defining equation
  // P(X >= k | p_L) = alpha, with X ~ Bin(n, p_L).
  const int n = 50, k = 45;
  const double p = clopper_pearson_lower(k, n);
  double tail = 0.0;
  for (int x = k; x <= n; ++x) {
    tail += std::exp(std::lgamma(n + 1.0) - std::lgamma(x + 1.0) - std::lgamma(n - x + 1.0) +
                     x * std::log(p) + (n - x) * std::log1p(-p));
  }
  EXPECT_NEAR(tail, 0.05, 1e-9);
  EXPECT_THROW(clopper_pearson_lower(3, 2), std::invalid_argument);
}

TEST(Statistics, SummaryUsesLinearInterpolatedPercentiles) {
  const Summary s = summarize({5, 1, 4, 2, 3});
  EXPECT_EQ(s.count, 5);
  EXPECT_DOUBLE_EQ(s.mean, 3.0);
  EXPECT_DOUBLE_EQ(s.p50, 3.0);
  EXPECT_DOUBLE_EQ(s.p95, 4.8);
  EXPECT_DOUBLE_EQ(s.p99, 4.96);
  EXPECT_DOUBLE_EQ(s.min, 1.0);
  EXPECT_DOUBLE_EQ(s.max, 5.0);
  EXPECT_EQ(summarize({}).count, 0);
}

TEST(RunHash, DependsOnEveryBitAndOnFraming) {
  RunHasher a, b, c;
  a.add(1.0);
  a.add(std::string_view("ab"));
  a.add(std::string_view("c"));
  b.add(1.0);
  b.add(std::string_view("a"));
  b.add(std::string_view("bc"));
  c.add(std::nextafter(1.0, 2.0));
  c.add(std::string_view("ab"));
  c.add(std::string_view("c"));
  EXPECT_EQ(a.hex().size(), 32u);
  EXPECT_NE(a.hex(), b.hex());
  EXPECT_NE(a.hex(), c.hex());
  RunHasher a2;
  a2.add(1.0);
  a2.add(std::string_view("ab"));
  a2.add(std::string_view("c"));
  EXPECT_EQ(a.hex(), a2.hex());
}

class ResultsStoreTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = std::filesystem::temp_directory_path() /
           ("shelfcross_results_" + std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()));
    std::filesystem::remove_all(dir_);
    std::filesystem::create_directories(dir_);
  }
  void TearDown() override { std::filesystem::remove_all(dir_); }
  std::filesystem::path dir_;
};

RunRecord make_run(std::int64_t i) {
  return {i, run_seed(9, static_cast<std::uint64_t>(i)), "{\"start_distance_m\":3.1}", "success",
          "{\"settling_z_s\":1.5}", std::string(32, 'a'), 0.25, "{\"t\":[0]}", 1.5};
}

/// make_run(i) without a CPU figure: a lost run, or one stored before format 3.
RunRecord make_run_without_cpu(std::int64_t i) {
  RunRecord r = make_run(i);
  r.cpu_s.reset();
  return r;
}

TEST_F(ResultsStoreTest, StoresKnownOutcomesOnlyAndKeepsNothingOfARefusedBatch) {
  ResultsStore store = ResultsStore::open_or_create(dir_ / "results.sqlite", {"scenario: {}\n", 9, 10});
  const std::vector<std::string>& known = known_run_outcomes();
  for (const char* name : {"success", "collision", "timeout", "inventory_mismatch", "crashed", "hung", "worker_error"}) {
    EXPECT_NE(std::find(known.begin(), known.end(), name), known.end()) << name;
  }
  RunRecord hung = make_run(0);
  hung.outcome = "hung";
  store.insert(hung);
  RunRecord misspelt = make_run(2);
  misspelt.outcome = "sucess";
  EXPECT_THROW(store.insert(misspelt), std::invalid_argument);
  EXPECT_THROW(store.insert(std::vector<RunRecord>{make_run(1), misspelt}), std::invalid_argument);
  ASSERT_EQ(store.runs().size(), 1u);
  EXPECT_EQ(store.runs()[0].outcome, "hung");
}

TEST_F(ResultsStoreTest, KeepsRunsAcrossReopenAndRefusesOtherCampaigns) {
  const CampaignMeta meta{"scenario: {}\n", 9, 10};
  {
    ResultsStore store = ResultsStore::open_or_create(dir_ / "results.sqlite", meta);
    store.insert(make_run(3));
    store.insert(make_run(1));
    EXPECT_THROW(store.insert(make_run(1)), std::exception);  // a run is present once
  }
  {
    ResultsStore again = ResultsStore::open_or_create(dir_ / "results.sqlite", CampaignMeta{meta.scenario_yaml, 9, 20});
    EXPECT_EQ(again.finished_indices(), (std::vector<std::int64_t>{1, 3}));
    EXPECT_EQ(again.meta().runs_requested, 20);
    const std::vector<RunRecord> runs = again.runs();
    ASSERT_EQ(runs.size(), 2u);
    EXPECT_EQ(runs[0], make_run(1));
  }
  // Refused for what they are (not for the lock: no writer is open now).
  auto expect_mismatch_not_busy = [&](const CampaignMeta& other) {
    try {
      ResultsStore::open_or_create(dir_ / "results.sqlite", other);
      ADD_FAILURE() << "accepted another campaign";
    } catch (const ResultsBusy& e) {
      ADD_FAILURE() << e.what();
    } catch (const ResultsMismatch&) {
    }
  };
  expect_mismatch_not_busy(CampaignMeta{"other", 9, 10});
  expect_mismatch_not_busy(CampaignMeta{meta.scenario_yaml, 8, 10});
  EXPECT_THROW(ResultsStore::open_existing(dir_ / "missing.sqlite"), ResultsMismatch);
}

// Two writers of one campaign folder (a campaign started twice: the second ran run
// 851 again and died on "UNIQUE constraint failed" after the first had stored it): the second
// is refused at once, naming the first's pid, and nothing it could store is lost; readers
// (report, replay) still open it. The lock dies with its process, even by SIGKILL.
TEST_F(ResultsStoreTest, ASecondWriterIsRefusedAndAKilledWriterLeavesNoLock) {
  const CampaignMeta meta{"scenario: {}\n", 9, 10};
  const std::filesystem::path db = dir_ / "results.sqlite";
  {
    ResultsStore first = ResultsStore::open_or_create(db, meta);
    first.insert(make_run(0));
    try {
      ResultsStore::open_or_create(db, meta);
      ADD_FAILURE() << "a second writer was accepted";
    } catch (const ResultsBusy& e) {
      EXPECT_NE(std::string(e.what()).find("pid " + std::to_string(::getpid())), std::string::npos) << e.what();
    }
    EXPECT_EQ(ResultsStore::open_existing(db).finished_indices(), (std::vector<std::int64_t>{0}));
    first.insert(make_run(1));
  }
  const pid_t child = ::fork();
  ASSERT_GE(child, 0);
  if (child == 0) {  // holds the lock, then dies without closing anything
    ResultsStore held = ResultsStore::open_or_create(db, meta);
    ::raise(SIGKILL);
    ::_exit(3);
  }
  int status = 0;
  ASSERT_EQ(::waitpid(child, &status, 0), child);
  ASSERT_TRUE(WIFSIGNALED(status));
  ResultsStore after = ResultsStore::open_or_create(db, meta);
  EXPECT_EQ(after.finished_indices(), (std::vector<std::int64_t>{0, 1}));
}

TEST_F(ResultsStoreTest, StoresACpuFigureOrNone) {
  const std::filesystem::path db = dir_ / "results.sqlite";
  RunRecord lost = make_run_without_cpu(1);
  lost.outcome = "crashed";
  ResultsStore::open_or_create(db, {"scenario: {}\n", 9, 10}).insert({make_run(0), lost});
  const std::vector<RunRecord> runs = ResultsStore::open_existing(db).runs();
  ASSERT_EQ(runs.size(), 2u);
  EXPECT_EQ(runs[0], make_run(0));
  EXPECT_EQ(runs[1], lost);
  EXPECT_EQ(runs[1].cpu_s, std::nullopt);  // NULL, not 0
}

/// A database as format 2 stored it (before runs.cpu_s), holding make_run(i) of `indices`.
void make_version_2_database(const std::filesystem::path& db, const CampaignMeta& meta,
                             const std::vector<std::int64_t>& indices) {
  SQLite::Database d(db.string(), SQLite::OPEN_READWRITE | SQLite::OPEN_CREATE);
  d.exec("CREATE TABLE campaign(key TEXT PRIMARY KEY, value TEXT NOT NULL)");
  d.exec(
      "CREATE TABLE runs(run_index INTEGER PRIMARY KEY, seed TEXT NOT NULL, dispersion_json TEXT NOT NULL,"
      " outcome TEXT NOT NULL, metrics_json TEXT NOT NULL, run_hash TEXT NOT NULL, wall_s REAL NOT NULL,"
      " trace_json TEXT NOT NULL)");
  SQLite::Statement key(d, "INSERT INTO campaign(key, value) VALUES(?, ?)");
  for (const auto& [name, value] : std::vector<std::pair<std::string, std::string>>{
           {"format_version", "2"},
           {"scenario_yaml", meta.scenario_yaml},
           {"campaign_seed", std::to_string(meta.campaign_seed)},
           {"runs_requested", std::to_string(meta.runs_requested)}}) {
    key.bind(1, name);
    key.bind(2, value);
    key.exec();
    key.reset();
  }
  SQLite::Statement run(d, "INSERT INTO runs VALUES(?, ?, ?, ?, ?, ?, ?, ?)");
  for (const std::int64_t i : indices) {
    const RunRecord r = make_run(i);
    run.bind(1, r.index);
    run.bind(2, std::to_string(r.seed));
    run.bind(3, r.dispersion_json);
    run.bind(4, r.outcome);
    run.bind(5, r.metrics_json);
    run.bind(6, r.run_hash);
    run.bind(7, r.wall_s);
    run.bind(8, r.trace_json);
    run.exec();
    run.reset();
  }
}

std::string format_version_of(const std::filesystem::path& db) {
  SQLite::Database d(db.string(), SQLite::OPEN_READONLY);
  return d.execAndGet("SELECT value FROM campaign WHERE key = 'format_version'").getString();
}

// Campaigns stored before runs.cpu_s (format 2) are read as they are, without CPU figures;
// merged with a version-3 shard they give a version-3 database; the first writer that opens
// one (a campaign resumed) migrates it, and its new runs have their figures.
TEST_F(ResultsStoreTest, AVersion2DatabaseIsReadAsItIsAndMigratedByItsWriter) {
  const CampaignMeta meta{"scenario: {}\n", 9, 10};
  const std::filesystem::path old_db = dir_ / "old.sqlite", new_db = dir_ / "new.sqlite", merged = dir_ / "merged.sqlite";
  make_version_2_database(old_db, meta, {0, 2});
  {
    ResultsStore reader = ResultsStore::open_existing(old_db);
    EXPECT_EQ(reader.runs(), (std::vector<RunRecord>{make_run_without_cpu(0), make_run_without_cpu(2)}));
    EXPECT_THROW(reader.insert(make_run(4)), ResultsMismatch);
  }
  EXPECT_EQ(format_version_of(old_db), "2");

  ResultsStore::open_or_create(new_db, meta).insert(make_run(1));
  EXPECT_EQ(merge_campaigns({old_db, new_db}, merged).added, 3);
  EXPECT_EQ(format_version_of(merged), "3");
  EXPECT_EQ(ResultsStore::open_existing(merged).runs(),
            (std::vector<RunRecord>{make_run_without_cpu(0), make_run(1), make_run_without_cpu(2)}));
  EXPECT_EQ(format_version_of(old_db), "2");  // a merge's source is only read

  {
    ResultsStore writer = ResultsStore::open_or_create(old_db, meta);
    EXPECT_EQ(format_version_of(old_db), "3");
    writer.insert(make_run(4));
  }
  EXPECT_EQ(ResultsStore::open_existing(old_db).runs(),
            (std::vector<RunRecord>{make_run_without_cpu(0), make_run_without_cpu(2), make_run(4)}));
}

}  // namespace
}  // namespace shelfcross::verification
