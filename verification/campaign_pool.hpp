#pragma once
// The campaign's worker pool: run indices handed out on demand to `jobs` threads (so a slow
// run never idles the others), each thread owning one RunWorker (its own renderer context,
// plant, flight software), finished runs committed by the calling thread one transaction each.
//
// Resume: indices already in the store are skipped. Every run depends only on (scenario,
// campaign seed, index), so which worker ran it, and in what order, cannot change its record
// (apart from the informative wall time).

#include <atomic>
#include <cstdint>
#include <functional>
#include <memory>

#include "verification/results_store.hpp"

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

struct CampaignProgress {
  std::int64_t done = 0;        ///< runs in the store, this session's and earlier ones
  std::int64_t total = 0;       ///< runs requested
  std::int64_t successes = 0;   ///< of `done`
  std::int64_t done_this_session = 0;
  double elapsed_s = 0.0;       ///< wall time of this session
  double remaining_s = 0.0;     ///< estimate from this session's rate; 0 until a run finished
};

struct PoolOptions {
  int jobs = 1;
  /// Called on the calling thread after each committed run.
  std::function<void(const CampaignProgress&)> on_progress;
  /// When set and raised (e.g. by SIGINT), no new run starts; runs in flight finish and are
  /// committed, then run_pending returns.
  const std::atomic<bool>* stop = nullptr;
};

/// Runs every index in [0, runs) missing from `store`, and returns how many it committed.
std::int64_t run_pending(ResultsStore& store, std::uint64_t campaign_seed, std::int64_t runs,
                         const WorkerFactory& make_worker, const PoolOptions& options);

}  // namespace shelfcross::verification
