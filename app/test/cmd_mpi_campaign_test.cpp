// `shelfcross campaign` under mpirun (loopback only, oversubscribed on a small machine): three
// ranks (a coordinator and two workers) give the per-run hashes and the campaign hash of one
// process; a worker rank killed mid-campaign costs only its runs in flight: Open MPI aborts
// the job, and the same command again completes it with every run once; with
// `mpirun --enable-recovery` the job goes on and completes in one go. A search under mpirun
// stores the runs and rounds of one process.
#ifdef SHELFCROSS_MPIEXEC
#include <dirent.h>

#include <algorithm>
#include <cstdlib>

#include "campaign_helpers.hpp"

namespace {

using namespace shelfcross::app::test;

// As root (CI), Open MPI wants both variables; shared memory and loopback only.
std::vector<std::string> mpirun(int ranks, const std::vector<std::string>& extra_mpirun_args) {
  setenv("OMPI_ALLOW_RUN_AS_ROOT", "1", 1);
  setenv("OMPI_ALLOW_RUN_AS_ROOT_CONFIRM", "1", 1);
  // Debug preset (ASan): the ranks run without LeakSanitizer (ASan and UBSan stay on), given
  // to them alone with mpirun's -x. Open MPI keeps allocations for the life of a process and
  // unloads its components (mca_*.so) at MPI_Finalize, with no parameter to keep them, so with
  // LeakSanitizer's default frame-pointer stacks those allocations end in an unloaded "<unknown
  // module>" that no suppression can name (117 kB in about 3,340 allocations per rank). Whole
  // DWARF stacks (fast_unwind_on_malloc=0) would reach libmpi, but the worker processes inherit
  // the option, and there it deadlocks: libgcc's _Unwind_Find_FDE holds its lock while it
  // allocates, ASan's malloc unwinds again and waits for that lock (seen under
  // gdb, with the frames llvmpipe's JIT registers: every MPI test hung until its time limit).
  // The ranks' code but distributed/ is leak-checked by the single-process tests. (The hang
  // was once taken for slowness and gave these runs a 30 min wall-clock floor; without the
  // deadlock each of these tests takes about 22 s under the debug preset.)
  std::vector<std::string> c{SHELFCROSS_MPIEXEC, "-np", std::to_string(ranks), "--oversubscribe", "--bind-to", "none",
                             "--mca", "btl", "self,vader", "--mca", "oob_tcp_if_include", "lo",
                             "-x", "ASAN_OPTIONS=detect_leaks=0"};
  c.insert(c.end(), extra_mpirun_args.begin(), extra_mpirun_args.end());
  c.push_back(SHELFCROSS_PROGRAM);
  return c;
}

std::vector<std::string> campaign_args(const fs::path& scenario, int runs, const fs::path& out) {
  return {"campaign", "--scenario", scenario.string(), "--runs", std::to_string(runs), "--seed", "2024",
          "--jobs", "1", "--out", out.string()};
}

/// `args` with the value after `option` replaced by `value`.
std::vector<std::string> with_option(std::vector<std::string> args, const std::string& option, const std::string& value) {
  const auto at = std::find(args.begin(), args.end(), option);
  EXPECT_TRUE(at != args.end() && at + 1 != args.end()) << option;
  if (at != args.end() && at + 1 != args.end()) *(at + 1) = value;
  return args;
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
  // Each run's CPU figure travels from the worker rank's process to rank 0's store.
  EXPECT_EQ(nlohmann::json::parse(read_text(root / "mpi" / "summary.json"))["cost"]["cpu_s_per_run"]["count"], 4);
  // The same command again resumes: nothing left to do, nothing run twice.
  EXPECT_EQ(wait_exit(spawn(concat(mpirun(3, {}), campaign_args(scenario, 4, root / "mpi")))), 0);
  EXPECT_EQ(indices(root / "mpi" / "results.sqlite"), (std::vector<int>{0, 1, 2, 3}));
  // Bad input on rank 0 (another seed into the same folder): every rank leaves, exit code 2.
  EXPECT_EQ(wait_exit(spawn(with_option(concat(mpirun(3, {}), campaign_args(scenario, 4, root / "mpi")), "--seed", "2025"))),
            2);
}

TEST(MpiSearch, ThreeRanksEqualOneProcess) {
  // A search under mpirun: rank 0 plans the rounds, the worker ranks run them with the draws of
  // each round's broadcast proposal. The short scenario's runs all time out, so round 1 (the
  // estimation round) draws from a refitted proposal: its runs check the draws across ranks.
  const fs::path root = fresh_dir("mpi_search_equal");
  const fs::path scenario = short_scenario(root);
  const auto search = [&](const fs::path& out) { return search_args(scenario.string(), out); };
  EXPECT_EQ(wait_exit(spawn(concat({SHELFCROSS_PROGRAM}, search(root / "one")))), 0);
  const fs::path log = root / "mpi.log";
  EXPECT_EQ(wait_exit(spawn(concat(mpirun(3, {}), search(root / "mpi")), log.string())), 0) << read_text(log);
  EXPECT_NE(read_text(log).find("search on 2 worker ranks x 1 workers"), std::string::npos) << read_text(log);
  EXPECT_EQ(stored_hashes(root / "mpi" / "results.sqlite").size(), 4u);
  EXPECT_EQ(stored_hashes(root / "mpi" / "results.sqlite"), stored_hashes(root / "one" / "results.sqlite"));
  EXPECT_EQ(stored_rounds(root / "mpi" / "results.sqlite"), stored_rounds(root / "one" / "results.sqlite"));
  // Bad input on rank 0 (other settings into the same folder): every rank leaves, exit code 2.
  EXPECT_EQ(wait_exit(spawn(with_option(concat(mpirun(3, {}), search(root / "mpi")), "--estimation-runs", "3"))), 2);
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
  const auto command = concat(mpirun(3, {}), campaign_args(scenario, 4, root / "mpi"));
  const pid_t launcher = spawn(command);
  kill_rank_one_after_first_run(launcher, root / "mpi" / "results.sqlite");
  EXPECT_NE(wait_exit(launcher), 0);  // Open MPI aborts the job
  const int before = stored_runs(root / "mpi" / "results.sqlite");
  EXPECT_GE(before, 1);
  EXPECT_LT(before, 4);
  const fs::path log = root / "resume.log";
  EXPECT_EQ(wait_exit(spawn(command, log.string())), 0) << read_text(log);
  EXPECT_EQ(indices(root / "mpi" / "results.sqlite"), (std::vector<int>{0, 1, 2, 3}));
  EXPECT_EQ(wait_exit(spawn(concat({SHELFCROSS_PROGRAM}, campaign_args(scenario, 4, root / "one")))), 0);
  EXPECT_EQ(stored_hashes(root / "mpi" / "results.sqlite"), stored_hashes(root / "one" / "results.sqlite"));
  EXPECT_EQ(campaign_hash(root / "mpi"), campaign_hash(root / "one"));
}

TEST(MpiCampaign, KilledWorkerRankUnderRecoveryCompletesInOneGo) {
  const fs::path root = fresh_dir("mpi_campaign_recovery");
  const fs::path scenario = short_scenario(root);
  const fs::path log = root / "mpi.log";
  const pid_t launcher = spawn(concat(concat(mpirun(3, {"--enable-recovery"}), campaign_args(scenario, 4, root / "mpi")),
                                      {"--rank-timeout", "3"}),
                               log.string());
  kill_rank_one_after_first_run(launcher, root / "mpi" / "results.sqlite");
  EXPECT_EQ(wait_exit(launcher), 0) << read_text(log);
  EXPECT_NE(read_text(log).find("1 worker rank(s) lost"), std::string::npos) << read_text(log);
  EXPECT_EQ(indices(root / "mpi" / "results.sqlite"), (std::vector<int>{0, 1, 2, 3}));
  EXPECT_EQ(wait_exit(spawn(concat({SHELFCROSS_PROGRAM}, campaign_args(scenario, 4, root / "one")))), 0);
  EXPECT_EQ(campaign_hash(root / "mpi"), campaign_hash(root / "one"));
}

}  // namespace
#endif
