#pragma once
// A campaign across the ranks of an MPI job (`mpirun -np N shelfcross campaign ...`).
//
// Rank 0, the coordinator, owns the results database (verification::CampaignCollector): it
// hands out run indices on demand, one per free worker thread, and commits each finished run
// as it arrives. Ranks 1..N-1 each run a verification::RunPool of `--jobs` threads on what
// they are handed. Records depend only on (scenario, campaign seed, run index), so the
// database, every run hash and the campaign hash are those of a single process.
//
// Messages (MPI_COMM_WORLD; only each process's main thread calls MPI):
//   setup      broadcast from rank 0: the fully resolved scenario and the seed (or an error)
//   hello      worker -> 0   its thread count: how many runs it may hold at once
//   assign     0 -> worker   one run index to run
//   result     worker -> 0   a finished run's record (JSON)
//   heartbeat  both ways, once a second, so a rank (or rank 0) that went silent can be told
//   failed     worker -> 0   it could not make its workers (e.g. no EGL): its runs go back
//   finish     0 -> worker   leave; whether to skip MPI_Finalize (a rank was lost)
//
// Failures. A worker rank that dies costs only its runs in flight. Open MPI by default aborts
// the whole job when a rank dies; committed runs are safe in the database (WAL, synchronous=
// FULL), and the same command again resumes. Launched with `mpirun --enable-recovery`, the job
// goes on: the coordinator declares a rank silent for longer than the rank timeout lost and
// hands its runs in flight out again; a result that still arrives from it later is committed
// if no one else delivered that run first (it is the same record). Since MPI_Finalize would
// wait for the lost rank forever, every rank then leaves without it. Workers that hear nothing
// from rank 0 for the rank timeout (it died under --enable-recovery) leave with an error.
//
// The coordinator and the workers wait for messages by polling (MPI_Iprobe, then a 1 ms
// sleep) instead of a blocking receive, which Open MPI implements as a busy loop that would
// take a core from the simulations. The poll interval affects only latency, never results.

#include <atomic>
#include <chrono>
#include <cstdint>
#include <functional>
#include <string>

#include "verification/campaign/campaign_pool.hpp"
#include "verification/campaign/results_store.hpp"

namespace shelfcross::distributed {

/// True when an MPI launcher started this process (mpirun/mpiexec of Open MPI, or a PMIx/PMI
/// launcher such as Slurm's srun): the environment variables they set are present.
bool launched_by_mpi();

/// MPI for the life of one command: MPI_Init_thread (MPI_THREAD_FUNNELED) to MPI_Finalize.
class MpiSession {
 public:
  /// Throws std::runtime_error when the MPI library does not support MPI_THREAD_FUNNELED.
  MpiSession();
  ~MpiSession();
  MpiSession(const MpiSession&) = delete;
  MpiSession& operator=(const MpiSession&) = delete;
  int rank() const { return rank_; }
  int size() const { return size_; }
  /// Skip MPI_Finalize at the end (it would wait for a lost rank forever).
  void leave_without_finalize() { finalize_ = false; }
  /// False once a rank was lost (leave_without_finalize): no collective can complete any more.
  bool intact() const { return finalize_; }

 private:
  int rank_ = 0;
  int size_ = 1;
  bool finalize_ = true;
};

/// What every rank needs: rank 0 fills it in, or sets `error` when its own setup failed (the
/// other ranks then leave with exit code 2 and rank 0 reports the error).
struct CampaignSetup {
  std::string scenario_yaml;  ///< fully resolved (verification::write_scenario)
  std::uint64_t campaign_seed = 0;
  std::string error;
};

/// Collective: every rank gets rank 0's `setup`.
void share_setup(const MpiSession& mpi, CampaignSetup& setup);

/// Collective: every rank gets rank 0's `text` (a search's next round, app/cmd_search.cpp).
void broadcast_text(const MpiSession& mpi, std::string& text);

struct CoordinatorOptions {
  /// Called on rank 0 after each committed run.
  std::function<void(const verification::CampaignProgress&)> on_progress;
  /// When raised (SIGINT, SIGTERM on rank 0): nothing more is handed out; runs in flight come
  /// back and are committed, then every rank leaves.
  const std::atomic<bool>* stop = nullptr;
  verification::Shard shard;
  /// A worker rank silent for this long (no heartbeat, no result) is lost; see the file comment.
  std::chrono::milliseconds rank_timeout{60000};
};

struct CoordinatorResult {
  std::int64_t committed = 0;  ///< runs committed this session
  int ranks_lost = 0;          ///< worker ranks that went silent
  int ranks_failed = 0;        ///< worker ranks that could not make their workers
};

/// Rank 0 of a job of size >= 2: runs the pending runs of [0, runs) of the shard on the other
/// ranks and commits them into `store`; returns when every run is committed, or nothing more
/// can be (stop raised, no worker rank left). Calls mpi.leave_without_finalize() when a rank
/// was lost.
CoordinatorResult coordinate_campaign(MpiSession& mpi, verification::ResultsStore& store, std::int64_t runs,
                                      const CoordinatorOptions& options);

/// Ranks 1..N-1: run what rank 0 hands out on a RunPool of `jobs` threads until it says finish.
/// Throws the workers' construction error if none could be made (after telling rank 0), and
/// std::runtime_error when rank 0 has been silent (no heartbeat) for `coordinator_timeout`.
void serve_campaign(MpiSession& mpi, std::uint64_t campaign_seed, int jobs,
                    const verification::WorkerFactory& make_worker, std::chrono::milliseconds coordinator_timeout);

/// A run record as the message that carries it (JSON), and back; decode throws
/// std::invalid_argument on a malformed message.
std::string encode_record(const verification::RunRecord& record);
verification::RunRecord decode_record(const std::string& message);

}  // namespace shelfcross::distributed
