// Seeding, statistics, run hashes and the results store: the campaign's bookkeeping.
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <set>

#include <csignal>
#include <sys/wait.h>
#include <unistd.h>

#include <gtest/gtest.h>

#include "shelfcross/random.hpp"
#include "verification/results_store.hpp"
#include "verification/run_hash.hpp"
#include "verification/statistics.hpp"

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
          "{\"settling_z_s\":1.5}", std::string(32, 'a'), 0.25, "{\"t\":[0]}"};
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

// Two writers of one campaign folder (a campaign started twice, session 8: the second ran run
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

}  // namespace
}  // namespace shelfcross::verification
