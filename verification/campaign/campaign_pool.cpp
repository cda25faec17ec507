#include "verification/campaign/campaign_pool.hpp"

#include <algorithm>
#include <charconv>
#include <stdexcept>

#include "shelfcross/random.hpp"
#include "verification/cosim/run_metrics_json.hpp"

namespace shelfcross::verification {

Shard parse_shard(const std::string& text) {
  const auto slash = text.find('/');
  const auto number = [&](std::string_view part, int& out) {
    const auto [end, ec] = std::from_chars(part.data(), part.data() + part.size(), out);
    return ec == std::errc() && end == part.data() + part.size() && !part.empty();
  };
  Shard s;
  if (slash == std::string::npos || !number(std::string_view(text).substr(0, slash), s.index) ||
      !number(std::string_view(text).substr(slash + 1), s.count)) {
    throw std::invalid_argument("--shard '" + text + "': expected I/N, e.g. 0/4 for the first of 4 shards");
  }
  if (s.count < 1 || s.index < 0 || s.index >= s.count) {
    throw std::invalid_argument("--shard '" + text + "': need 0 <= I < N (shards are numbered from 0)");
  }
  return s;
}

RunRecord worker_error_record(std::int64_t index, std::uint64_t seed, const std::string& message) {
  return RunRecord{index, seed, "{}", "worker_error", stored_metrics_json({std::nullopt, message, std::nullopt}),
                   std::string(32, '0'), 0.0, "{}", std::nullopt};  // no CPU figure: the run did not finish
}

// ---------------------------------------------------------------------------------------------
// RunPool

RunPool::RunPool(int jobs, std::uint64_t campaign_seed, WorkerFactory make_worker)
    : campaign_seed_(campaign_seed), make_worker_(std::move(make_worker)) {
  jobs = std::max(1, jobs);
  threads_alive_ = jobs;
  for (int w = 0; w < jobs; ++w) threads_.emplace_back([this, w] { thread_main(w); });
}

RunPool::~RunPool() {
  {
    std::lock_guard lock(mutex_);
    shutting_down_ = true;
    queued_.clear();
  }
  work_ready_.notify_all();
  for (auto& t : threads_) t.join();
}

void RunPool::thread_main(int worker_id) {
  std::unique_ptr<RunWorker> worker;
  try {
    worker = make_worker_(worker_id);
  } catch (...) {
    std::lock_guard lock(mutex_);
    if (!setup_error_) setup_error_ = std::current_exception();
  }
  while (worker) {
    std::int64_t index = 0;
    {
      std::unique_lock lock(mutex_);
      work_ready_.wait(lock, [&] { return shutting_down_ || !queued_.empty(); });
      if (shutting_down_) break;
      index = queued_.front();
      queued_.pop_front();
    }
    const std::uint64_t seed = run_seed(campaign_seed_, static_cast<std::uint64_t>(index));
    RunRecord record;
    try {
      record = worker->run(index, seed);
    } catch (const std::exception& e) {
      record = worker_error_record(index, seed, e.what());
    }
    std::lock_guard lock(mutex_);
    finished_.push_back(std::move(record));
    record_ready_.notify_one();
  }
  std::lock_guard lock(mutex_);
  --threads_alive_;
  record_ready_.notify_one();
}

void RunPool::submit(std::int64_t index) {
  {
    std::lock_guard lock(mutex_);
    queued_.push_back(index);
    ++in_flight_;
  }
  work_ready_.notify_one();
}

std::int64_t RunPool::in_flight() const {
  std::lock_guard lock(mutex_);
  return in_flight_;
}

std::optional<RunRecord> RunPool::wait_finished(std::optional<std::chrono::milliseconds> timeout) {
  std::unique_lock lock(mutex_);
  const auto ready = [&] { return !finished_.empty() || in_flight_ == 0 || threads_alive_ == 0; };
  if (timeout) {
    record_ready_.wait_for(lock, *timeout, ready);
  } else {
    record_ready_.wait(lock, ready);
  }
  if (finished_.empty()) {
    if (threads_alive_ == 0 && in_flight_ > 0) {
      if (setup_error_) std::rethrow_exception(setup_error_);
      throw std::logic_error("RunPool: runs queued but no worker thread left");
    }
    return std::nullopt;
  }
  RunRecord record = std::move(finished_.front());
  finished_.pop_front();
  --in_flight_;
  return record;
}

// ---------------------------------------------------------------------------------------------
// CampaignCollector

CampaignCollector::CampaignCollector(ResultsStore& store, std::int64_t runs, Options options)
    : store_(store), options_(std::move(options)), t0_(std::chrono::steady_clock::now()) {
  for (const RunRecord& r : store_.runs()) {
    if (r.index >= runs || !options_.shard.contains(r.index)) continue;
    stored_.insert(r.index);
    ++progress_.done;
    progress_.successes += r.outcome == "success";
  }
  for (std::int64_t i = options_.shard.index; i < runs; i += options_.shard.count) {
    ++progress_.total;
    if (!stored_.count(i)) to_hand_out_.push_back(i);
  }
}

std::optional<std::int64_t> CampaignCollector::next_index() {
  if (exhausted()) return std::nullopt;
  const std::int64_t index = to_hand_out_.front();
  to_hand_out_.pop_front();
  return index;
}

void CampaignCollector::give_back(std::int64_t index) {
  if (!stored_.count(index)) to_hand_out_.push_front(index);
}

bool CampaignCollector::commit(const RunRecord& record) {
  if (stored_.count(record.index)) return false;
  store_.insert(record);
  stored_.insert(record.index);
  // A run given back and then finished by its first worker after all: not handed out again.
  std::erase(to_hand_out_, record.index);
  ++progress_.done;
  ++progress_.done_this_session;
  progress_.successes += record.outcome == "success";
  progress_.elapsed_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0_).count();
  const double per_run_s = progress_.elapsed_s / static_cast<double>(progress_.done_this_session);
  progress_.remaining_s = per_run_s * static_cast<double>(progress_.total - progress_.done);
  if (options_.on_progress) options_.on_progress(progress_);
  return true;
}

// ---------------------------------------------------------------------------------------------

std::int64_t run_pending(ResultsStore& store, std::uint64_t campaign_seed, std::int64_t runs,
                         const WorkerFactory& make_worker, const PoolOptions& options) {
  CampaignCollector collector(store, runs, {.on_progress = options.on_progress, .stop = options.stop, .shard = options.shard});
  const std::int64_t pending = collector.progress().total - collector.progress().done;
  if (pending == 0) return 0;
  RunPool pool(static_cast<int>(std::min<std::int64_t>(options.jobs, pending)), campaign_seed, make_worker);
  // One run per thread in flight: a new one starts only when one finishes, so a stop request
  // leaves nothing queued behind the runs in flight.
  for (int k = 0; k < pool.jobs(); ++k) {
    if (auto index = collector.next_index()) pool.submit(*index);
  }
  std::exception_ptr store_error;
  while (pool.in_flight() > 0) {
    std::optional<RunRecord> record;
    try {
      record = pool.wait_finished();
    } catch (...) {
      // No worker could be made: an error if this session committed nothing.
      if (collector.committed() == 0) throw;
      break;
    }
    if (!record) break;
    if (store_error) continue;  // drain so workers can finish; nothing more is committed
    try {
      collector.commit(*record);
    } catch (...) {
      store_error = std::current_exception();
      continue;
    }
    if (auto index = collector.next_index()) pool.submit(*index);
  }
  if (store_error) std::rethrow_exception(store_error);
  return collector.committed();
}

}  // namespace shelfcross::verification
