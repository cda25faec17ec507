#pragma once
// The campaign's scheduling, in two halves that a single process joins directly (run_pending)
// and an MPI campaign joins through messages (distributed/):
//
//   RunPool            `jobs` threads, each owning one RunWorker (its own renderer context,
//                      plant, flight software; in the program, a worker process of its own:
//                      run_process.hpp); run indices are submitted to it and finished
//                      records come back, in completion order.
//   CampaignCollector  the store's side: which indices are still missing (of the campaign or
//                      of one shard of it), handed out in index order on demand (so a slow run
//                      never idles the others), runs lost in flight taken back and handed out
//                      again, finished runs committed one transaction each, progress.
//
// Resume: indices already in the store are skipped. Every run depends only on (scenario,
// campaign seed, index), so which worker, process or host ran it, and in what order, cannot
// change its record (apart from the informative wall time).

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <exception>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <set>
#include <string>
#include <thread>
#include <vector>

#include "verification/campaign/results_store.hpp"

namespace shelfcross::verification {

/// Runs one simulation. Must not throw for anything a run can do (a crash, a divergence, an
/// exception of the flight software are outcomes); if it throws anyway, the pool records the
/// run with outcome "worker_error" and the message, and the campaign goes on.
class RunWorker {
 public:
  virtual ~RunWorker() = default;
  virtual RunRecord run(std::int64_t index, std::uint64_t seed) = 0;
};

/// Makes the worker of thread `worker_id` (0..jobs-1), on that thread.
using WorkerFactory = std::function<std::unique_ptr<RunWorker>(int worker_id)>;

/// Slice `index` of `count` of a campaign's run indices: the runs k with k % count == index.
/// Interleaved rather than contiguous, so every shard gets a fair share of slow and fast runs.
struct Shard {
  int index = 0;
  int count = 1;
  bool contains(std::int64_t run_index) const { return run_index % count == index; }
  bool operator==(const Shard&) const = default;
};

/// Parses "I/N" (0 <= I < N, both integers). Throws std::invalid_argument with a clear message.
Shard parse_shard(const std::string& text);

struct CampaignProgress {
  std::int64_t done = 0;        ///< runs in the store, this session's and earlier ones
  std::int64_t total = 0;       ///< runs requested (of this shard)
  std::int64_t successes = 0;   ///< of `done`
  std::int64_t done_this_session = 0;
  double elapsed_s = 0.0;       ///< wall time of this session
  double remaining_s = 0.0;     ///< estimate from this session's rate; 0 until a run finished
};

/// `jobs` threads that run submitted indices; see the file comment.
class RunPool {
 public:
  RunPool(int jobs, std::uint64_t campaign_seed, WorkerFactory make_worker);
  /// Lets the runs in flight finish (their records are dropped), drops queued ones, joins.
  ~RunPool();
  RunPool(const RunPool&) = delete;
  RunPool& operator=(const RunPool&) = delete;

  int jobs() const { return static_cast<int>(threads_.size()); }
  /// Queues a run; a free thread starts it.
  void submit(std::int64_t index);
  /// Runs submitted and not yet returned by wait_finished.
  std::int64_t in_flight() const;
  /// The next finished record, waiting at most `timeout` (forever when nullopt); nullopt when
  /// none came in time or none is in flight. Throws the first worker-construction error when
  /// no thread could make its worker while runs wait.
  std::optional<RunRecord> wait_finished(std::optional<std::chrono::milliseconds> timeout = std::nullopt);

 private:
  void thread_main(int worker_id);
  std::uint64_t campaign_seed_;
  WorkerFactory make_worker_;
  mutable std::mutex mutex_;
  std::condition_variable work_ready_, record_ready_;
  std::deque<std::int64_t> queued_;
  std::deque<RunRecord> finished_;
  std::int64_t in_flight_ = 0;
  int threads_alive_ = 0;
  bool shutting_down_ = false;
  std::exception_ptr setup_error_;
  std::vector<std::thread> threads_;
};

/// The store's side of a campaign; one thread (the collector) uses it.
class CampaignCollector {
 public:
  struct Options {
    /// Called after each committed run.
    std::function<void(const CampaignProgress&)> on_progress;
    /// When set and raised (e.g. by SIGINT), next_index() hands out nothing more.
    const std::atomic<bool>* stop = nullptr;
    Shard shard;
  };
  /// Pending: the indices of [0, runs) in `options.shard` missing from `store`.
  CampaignCollector(ResultsStore& store, std::int64_t runs, Options options);

  /// The lowest pending index not handed out, or nullopt (none left, or stop raised).
  std::optional<std::int64_t> next_index();
  /// A handed-out run that will not come back (its worker died): handed out again first.
  void give_back(std::int64_t index);
  /// Commits a finished run; one already stored (a run handed out twice) is skipped, and
  /// false is returned. Throws what the store throws.
  bool commit(const RunRecord& record);

  bool stopping() const { return options_.stop && options_.stop->load(); }
  /// Every pending run handed out (or stop raised): nothing more for next_index().
  bool exhausted() const { return stopping() || to_hand_out_.empty(); }
  /// Every run of the campaign (or shard) is in the store.
  bool complete() const { return progress_.done == progress_.total; }
  const CampaignProgress& progress() const { return progress_; }
  std::int64_t committed() const { return progress_.done_this_session; }

 private:
  ResultsStore& store_;
  Options options_;
  std::set<std::int64_t> stored_;
  std::deque<std::int64_t> to_hand_out_;
  CampaignProgress progress_;
  std::chrono::steady_clock::time_point t0_;  // informative: progress and ETA only
};

struct PoolOptions {
  int jobs = 1;
  /// Called on the calling thread after each committed run.
  std::function<void(const CampaignProgress&)> on_progress;
  /// When set and raised (e.g. by SIGINT), no new run starts; runs in flight finish and are
  /// committed, then run_pending returns.
  const std::atomic<bool>* stop = nullptr;
  Shard shard;
};

/// Runs every index in [0, runs) of `options.shard` missing from `store` on a RunPool in this
/// process, and returns how many it committed.
std::int64_t run_pending(ResultsStore& store, std::uint64_t campaign_seed, std::int64_t runs,
                         const WorkerFactory& make_worker, const PoolOptions& options);

/// The record of a run whose worker threw: outcome "worker_error", the message in its metrics.
RunRecord worker_error_record(std::int64_t index, std::uint64_t seed, const std::string& message);

}  // namespace shelfcross::verification
