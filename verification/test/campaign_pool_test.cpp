// The worker pool: every pending run exactly once, results independent of the worker count,
// resume skips finished runs, a throwing worker is recorded and the campaign goes on.
#include <atomic>
#include <filesystem>
#include <thread>

#include <gtest/gtest.h>

#include "shelfcross/random.hpp"
#include "verification/campaign_pool.hpp"
#include "verification/run_hash.hpp"

namespace shelfcross::verification {
namespace {

// A deterministic stand-in for a simulation: its record depends only on (index, seed), and
// some runs take longer, so the dynamic schedule differs between worker counts.
class DrawWorker : public RunWorker {
 public:
  RunRecord run(std::int64_t index, std::uint64_t seed) override {
    RandomStream draws(seed, StreamId::dispersion);
    RunHasher hash;
    double sum = 0.0;
    const int n = 1000 + static_cast<int>(draws.below(50000));
    for (int i = 0; i < n; ++i) sum += draws.normal();
    hash.add(sum);
    if (index == 5) throw std::runtime_error("flight software bug");
    return {index, seed, "{}", sum > 0 ? "success" : "timeout", "{}", hash.hex(), 0.0};
  }
};

std::filesystem::path fresh_db(const std::string& name) {
  const auto dir = std::filesystem::temp_directory_path() / ("shelfcross_pool_" + name);
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir / "results.sqlite";
}

std::vector<RunRecord> without_wall_time(std::vector<RunRecord> runs) {
  for (auto& r : runs) r.wall_s = 0.0;
  return runs;
}

TEST(CampaignPool, SameRecordsForOneAndThreeWorkers) {
  const CampaignMeta meta{"s", 11, 40};
  const auto factory = [](int) { return std::make_unique<DrawWorker>(); };
  ResultsStore one = ResultsStore::open_or_create(fresh_db("one"), meta);
  ResultsStore three = ResultsStore::open_or_create(fresh_db("three"), meta);
  EXPECT_EQ(run_pending(one, 11, 40, factory, {.jobs = 1}), 40);
  EXPECT_EQ(run_pending(three, 11, 40, factory, {.jobs = 3}), 40);
  const auto a = without_wall_time(one.runs());
  const auto b = without_wall_time(three.runs());
  ASSERT_EQ(a.size(), 40u);
  EXPECT_EQ(a, b);
  EXPECT_EQ(a[5].outcome, "worker_error");
  EXPECT_NE(a[5].metrics_json.find("flight software bug"), std::string::npos);
}

// Raises the stop flag while running one index, as a SIGINT arriving mid-run would.
class StoppingWorker : public DrawWorker {
 public:
  StoppingWorker(std::atomic<bool>& stop, std::int64_t at) : stop_(stop), at_(at) {}
  RunRecord run(std::int64_t index, std::uint64_t seed) override {
    if (index == at_) stop_ = true;
    return DrawWorker::run(index, seed);
  }

 private:
  std::atomic<bool>& stop_;
  std::int64_t at_;
};

TEST(CampaignPool, StopsOnRequestAndResumesWithoutRepeats) {
  const CampaignMeta meta{"s", 3, 30};
  const auto db = fresh_db("resume");
  std::atomic<bool> stop{false};
  {
    // One worker: the run in flight (index 6) finishes and is committed, then nothing starts.
    ResultsStore store = ResultsStore::open_or_create(db, meta);
    const auto stopping = [&](int) { return std::make_unique<StoppingWorker>(stop, 6); };
    EXPECT_EQ(run_pending(store, 3, 30, stopping, {.jobs = 1, .stop = &stop}), 7);
  }
  ResultsStore store = ResultsStore::open_or_create(db, meta);
  EXPECT_EQ(store.finished_indices(), (std::vector<std::int64_t>{0, 1, 2, 3, 4, 5, 6}));
  CampaignProgress last;
  const auto factory = [](int) { return std::make_unique<DrawWorker>(); };
  EXPECT_EQ(run_pending(store, 3, 30, factory, {.jobs = 2, .on_progress = [&](const CampaignProgress& p) { last = p; }}),
            23);
  EXPECT_EQ(last.done, 30);
  EXPECT_EQ(last.done_this_session, 23);
  EXPECT_EQ(store.finished_indices().size(), 30u);

  ResultsStore whole = ResultsStore::open_or_create(fresh_db("whole"), meta);
  run_pending(whole, 3, 30, factory, {.jobs = 1});
  EXPECT_EQ(without_wall_time(store.runs()), without_wall_time(whole.runs()));
}

}  // namespace
}  // namespace shelfcross::verification
