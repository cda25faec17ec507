#pragma once
// Runs in worker processes: a campaign's runs each happen in a child process of the program
// (the hidden `shelfcross worker` subcommand), so that a run that crashes (a signal, e.g. a
// fault inside the graphics driver), hangs or eats the machine's memory takes down its worker
// only. The run is recorded as `crashed` or `hung`, with the reason and its seed, the worker is
// replaced, and the campaign goes on.
//
//   parent (RunPool thread)                      child (`shelfcross worker --fd 3`)
//   ProcessRunWorker ---- socketpair, fd 3 ----> serve_worker_runs
//     {"scenario_yaml": ...}              --->   parses it, builds its CampaignWorker (one
//                                         <---   {"ready": true} | {"error": "..."}   renderer,
//     {"index": k, "seed": s, "draws": {..}} --> one EGL context for the worker's life)
//                                         <---   the run's RunRecord as JSON
//
// One JSON document per line (JSON text never holds a raw newline). The parent draws each
// run's dispersions (the scenario's own, or a search round's proposal: campaign.hpp,
// DrawFunction) and sends them; JSON numbers round-trip doubles exactly, so the child's record
// is the one CampaignWorker makes in a thread, and results, run hashes and the campaign hash
// are the same as with in-process workers (all but the informative wall_s and cpu_s; cpu_s is
// the child process's CPU time across the run). Limits, checked by the parent while it waits:
//   wall clock   max(wall_floor_s, wall_factor x the run's cosim.timeout_s) from the moment
//                the run is handed over (start-up, at most max(300 s, that limit), not
//                counted; nor is any time the campaign itself was stopped or the machine
//                suspended): exceeded -> SIGKILL, `hung`
//   memory       the child's resident set (/proc/PID/statm) above memory_limit_mb:
//                SIGKILL, `crashed` (RLIMIT_AS is not used: AddressSanitizer and Mesa's
//                llvmpipe reserve far more address space than they use)
// A child that ends by a signal, or exits, while a run is in flight: `crashed`. The next run
// starts a fresh child; if that one cannot start (it dies or errs before it is ready), that
// run is recorded as `worker_error` with the reason, and the run after tries again.
// The child ignores SIGINT and SIGTERM (Ctrl-C stops the parent, which lets the runs in flight
// finish) and dies with its parent thread (PR_SET_PDEATHSIG).

#include <sys/types.h>

#include <cstdint>
#include <memory>
#include <string>

#include "verification/campaign/campaign.hpp"
#include "verification/campaign/campaign_pool.hpp"
#include "verification/scenario/scenario.hpp"

namespace shelfcross::verification {

struct WorkerLimits {
  double wall_factor = 10.0;      ///< wall seconds per simulated second of cosim.timeout_s ...
  double wall_floor_s = 60.0;     ///< ... never less than this
  std::int64_t memory_limit_mb = 4096;  ///< resident set of one worker process; 0: no limit
};

/// The wall-clock limit of one run of `scenario` (see the file comment).
double run_wall_limit_s(const Scenario& scenario, const WorkerLimits& limits);

/// A RunWorker whose runs happen in a child process (`executable worker --fd 3`), started in
/// the constructor and again after one died; each run with draw(seed) when `draw` is set, else
/// with the scenario's own draws. Throws std::runtime_error when the child cannot start or
/// reports an error before it is ready.
class ProcessRunWorker : public RunWorker {
 public:
  ProcessRunWorker(std::shared_ptr<const Scenario> nominal, WorkerLimits limits, std::string executable,
                   DrawFunction draw = {});
  ~ProcessRunWorker() override;
  ProcessRunWorker(const ProcessRunWorker&) = delete;
  ProcessRunWorker& operator=(const ProcessRunWorker&) = delete;

  /// Throws std::invalid_argument when the child answers with another run's record.
  RunRecord run(std::int64_t index, std::uint64_t seed) override;
  /// The child's process id (0 when none runs): for tests.
  pid_t child_pid() const { return pid_; }

 private:
  void start_child();
  /// Kills the child (if alive) and reaps it; returns its wait status.
  int end_child(bool kill_first);
  RunRecord lost_run_record(std::int64_t index, std::uint64_t seed, const DrawnValues& drawn,
                            const std::string& outcome, const std::string& detail, int signal_number) const;

  /// The run's draws: draw(seed), or the scenario's own.
  DrawnValues draws_of(std::uint64_t seed) const;

  std::shared_ptr<const Scenario> nominal_;
  DrawFunction draw_;
  std::string scenario_yaml_;
  WorkerLimits limits_;
  std::string executable_;
  pid_t pid_ = 0;
  int fd_ = -1;
  std::string buffer_;  ///< bytes read from the child beyond the last line
};

/// Workers in child processes of `executable` (for the program itself: "/proc/self/exe"),
/// drawing with `draw` when set (see ProcessRunWorker).
WorkerFactory process_worker_factory(std::shared_ptr<const Scenario> nominal, WorkerLimits limits,
                                     std::string executable = "/proc/self/exe", DrawFunction draw = {});

/// The child's side: serves runs on `fd` until the parent closes it. Returns the exit code.
int serve_worker_runs(int fd);

}  // namespace shelfcross::verification
