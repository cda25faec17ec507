// A campaign's runs live in worker processes (verification/campaign/run_process.hpp): runs that crash
// (cosim.inject_crash_s: a real SIGSEGV) or hang (cosim.inject_hang_s) are recorded as such
// with their reason and seed (and no CPU figure), the campaign (or search) completes with exit 0
// and its report lists them with their replay commands; runs that complete give exactly the
// records of in-process workers, apart from the informative wall and CPU times.
#include <cmath>
#include <csignal>
#include <optional>
#include <regex>
#include <thread>

#include "campaign_helpers.hpp"
#include "shelfcross/random.hpp"
#include "verification/campaign/campaign.hpp"

namespace {

using namespace shelfcross::app::test;
using nlohmann::json;

/// short_scenario with `extra` (lines of the cosim section) and cosim.timeout_s set to `timeout_s`.
fs::path faulty_scenario(const fs::path& dir, const std::string& extra, int timeout_s) {
  std::ifstream in(short_scenario(dir));
  std::stringstream text;
  text << in.rdbuf();
  std::string yaml = text.str();
  const std::string timeout = "  timeout_s: " + std::to_string(kShortTimeout_s) + "\n";
  const auto at = yaml.find(timeout);
  yaml.replace(at, timeout.size(), "  timeout_s: " + std::to_string(timeout_s) + "\n" + extra);
  const fs::path path = dir / "faulty.yaml";
  std::ofstream(path) << yaml;
  return path;
}

struct StoredRun {
  int index;
  std::uint64_t seed;
  std::string outcome;
  json metrics;
  std::optional<double> cpu_s;
};

std::vector<StoredRun> stored_runs_of(const fs::path& db) {
  SQLite::Database d(db.string(), SQLite::OPEN_READONLY);
  SQLite::Statement q(d, "SELECT run_index, seed, outcome, metrics_json, cpu_s FROM runs ORDER BY run_index");
  std::vector<StoredRun> out;
  while (q.executeStep()) {
    out.push_back({q.getColumn(0).getInt(), std::stoull(q.getColumn(1).getString()), q.getColumn(2).getString(),
                   json::parse(q.getColumn(3).getString()),
                   q.getColumn(4).isNull() ? std::nullopt : std::optional<double>(q.getColumn(4).getDouble())});
  }
  return out;
}

int count_of(const std::string& text, const std::string& what) {
  int n = 0;
  for (auto at = text.find(what); at != std::string::npos; at = text.find(what, at + 1)) ++n;
  return n;
}

TEST(CampaignWorkers, RunsThatCrashAreRecordedAndTheCampaignCompletes) {
  const fs::path root = fresh_dir("workers_crash");
  const std::string scenario = faulty_scenario(root, "  inject_crash_s: 1.5\n", 2).string();
  const fs::path out = root / "out";
  EXPECT_EQ(wait_exit(spawn({SHELFCROSS_PROGRAM, "campaign", "--scenario", scenario, "--runs", "3", "--seed", "12",
                             "--jobs", "2", "--out", out.string()},
                            (root / "log.txt").string())),
            0)
      << read_text(root / "log.txt");
  const std::vector<StoredRun> runs = stored_runs_of(out / "results.sqlite");
  ASSERT_EQ(runs.size(), 3u);
  for (const StoredRun& r : runs) {
    EXPECT_EQ(r.outcome, "crashed");
    EXPECT_EQ(r.seed, shelfcross::run_seed(12, static_cast<std::uint64_t>(r.index)));
    EXPECT_EQ(r.metrics.value("signal", 0), SIGSEGV);
    EXPECT_EQ(r.metrics.value("detail", ""), "worker process killed by signal 11 (SIGSEGV)");
    EXPECT_EQ(r.cpu_s, std::nullopt);  // lost with its process: no CPU figure, not 0
  }
  const json summary = json::parse(read_text(out / "summary.json"));
  EXPECT_EQ(summary["outcomes"], json({{"crashed", 3}}));
  EXPECT_EQ(summary["cost"]["cpu_s_per_run"], nullptr);
  const std::string report = read_text(out / "report.md");
  EXPECT_EQ(count_of(report, "killed by signal 11 (SIGSEGV) | `shelfcross replay "), 3) << report;
  EXPECT_EQ(count_of(report, "CPU time not recorded"), 1) << report;
}

TEST(CampaignWorkers, ASearchWhoseRunsCrashRecordsThemAndCompletes) {
  // A search's runs are drawn from its rounds' proposals and sent to the worker processes with
  // their draws; a crash takes its worker only, and counts as a mission failure.
  const fs::path root = fresh_dir("workers_search_crash");
  const std::string scenario = faulty_scenario(root, "  inject_crash_s: 1.5\n", 2).string();
  const fs::path out = root / "out";
  EXPECT_EQ(wait_exit(spawn({SHELFCROSS_PROGRAM, "search", "--scenario", scenario, "--budget", "4", "--seed", "5",
                             "--jobs", "2", "--class", "mission", "--round-runs", "2", "--estimation-runs", "2",
                             "--out", out.string()},
                            (root / "log.txt").string())),
            0)
      << read_text(root / "log.txt");
  const std::vector<StoredRun> runs = stored_runs_of(out / "results.sqlite");
  ASSERT_EQ(runs.size(), 4u);
  for (const StoredRun& r : runs) {
    EXPECT_EQ(r.outcome, "crashed");
    EXPECT_EQ(r.metrics.value("signal", 0), SIGSEGV);
  }
  const json summary = json::parse(read_text(out / "search_summary.json"));
  EXPECT_EQ(summary["estimates"]["mission"]["round"], 1);
  EXPECT_EQ(summary["estimates"]["mission"]["failures"], 2);
  EXPECT_EQ(summary["failures"].size(), 4u);
}

TEST(CampaignWorkers, RunsThatHangAreKilledAtTheirLimitAndRecorded) {
  const fs::path root = fresh_dir("workers_hang");
  const std::string scenario = faulty_scenario(root, "  inject_hang_s: 1\n", 4).string();
  const fs::path out = root / "out";
  // The limit: max(2 s, 0 x cosim.timeout_s) of wall-clock time per run.
  EXPECT_EQ(wait_exit(spawn({SHELFCROSS_PROGRAM, "campaign", "--scenario", scenario, "--runs", "2", "--seed", "3",
                             "--jobs", "1", "--run-wall-factor", "0", "--run-wall-floor", "2", "--out", out.string()},
                            (root / "log.txt").string())),
            0)
      << read_text(root / "log.txt");
  const std::vector<StoredRun> runs = stored_runs_of(out / "results.sqlite");
  ASSERT_EQ(runs.size(), 2u);
  for (const StoredRun& r : runs) {
    EXPECT_EQ(r.outcome, "hung");
    EXPECT_EQ(r.seed, shelfcross::run_seed(3, static_cast<std::uint64_t>(r.index)));
    EXPECT_TRUE(r.metrics.value("detail", "").starts_with("no result after 2.0 s of wall-clock time"))
        << r.metrics.dump();
  }
  EXPECT_EQ(count_of(read_text(out / "report.md"), "`shelfcross replay "), 2);
}

// A campaign stopped with a run in flight (Ctrl-Z, SIGSTOP, a suspended machine) and continued
// after longer than the run's wall-clock limit: the stop is not counted against the run, which
// completes (a campaign stopped for 47 min once stored its run in flight `hung`).
TEST(CampaignWorkers, AStoppedCampaignDoesNotCountTheStopAgainstItsRun) {
  const fs::path root = fresh_dir("workers_stopped");
  const std::string scenario = short_scenario(root).string();
  const fs::path out = root / "out";
  // The limit: 12 s of wall-clock time per run (a short run takes a few); the stop lasts 16 s.
  const pid_t campaign = spawn({SHELFCROSS_PROGRAM, "campaign", "--scenario", scenario, "--runs", "1", "--seed", "3",
                                "--jobs", "1", "--run-wall-factor", "0", "--run-wall-floor", "12", "--out",
                                out.string()},
                               (root / "log.txt").string());
  std::vector<pid_t> workers;
  for (int i = 0; i < 600 && workers.empty(); ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
    workers = children_of(campaign);
  }
  ASSERT_EQ(workers.size(), 1u) << read_text(root / "log.txt");
  std::this_thread::sleep_for(std::chrono::seconds(1));  // into the run (or the worker's start-up)
  ::kill(campaign, SIGSTOP);
  ::kill(workers[0], SIGSTOP);
  std::this_thread::sleep_for(std::chrono::seconds(16));
  ::kill(workers[0], SIGCONT);
  ::kill(campaign, SIGCONT);
  EXPECT_EQ(wait_exit(campaign), 0) << read_text(root / "log.txt");
  const std::vector<StoredRun> runs = stored_runs_of(out / "results.sqlite");
  ASSERT_EQ(runs.size(), 1u);
  EXPECT_NE(runs[0].outcome, "hung") << runs[0].metrics.dump();
}

TEST(CampaignWorkers, WorkerProcessesStoreTheRecordsOfInProcessWorkers) {
  namespace v = shelfcross::verification;
  const fs::path root = fresh_dir("workers_same");
  const std::string scenario = short_scenario(root).string();
  const fs::path out = root / "processes";
  EXPECT_EQ(wait_exit(spawn({SHELFCROSS_PROGRAM, "campaign", "--scenario", scenario, "--runs", "3", "--seed", "9",
                             "--jobs", "2", "--out", out.string()})),
            0);
  // The same campaign on CampaignWorker threads in this process, as campaigns ran before.
  auto nominal = std::make_shared<const v::Scenario>(v::load_scenario(scenario));
  v::ResultsStore threads = v::ResultsStore::open_or_create(root / "threads.sqlite", {v::write_scenario(*nominal), 9, 3});
  v::run_pending(threads, 9, 3, [nominal](int) { return std::make_unique<v::CampaignWorker>(nominal); }, {.jobs = 2});
  v::ResultsStore processes = v::ResultsStore::open_existing(out / "results.sqlite");
  std::vector<v::RunRecord> a = threads.runs(), b = processes.runs();
  ASSERT_EQ(a.size(), 3u);
  ASSERT_EQ(b.size(), 3u);
  for (size_t i = 0; i < a.size(); ++i) {
    // Each run's CPU seconds: its worker process's, or its worker thread's.
    for (const v::RunRecord& r : {a[i], b[i]}) {
      ASSERT_TRUE(r.cpu_s.has_value()) << "run " << i;
      EXPECT_TRUE(std::isfinite(*r.cpu_s) && *r.cpu_s > 0.0) << *r.cpu_s;
    }
    a[i].wall_s = b[i].wall_s = 0.0;  // informative, not part of the result
    a[i].cpu_s = b[i].cpu_s = std::nullopt;
    EXPECT_EQ(a[i], b[i]) << "run " << i;
  }
  EXPECT_EQ(v::summarize_campaign(a, 3, 0.02).campaign_hash, campaign_hash(out));
  const json cost = json::parse(read_text(out / "summary.json"))["cost"];
  EXPECT_EQ(cost["cpu_s_per_run"]["count"], 3);
  EXPECT_GT(cost["cpu_s_per_simulated_s"].get<double>(), 0.0);
  EXPECT_EQ(count_of(read_text(out / "report.md"), "| runs with a CPU figure | 3 of 3 |"), 1);
}

}  // namespace
