#include "distributed/mpi_campaign.hpp"

// The C API only: Open MPI's mpi.h otherwise pulls in the deprecated C++ bindings, which need
// libmpi_cxx.
#define OMPI_SKIP_MPICXX 1
#define MPICH_SKIP_MPICXX 1
#include <mpi.h>

#include <cstdlib>
#include <cstring>
#include <map>
#include <optional>
#include <set>
#include <stdexcept>
#include <thread>
#include <vector>

#include <nlohmann/json.hpp>

namespace shelfcross::distributed {
namespace {

using verification::RunRecord;
using Clock = std::chrono::steady_clock;  // timeouts, heartbeats and polling only; never results

constexpr int kCoordinator = 0;
enum Tag : int { kHello = 1, kAssign, kResult, kHeartbeat, kFailed, kFinish };
constexpr auto kPollInterval = std::chrono::milliseconds(1);
constexpr auto kHeartbeatInterval = std::chrono::seconds(1);

void check(int code, const char* what) {
  if (code != MPI_SUCCESS) {
    char text[MPI_MAX_ERROR_STRING];
    int length = 0;
    MPI_Error_string(code, text, &length);
    throw std::runtime_error(std::string(what) + ": " + std::string(text, static_cast<size_t>(length)));
  }
}

/// The other side of a message is gone (or has not answered for the rank timeout).
struct Unreachable : std::runtime_error {
  using std::runtime_error::runtime_error;
};

/// Sends `bytes`, polling for completion: a large message waits for the receiver to take it,
/// and a receiver that died (under --enable-recovery) never does; after `timeout` this throws
/// instead of spinning for ever.
void send_bytes(std::string bytes, int dest, Tag tag, std::chrono::milliseconds timeout) {
  auto buffer = std::make_unique<std::string>(std::move(bytes));
  MPI_Request request;
  check(MPI_Isend(buffer->data(), static_cast<int>(buffer->size()), MPI_CHAR, dest, tag, MPI_COMM_WORLD, &request),
        "MPI_Isend");
  const auto start = std::chrono::steady_clock::now();
  for (;;) {
    int done = 0;
    check(MPI_Test(&request, &done, MPI_STATUS_IGNORE), "MPI_Test");
    if (done) return;
    if (std::chrono::steady_clock::now() - start > timeout) {
      (void)buffer.release();  // MPI may still read it: left to the process's end
      throw Unreachable("rank " + std::to_string(dest) + " took no message for " +
                               std::to_string(timeout.count() / 1000) + " s");
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
}

void send_int64(std::int64_t value, int dest, Tag tag) {
  check(MPI_Send(&value, 1, MPI_INT64_T, dest, tag, MPI_COMM_WORLD), "MPI_Send");
}

/// A 0 or 1 without waiting for it to arrive and without failing: for a rank that may be
/// dead. The buffer is static: the send may still be pending when the caller returns.
void post_flag(bool flag, int dest, Tag tag) {
  static const std::int64_t kValues[2] = {0, 1};
  MPI_Request request;
  if (MPI_Isend(&kValues[flag], 1, MPI_INT64_T, dest, tag, MPI_COMM_WORLD, &request) == MPI_SUCCESS) {
    MPI_Request_free(&request);
  }
}

struct Message {
  int source = 0;
  Tag tag = kHello;
  std::string bytes;
  std::int64_t int64() const {
    if (bytes.size() != sizeof(std::int64_t)) throw std::runtime_error("MPI message of the wrong size");
    std::int64_t v = 0;
    std::memcpy(&v, bytes.data(), sizeof v);
    return v;
  }
};

/// The next message from `source` (MPI_ANY_SOURCE for any), if one has arrived.
std::optional<Message> poll(int source) {
  int arrived = 0;
  MPI_Status status;
  check(MPI_Iprobe(source, MPI_ANY_TAG, MPI_COMM_WORLD, &arrived, &status), "MPI_Iprobe");
  if (!arrived) return std::nullopt;
  int count = 0;
  MPI_Get_count(&status, MPI_CHAR, &count);
  Message m{status.MPI_SOURCE, static_cast<Tag>(status.MPI_TAG), std::string(static_cast<size_t>(count), '\0')};
  check(MPI_Recv(m.bytes.data(), count, MPI_CHAR, status.MPI_SOURCE, status.MPI_TAG, MPI_COMM_WORLD, MPI_STATUS_IGNORE),
        "MPI_Recv");
  return m;
}

}  // namespace

bool launched_by_mpi() {
  for (const char* name : {"OMPI_COMM_WORLD_SIZE", "PMIX_RANK", "PMI_SIZE"}) {
    if (std::getenv(name)) return true;
  }
  return false;
}

MpiSession::MpiSession() {
  int provided = 0;
  check(MPI_Init_thread(nullptr, nullptr, MPI_THREAD_FUNNELED, &provided), "MPI_Init_thread");
  // Errors come back as codes (and then exceptions) instead of aborting the job on the spot.
  MPI_Comm_set_errhandler(MPI_COMM_WORLD, MPI_ERRORS_RETURN);
  if (provided < MPI_THREAD_FUNNELED) {
    MPI_Finalize();
    throw std::runtime_error("the MPI library does not support threads (MPI_THREAD_FUNNELED)");
  }
  MPI_Comm_rank(MPI_COMM_WORLD, &rank_);
  MPI_Comm_size(MPI_COMM_WORLD, &size_);
}

MpiSession::~MpiSession() {
  if (finalize_) MPI_Finalize();
}

void share_setup(const MpiSession& mpi, CampaignSetup& setup) {
  std::string bytes;
  if (mpi.rank() == kCoordinator) {
    bytes = nlohmann::json{{"scenario_yaml", setup.scenario_yaml}, {"campaign_seed", setup.campaign_seed},
                           {"error", setup.error}}
                .dump();
  }
  broadcast_text(mpi, bytes);
  if (mpi.rank() != kCoordinator) {
    const auto j = nlohmann::json::parse(bytes);
    setup = {j.at("scenario_yaml").get<std::string>(), j.at("campaign_seed").get<std::uint64_t>(),
             j.at("error").get<std::string>()};
  }
}

void broadcast_text(const MpiSession&, std::string& text) {
  std::int64_t size = static_cast<std::int64_t>(text.size());
  check(MPI_Bcast(&size, 1, MPI_INT64_T, kCoordinator, MPI_COMM_WORLD), "MPI_Bcast");
  text.resize(static_cast<size_t>(size));
  check(MPI_Bcast(text.data(), static_cast<int>(size), MPI_CHAR, kCoordinator, MPI_COMM_WORLD), "MPI_Bcast");
}

std::string encode_record(const RunRecord& r) { return verification::encode_run_record(r); }

RunRecord decode_record(const std::string& message) { return verification::decode_run_record(message); }

// ---------------------------------------------------------------------------------------------
// Rank 0

CoordinatorResult coordinate_campaign(MpiSession& mpi, verification::ResultsStore& store, std::int64_t runs,
                                      const CoordinatorOptions& options) {
  verification::CampaignCollector collector(
      store, runs, {.on_progress = options.on_progress, .stop = options.stop, .shard = options.shard});
  enum class State { active, failed, lost };
  struct Rank {
    State state = State::active;
    std::int64_t slots = 0;  // until its hello: nothing handed out
    std::set<std::int64_t> in_flight;
    Clock::time_point last_heard;
  };
  std::map<int, Rank> ranks;
  const auto start = Clock::now();
  for (int r = 1; r < mpi.size(); ++r) ranks[r].last_heard = start;
  CoordinatorResult result;
  const auto retire = [&](Rank& rank, State state) {
    rank.state = state;
    for (std::int64_t index : rank.in_flight) collector.give_back(index);
    rank.in_flight.clear();
  };
  const auto lose = [&](Rank& rank) {
    retire(rank, State::lost);
    ++result.ranks_lost;
  };
  auto last_beat = start;

  for (;;) {
    // Hand out: every free thread of every active rank gets the next pending index.
    std::int64_t in_flight = 0;
    bool any_active = false;
    for (auto& [r, rank] : ranks) {
      if (rank.state != State::active) continue;
      any_active = true;
      while (rank.state == State::active && static_cast<std::int64_t>(rank.in_flight.size()) < rank.slots) {
        const auto index = collector.next_index();
        if (!index) break;
        rank.in_flight.insert(*index);
        if (MPI_Send(&*index, 1, MPI_INT64_T, r, kAssign, MPI_COMM_WORLD) != MPI_SUCCESS) lose(rank);
      }
      in_flight += static_cast<std::int64_t>(rank.in_flight.size());
    }
    if (in_flight == 0 && (collector.exhausted() || !any_active)) break;

    // Take in everything that has arrived, or wait a poll interval.
    bool heard = false;
    while (auto m = poll(MPI_ANY_SOURCE)) {
      heard = true;
      Rank& rank = ranks[m->source];
      if (m->tag == kResult) {
        // A run handed out twice (its first rank was thought lost) is committed once.
        const RunRecord record = decode_record(m->bytes);
        rank.in_flight.erase(record.index);
        collector.commit(record);
      } else if (m->tag == kHello && rank.state == State::active) {
        rank.slots = m->int64();
      } else if (m->tag == kFailed && rank.state == State::active) {
        retire(rank, State::failed);
        ++result.ranks_failed;
      }
      rank.last_heard = Clock::now();  // a lost rank stays lost: its runs went to others
    }
    if (!heard) std::this_thread::sleep_for(kPollInterval);

    const auto now = Clock::now();
    for (auto& [r, rank] : ranks) {
      if (rank.state == State::active && now - rank.last_heard > options.rank_timeout) lose(rank);
    }
    // Heartbeats the other way, so workers can tell a coordinator that died (under
    // --enable-recovery the launcher would leave them waiting for ever).
    if (now - last_beat >= kHeartbeatInterval) {
      for (auto& [r, rank] : ranks) {
        if (rank.state != State::lost) post_flag(false, r, kHeartbeat);
      }
      last_beat = now;
    }
  }

  // Every rank leaves; a lost one may be gone, so its message is not waited for.
  const std::int64_t leave_without_finalize = result.ranks_lost > 0;
  for (auto& [r, rank] : ranks) {
    if (rank.state == State::lost) {
      post_flag(leave_without_finalize, r, kFinish);
    } else {
      send_int64(leave_without_finalize, r, kFinish);
    }
  }
  if (leave_without_finalize) mpi.leave_without_finalize();
  result.committed = collector.committed();
  return result;
}

// ---------------------------------------------------------------------------------------------
// Ranks 1..N-1

namespace {

void serve(MpiSession& mpi, std::uint64_t campaign_seed, int jobs, const verification::WorkerFactory& make_worker,
           std::chrono::milliseconds coordinator_timeout) {
  verification::RunPool pool(jobs, campaign_seed, make_worker);
  send_int64(pool.jobs(), kCoordinator, kHello);
  auto last_sent = Clock::now();
  auto last_heard = last_sent;
  std::exception_ptr failure;
  for (;;) {
    bool finish = false;
    while (auto m = poll(kCoordinator)) {
      last_heard = Clock::now();
      if (m->tag == kAssign) {
        pool.submit(m->int64());
      } else if (m->tag == kFinish) {
        if (m->int64()) mpi.leave_without_finalize();
        finish = true;
        break;
      }
    }
    if (finish) break;
    if (Clock::now() - last_heard > coordinator_timeout) {
      throw Unreachable("rank " + std::to_string(mpi.rank()) + ": nothing heard from rank 0 for " +
                               std::to_string(coordinator_timeout.count() / 1000) + " s; leaving");
    }
    std::optional<RunRecord> record;
    if (!failure && pool.in_flight() > 0) {
      try {
        record = pool.wait_finished(kPollInterval);
      } catch (...) {
        // No thread could make its worker: the runs go back to rank 0, which hands them to
        // other ranks; this rank waits to be told to leave.
        failure = std::current_exception();
        send_bytes("", kCoordinator, kFailed, coordinator_timeout);
        last_sent = Clock::now();
      }
    } else {
      std::this_thread::sleep_for(kPollInterval);
    }
    if (record) {
      send_bytes(encode_record(*record), kCoordinator, kResult, coordinator_timeout);
      last_sent = Clock::now();
    } else if (Clock::now() - last_sent >= kHeartbeatInterval) {
      send_bytes("", kCoordinator, kHeartbeat, coordinator_timeout);
      last_sent = Clock::now();
    }
  }
  if (failure) std::rethrow_exception(failure);
}

}  // namespace

void serve_campaign(MpiSession& mpi, std::uint64_t campaign_seed, int jobs, const verification::WorkerFactory& make_worker,
                    std::chrono::milliseconds coordinator_timeout) {
  try {
    serve(mpi, campaign_seed, jobs, make_worker, coordinator_timeout);
  } catch (const Unreachable&) {
    // Rank 0 is gone or unreachable: MPI_Finalize would wait for it for ever. (A worker that
    // could not be made is reported to rank 0 first and leaves through "finish", normally.)
    mpi.leave_without_finalize();
    throw;
  }
}

}  // namespace shelfcross::distributed
