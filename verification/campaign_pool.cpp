#include "verification/campaign_pool.hpp"

#include <algorithm>
#include <chrono>
#include <condition_variable>
#include <deque>
#include <exception>
#include <mutex>
#include <set>
#include <thread>
#include <vector>

#include <nlohmann/json.hpp>

#include "shelfcross/random.hpp"

namespace shelfcross::verification {

std::int64_t run_pending(ResultsStore& store, std::uint64_t campaign_seed, std::int64_t runs,
                         const WorkerFactory& make_worker, const PoolOptions& options) {
  const std::vector<std::int64_t> finished = store.finished_indices();
  const std::set<std::int64_t> finished_set(finished.begin(), finished.end());
  std::vector<std::int64_t> pending;
  for (std::int64_t i = 0; i < runs; ++i) {
    if (!finished_set.count(i)) pending.push_back(i);
  }
  CampaignProgress progress;
  progress.total = runs;
  for (const RunRecord& r : store.runs()) {
    if (r.index < runs) {
      ++progress.done;
      progress.successes += r.outcome == "success";
    }
  }
  if (pending.empty()) return 0;

  // Shared between the workers and the collector (this thread).
  std::atomic<size_t> next{0};
  std::mutex mutex;
  std::condition_variable ready;
  std::deque<RunRecord> finished_runs;
  int workers_alive = 0;
  std::exception_ptr worker_setup_error;

  const int jobs = std::max(1, std::min<int>(options.jobs, static_cast<int>(pending.size())));
  std::vector<std::thread> threads;
  workers_alive = jobs;
  for (int w = 0; w < jobs; ++w) {
    threads.emplace_back([&, w] {
      std::unique_ptr<RunWorker> worker;
      try {
        worker = make_worker(w);
      } catch (...) {
        std::lock_guard lock(mutex);
        if (!worker_setup_error) worker_setup_error = std::current_exception();
      }
      while (worker) {
        if (options.stop && options.stop->load()) break;
        const size_t k = next.fetch_add(1);
        if (k >= pending.size()) break;
        const std::int64_t index = pending[k];
        const std::uint64_t seed = run_seed(campaign_seed, static_cast<std::uint64_t>(index));
        RunRecord record;
        try {
          record = worker->run(index, seed);
        } catch (const std::exception& e) {
          record = RunRecord{index, seed, "{}", "worker_error",
                             nlohmann::json{{"error", e.what()}}.dump(), std::string(32, '0'), 0.0, "{}"};
        }
        std::lock_guard lock(mutex);
        finished_runs.push_back(std::move(record));
        ready.notify_one();
      }
      std::lock_guard lock(mutex);
      --workers_alive;
      ready.notify_one();
    });
  }

  const auto t0 = std::chrono::steady_clock::now();  // informative: progress and ETA only
  std::int64_t committed = 0;
  std::exception_ptr store_error;
  for (;;) {
    std::unique_lock lock(mutex);
    ready.wait(lock, [&] { return !finished_runs.empty() || workers_alive == 0; });
    if (finished_runs.empty()) break;
    RunRecord record = std::move(finished_runs.front());
    finished_runs.pop_front();
    lock.unlock();
    if (store_error) continue;  // drain so workers can finish; nothing more is committed
    try {
      store.insert(record);
    } catch (...) {
      store_error = std::current_exception();
      continue;
    }
    ++committed;
    ++progress.done;
    ++progress.done_this_session;
    progress.successes += record.outcome == "success";
    progress.elapsed_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    const double rate = progress.elapsed_s / static_cast<double>(progress.done_this_session);
    progress.remaining_s = rate * static_cast<double>(progress.total - progress.done);
    if (options.on_progress) options.on_progress(progress);
  }
  for (auto& t : threads) t.join();
  if (store_error) std::rethrow_exception(store_error);
  if (worker_setup_error && committed == 0) std::rethrow_exception(worker_setup_error);
  return committed;
}

}  // namespace shelfcross::verification
