#pragma once
// The options `campaign`, `compare` and `search` share for their worker processes' limits
// (verification/campaign/run_process.hpp).

#include <CLI/CLI.hpp>

#include "verification/campaign/run_process.hpp"

namespace shelfcross::app {

/// Adds the three options to `sub`, writing into `limits` (which must outlive parsing); values
/// outside their ranges are usage errors reported by CLI11 (exit code 2 in the program).
inline void add_worker_limit_options(CLI::App& sub, verification::WorkerLimits& limits) {
  sub.add_option("--run-wall-factor", limits.wall_factor,
                 "a run whose worker process gives no result within max(--run-wall-floor, this x the scenario's "
                 "cosim.timeout_s) seconds of wall-clock time is killed and recorded as `hung`")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 1000.0));
  sub.add_option("--run-wall-floor", limits.wall_floor_s, "seconds; see --run-wall-factor")
      ->capture_default_str()
      ->check(CLI::Range(0.1, 86400.0));
  sub.add_option("--worker-memory", limits.memory_limit_mb,
                 "MiB: a worker process whose resident set grows beyond this is killed and its run recorded as "
                 "`crashed` (0: no limit)")
      ->capture_default_str()
      ->check(CLI::Range(std::int64_t{0}, std::int64_t{1} << 30));
}

}  // namespace shelfcross::app
