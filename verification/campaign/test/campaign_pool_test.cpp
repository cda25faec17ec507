// The worker pool: every pending run exactly once, results independent of the worker count,
// resume skips finished runs, a throwing worker is recorded and the campaign goes on; shards
// are disjoint slices that merge into the whole campaign; a run lost in flight is handed out
// again and a run delivered twice is stored once.
#include <atomic>
#include <filesystem>
#include <thread>

#include <gtest/gtest.h>

#include "shelfcross/random.hpp"
#include "verification/campaign/campaign.hpp"
#include "verification/campaign/campaign_merge.hpp"
#include "verification/campaign/campaign_pool.hpp"
#include "verification/cosim/run_hash.hpp"
#include "verification/cosim/run_metrics_json.hpp"

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
    return {index, seed, "{}", sum > 0 ? "success" : "timeout", stored_metrics_json({std::nullopt, "", std::nullopt}),
            hash.hex(), 0.0};
  }
};

std::filesystem::path fresh_db(const std::string& name) {
  const auto dir = std::filesystem::temp_directory_path() / ("shelfcross_pool_" + name);
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir / "results.sqlite";
}

/// The runs without their informative wall and CPU times, which vary from one run to the next.
std::vector<RunRecord> without_timings(std::vector<RunRecord> runs) {
  for (auto& r : runs) {
    r.wall_s = 0.0;
    r.cpu_s.reset();
  }
  return runs;
}

TEST(CampaignPool, SameRecordsForOneAndThreeWorkers) {
  const CampaignMeta meta{"s", 11, 40};
  const auto factory = [](int) { return std::make_unique<DrawWorker>(); };
  ResultsStore one = ResultsStore::open_or_create(fresh_db("one"), meta);
  ResultsStore three = ResultsStore::open_or_create(fresh_db("three"), meta);
  EXPECT_EQ(run_pending(one, 11, 40, factory, {.jobs = 1}), 40);
  EXPECT_EQ(run_pending(three, 11, 40, factory, {.jobs = 3}), 40);
  const auto a = without_timings(one.runs());
  const auto b = without_timings(three.runs());
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
  EXPECT_EQ(without_timings(store.runs()), without_timings(whole.runs()));
}

TEST(CampaignPool, ParsesShards) {
  EXPECT_EQ(parse_shard("0/1"), (Shard{0, 1}));
  EXPECT_EQ(parse_shard("3/4"), (Shard{3, 4}));
  for (const char* bad : {"4/4", "-1/4", "1/0", "1", "a/4", "1/4x", "/4", "1/"}) {
    EXPECT_THROW(parse_shard(bad), std::invalid_argument) << bad;
  }
}

TEST(CampaignPool, ShardsMergeIntoTheWholeCampaign) {
  const CampaignMeta meta{"s", 9, 23};
  const auto factory = [](int) { return std::make_unique<DrawWorker>(); };
  ResultsStore whole = ResultsStore::open_or_create(fresh_db("shard_whole"), meta);
  run_pending(whole, 9, 23, factory, {.jobs = 2});
  std::vector<std::filesystem::path> shard_dbs;
  for (int k = 0; k < 3; ++k) {
    shard_dbs.push_back(fresh_db("shard" + std::to_string(k)));
    ResultsStore shard = ResultsStore::open_or_create(shard_dbs.back(), meta);
    EXPECT_EQ(run_pending(shard, 9, 23, factory, {.jobs = 2, .shard = {k, 3}}), k < 2 ? 8 : 7);
    for (std::int64_t index : shard.finished_indices()) EXPECT_EQ(index % 3, k);
    EXPECT_EQ(summarize_campaign(shard.runs(), 23, 0.02).campaign_hash, "");
  }
  const auto target = fresh_db("shard_merged");
  const MergeCounts counts = merge_campaigns(shard_dbs, target);
  EXPECT_EQ(counts.added, 23);
  EXPECT_EQ(counts.duplicates, 0);
  ResultsStore merged = ResultsStore::open_existing(target);
  EXPECT_EQ(merged.meta(), meta);
  EXPECT_EQ(without_timings(merged.runs()), without_timings(whole.runs()));
  const auto hash = summarize_campaign(whole.runs(), 23, 0.02).campaign_hash;
  EXPECT_EQ(hash.size(), 32u);
  EXPECT_EQ(summarize_campaign(merged.runs(), 23, 0.02).campaign_hash, hash);
  // Merging a shard again adds nothing.
  EXPECT_EQ(merge_campaigns({shard_dbs[1]}, target).duplicates, 8);

  // A run stored with another hash (another build) is refused, and the target is unchanged.
  const auto odd = fresh_db("shard_odd");
  {
    ResultsStore s = ResultsStore::open_or_create(odd, meta);
    RunRecord r = whole.runs()[4];
    r.run_hash = std::string(32, 'f');
    s.insert(r);
  }
  EXPECT_THROW(merge_campaigns({odd}, target), ResultsMismatch);
  // Another campaign (other seed) is refused.
  const auto other = fresh_db("shard_other");
  ResultsStore::open_or_create(other, CampaignMeta{"s", 10, 23});
  EXPECT_THROW(merge_campaigns({shard_dbs[0], other}, fresh_db("shard_mixed")), ResultsMismatch);
  EXPECT_EQ(merged.runs().size(), 23u);
}

TEST(CampaignPool, CollectorHandsLostRunsOutAgainAndStoresEachRunOnce) {
  const CampaignMeta meta{"s", 4, 5};
  ResultsStore store = ResultsStore::open_or_create(fresh_db("collector"), meta);
  store.insert(DrawWorker().run(1, run_seed(4, 1)));
  CampaignCollector collector(store, 5, {});
  EXPECT_EQ(collector.progress().done, 1);
  EXPECT_EQ(collector.progress().total, 5);
  EXPECT_EQ(collector.next_index(), 0);
  EXPECT_EQ(collector.next_index(), 2);
  collector.give_back(0);  // its worker died
  EXPECT_EQ(collector.next_index(), 0);
  EXPECT_EQ(collector.next_index(), 3);
  collector.give_back(2);
  // Run 2 arrives after all from the worker thought lost: stored, and not handed out again.
  EXPECT_TRUE(collector.commit(DrawWorker().run(2, run_seed(4, 2))));
  EXPECT_FALSE(collector.commit(DrawWorker().run(2, run_seed(4, 2))));
  EXPECT_EQ(collector.next_index(), 4);
  EXPECT_EQ(collector.next_index(), std::nullopt);
  EXPECT_TRUE(collector.exhausted());
  EXPECT_FALSE(collector.complete());
  for (std::int64_t i : {0, 3, 4}) EXPECT_TRUE(collector.commit(DrawWorker().run(i, run_seed(4, i))));
  EXPECT_TRUE(collector.complete());
  EXPECT_EQ(collector.committed(), 4);
  EXPECT_EQ(store.finished_indices(), (std::vector<std::int64_t>{0, 1, 2, 3, 4}));
}

}  // namespace
}  // namespace shelfcross::verification
