// `shelfcross campaign` under mpirun (loopback only, oversubscribed on a small machine): three
// ranks (a coordinator and two workers) give the per-run hashes and the campaign hash of one
// process; a worker rank killed mid-campaign costs only its runs in flight: Open MPI aborts
// the job, and the same command again completes it with every run once; with
// `mpirun --enable-recovery` the job goes on and completes in one go. A search under mpirun
// stores the runs and rounds of one process.
#ifdef SHELFCROSS_MPIEXEC
#include <dirent.h>

#include <cstdlib>

#include "campaign_helpers.hpp"

namespace {

using namespace shelfcross::app::test;

// As root (CI), Open MPI wants both variables; shared memory and loopback only.
std::vector<std::string> mpirun(int ranks, const std::vector<std::string>& extra_mpirun_args) {
  setenv("OMPI_ALLOW_RUN_AS_ROOT", "1", 1);
  setenv("OMPI_ALLOW_RUN_AS_ROOT_CONFIRM", "1", 1);
  // Debug preset (ASan): Open MPI's own lifetime allocations are not shelfcross's leaks
  // (scripts/lsan.supp). Open MPI and libc are built without frame pointers and Open MPI 4.1
  // unloads its components at MPI_Finalize (it has no parameter to keep them), so LeakSanitizer's
  // default (frame-pointer) stacks of their allocations stop after one frame, in an unloaded
  // "<unknown module>", and match nothing; unwinding by DWARF tables on every allocation
  // (fast_unwind_on_malloc=0) gives whole stacks that reach libmpi or libopen-pal. Slower, so
  // only for the ranks (and their worker processes) started here; harmless without ASan.
  // The worker processes inherit it (they are the ranks' children), and under the debug preset
  // on a 2-core machine a run then took longer than the default 60 s wall-clock floor and was
  // stored `hung`: these tests give their runs a floor of 30 min (campaign_args), since what
  // they check is hashes and lost ranks, not the hung-run limit (cmd_campaign_workers_test.cpp checks
  // that one).
  setenv("LSAN_OPTIONS",
         "suppressions=" SHELFCROSS_SOURCE_DIR "/scripts/lsan.supp:print_suppressions=0:fast_unwind_on_malloc=0", 1);
  std::vector<std::string> c{SHELFCROSS_MPIEXEC, "-np", std::to_string(ranks), "--oversubscribe", "--bind-to", "none",
                             "--mca", "btl", "self,vader", "--mca", "oob_tcp_if_include", "lo"};
  c.insert(c.end(), extra_mpirun_args.begin(), extra_mpirun_args.end());
  c.push_back(SHELFCROSS_PROGRAM);
  return c;
}

std::vector<std::string> campaign_args(const fs::path& scenario, int runs, const fs::path& out) {
  return {"campaign", "--scenario", scenario.string(), "--runs", std::to_string(runs), "--seed", "2024",
          "--jobs", "1", "--run-wall-floor", "1800", "--out", out.string()};
}

std::vector<std::string> concat(std::vector<std::string> a, const std::vector<std::string>& b) {
  a.insert(a.end(), b.begin(), b.end());
  return a;
}

/// The process id of MPI rank `rank` among the children of mpirun `launcher` (0 if none yet).
pid_t rank_pid(pid_t launcher, int rank) {
  const std::string wanted = "OMPI_COMM_WORLD_RANK=" + std::to_string(rank);
  for (const pid_t child : children_of(launcher)) {
    const std::string environ_text = read_text("/proc/" + std::to_string(child) + "/environ");
    for (size_t at = 0; at < environ_text.size();) {
      const size_t end = environ_text.find('\0', at);
      if (environ_text.compare(at, (end == std::string::npos ? environ_text.size() : end) - at, wanted) == 0) {
        return child;
      }
      if (end == std::string::npos) break;
      at = end + 1;
    }
  }
  return 0;
}

std::vector<int> indices(const fs::path& db) {
  std::vector<int> out;
  for (const auto& [index, hash] : stored_hashes(db)) out.push_back(index);
  return out;
}

TEST(MpiCampaign, ThreeRanksEqualOneProcess) {
  const fs::path root = fresh_dir("mpi_campaign_equal");
  const fs::path scenario = short_scenario(root);
  EXPECT_EQ(wait_exit(spawn(concat({SHELFCROSS_PROGRAM}, campaign_args(scenario, 4, root / "one")))), 0);
  const fs::path log = root / "mpi.log";
  EXPECT_EQ(wait_exit(spawn(concat(mpirun(3, {}), campaign_args(scenario, 4, root / "mpi")), log.string())), 0)
      << read_text(log);
  EXPECT_NE(read_text(log).find("campaign on 2 worker ranks x 1 threads"), std::string::npos) << read_text(log);
  EXPECT_EQ(stored_hashes(root / "mpi" / "results.sqlite"), stored_hashes(root / "one" / "results.sqlite"));
  EXPECT_EQ(campaign_hash(root / "mpi"), campaign_hash(root / "one"));
  EXPECT_EQ(campaign_hash(root / "one").size(), 32u);
  EXPECT_EQ(stored_link_models(root / "mpi" / "results.sqlite"), std::vector<std::string>(4, "sdk"));
  // The same command again resumes: nothing left to do, nothing run twice.
  EXPECT_EQ(wait_exit(spawn(concat(mpirun(3, {}), campaign_args(scenario, 4, root / "mpi")))), 0);
  EXPECT_EQ(indices(root / "mpi" / "results.sqlite"), (std::vector<int>{0, 1, 2, 3}));
  // Bad input on rank 0 (another seed into the same folder): every rank leaves, exit code 2.
  auto other = concat(mpirun(3, {}), campaign_args(scenario, 4, root / "mpi"));
  other[other.size() - 5] = "2025";
  EXPECT_EQ(wait_exit(spawn(other)), 2);
}

TEST(MpiSearch, ThreeRanksEqualOneProcess) {
  // A search under mpirun: rank 0 plans the rounds, the worker ranks run them with the draws of
  // each round's broadcast proposal. The short scenario's runs all time out, so round 1 (the
  // estimation round) draws from a refitted proposal: its runs check the draws across ranks.
  const fs::path root = fresh_dir("mpi_search_equal");
  const fs::path scenario = short_scenario(root);
  const auto search = [&](const fs::path& out) {
    return std::vector<std::string>{"search", "--scenario", scenario.string(), "--budget", "6", "--seed", "77",
                                    "--jobs", "1", "--class", "mission", "--round-runs", "2", "--estimation-runs", "2",
                                    "--run-wall-floor", "1800", "--out", out.string()};
  };
  EXPECT_EQ(wait_exit(spawn(concat({SHELFCROSS_PROGRAM}, search(root / "one")))), 0);
  const fs::path log = root / "mpi.log";
  EXPECT_EQ(wait_exit(spawn(concat(mpirun(3, {}), search(root / "mpi")), log.string())), 0) << read_text(log);
  EXPECT_NE(read_text(log).find("search on 2 worker ranks x 1 workers"), std::string::npos) << read_text(log);
  EXPECT_EQ(stored_hashes(root / "mpi" / "results.sqlite").size(), 6u);
  EXPECT_EQ(stored_hashes(root / "mpi" / "results.sqlite"), stored_hashes(root / "one" / "results.sqlite"));
  EXPECT_EQ(stored_rounds(root / "mpi" / "results.sqlite"), stored_rounds(root / "one" / "results.sqlite"));
  // Bad input on rank 0 (other settings into the same folder): every rank leaves, exit code 2.
  auto other = concat(mpirun(3, {}), search(root / "mpi"));
  other[other.size() - 5] = "3";  // --estimation-runs 3
  EXPECT_EQ(other[other.size() - 6], "--estimation-runs");
  EXPECT_EQ(wait_exit(spawn(other)), 2);
}

// Kills worker rank 1 once the first run is committed (it is then most likely in a run).
void kill_rank_one_after_first_run(pid_t launcher, const fs::path& db) {
  pid_t victim = 0;
  for (int i = 0; i < 6000 && (stored_runs(db) < 1 || victim == 0); ++i) {
    if (victim == 0) victim = rank_pid(launcher, 1);
    usleep(10000);
  }
  ASSERT_GE(stored_runs(db), 1);
  ASSERT_NE(victim, 0);
  kill(victim, SIGKILL);
}

TEST(MpiCampaign, KilledWorkerRankThenResumeCompletesEveryRunOnce) {
  const fs::path root = fresh_dir("mpi_campaign_killed");
  const fs::path scenario = short_scenario(root);
  const auto command = concat(mpirun(3, {}), campaign_args(scenario, 6, root / "mpi"));
  const pid_t launcher = spawn(command);
  kill_rank_one_after_first_run(launcher, root / "mpi" / "results.sqlite");
  EXPECT_NE(wait_exit(launcher), 0);  // Open MPI aborts the job
  const int before = stored_runs(root / "mpi" / "results.sqlite");
  EXPECT_GE(before, 1);
  EXPECT_LT(before, 6);
  const fs::path log = root / "resume.log";
  EXPECT_EQ(wait_exit(spawn(command, log.string())), 0) << read_text(log);
  EXPECT_EQ(indices(root / "mpi" / "results.sqlite"), (std::vector<int>{0, 1, 2, 3, 4, 5}));
  EXPECT_EQ(wait_exit(spawn(concat({SHELFCROSS_PROGRAM}, campaign_args(scenario, 6, root / "one")))), 0);
  EXPECT_EQ(stored_hashes(root / "mpi" / "results.sqlite"), stored_hashes(root / "one" / "results.sqlite"));
  EXPECT_EQ(campaign_hash(root / "mpi"), campaign_hash(root / "one"));
}

TEST(MpiCampaign, KilledWorkerRankUnderRecoveryCompletesInOneGo) {
  const fs::path root = fresh_dir("mpi_campaign_recovery");
  const fs::path scenario = short_scenario(root);
  const fs::path log = root / "mpi.log";
  const pid_t launcher = spawn(concat(concat(mpirun(3, {"--enable-recovery"}), campaign_args(scenario, 6, root / "mpi")),
                                      {"--rank-timeout", "3"}),
                               log.string());
  kill_rank_one_after_first_run(launcher, root / "mpi" / "results.sqlite");
  EXPECT_EQ(wait_exit(launcher), 0) << read_text(log);
  EXPECT_NE(read_text(log).find("1 worker rank(s) lost"), std::string::npos) << read_text(log);
  EXPECT_EQ(indices(root / "mpi" / "results.sqlite"), (std::vector<int>{0, 1, 2, 3, 4, 5}));
  EXPECT_EQ(wait_exit(spawn(concat({SHELFCROSS_PROGRAM}, campaign_args(scenario, 6, root / "one")))), 0);
  EXPECT_EQ(campaign_hash(root / "mpi"), campaign_hash(root / "one"));
}

}  // namespace
#endif
