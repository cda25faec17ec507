#pragma once
// What the campaign CLI tests share: starting the program (or mpirun) as a child process,
// waiting for it, a short scenario, and reading a campaign's results back.
#include <fcntl.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>
#include <SQLiteCpp/SQLiteCpp.h>

extern char** environ;

namespace shelfcross::app::test {

namespace fs = std::filesystem;

/// Starts `args` (args[0] an absolute path) with stdout and stderr into `log` (/dev/null if empty).
inline pid_t spawn(const std::vector<std::string>& args, const std::string& log = "") {
  std::vector<char*> argv;
  for (const auto& a : args) argv.push_back(const_cast<char*>(a.c_str()));
  argv.push_back(nullptr);
  pid_t pid = 0;
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  const std::string target = log.empty() ? "/dev/null" : log;
  posix_spawn_file_actions_addopen(&actions, 1, target.c_str(), O_WRONLY | O_CREAT | O_APPEND, 0644);
  posix_spawn_file_actions_adddup2(&actions, 1, 2);
  EXPECT_EQ(posix_spawn(&pid, argv[0], &actions, nullptr, argv.data(), environ), 0);
  posix_spawn_file_actions_destroy(&actions);
  return pid;
}

/// Exit code, or 128 + signal.
inline int wait_exit(pid_t pid) {
  int status = 0;
  waitpid(pid, &status, 0);
  return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
}

/// Runs stored so far (0 while the database does not exist yet).
inline int stored_runs(const fs::path& db) {
  if (!fs::exists(db)) return 0;
  try {
    SQLite::Database d(db.string(), SQLite::OPEN_READONLY);
    d.exec("PRAGMA busy_timeout=5000");
    return d.execAndGet("SELECT COUNT(*) FROM runs").getInt();
  } catch (const std::exception&) {
    return 0;  // not created yet
  }
}

/// (run index, run hash) of every stored run, by index.
inline std::vector<std::pair<int, std::string>> stored_hashes(const fs::path& db) {
  SQLite::Database d(db.string(), SQLite::OPEN_READONLY);
  SQLite::Statement q(d, "SELECT run_index, run_hash FROM runs ORDER BY run_index");
  std::vector<std::pair<int, std::string>> out;
  while (q.executeStep()) out.emplace_back(q.getColumn(0).getInt(), q.getColumn(1).getString());
  return out;
}

/// (round, first_run, runs, estimation, proposal_json) of every stored round.
inline std::vector<std::string> stored_rounds(const fs::path& db) {
  SQLite::Database d(db.string(), SQLite::OPEN_READONLY);
  SQLite::Statement q(d, "SELECT round, first_run, runs, estimation, proposal_json FROM search_rounds ORDER BY round");
  std::vector<std::string> out;
  while (q.executeStep()) {
    out.push_back(q.getColumn(0).getString() + " " + q.getColumn(1).getString() + " " + q.getColumn(2).getString() +
                  " " + q.getColumn(3).getString() + " " + q.getColumn(4).getString());
  }
  return out;
}

/// How long a run of short_scenario lasts (cosim.timeout_s): the SDK start-up, the video stream's
/// first pictures and the takeoff command (sent at about 1.3 s), enough to differ per seed. What
/// these tests check of a campaign (resuming, shards, ranks, worker processes) needs no flight;
/// whole flights are the co-simulation's tests (verification/).
inline constexpr int kShortTimeout_s = 2;

/// The default scenario with runs cut at kShortTimeout_s. Its link is the shipped one (sdk: the
/// Tello's datagrams through tello_pilot's loop).
inline fs::path short_scenario(const fs::path& dir) {
  std::ifstream in(std::string(SHELFCROSS_SOURCE_DIR) + "/scenarios/paper_test_shelf.yaml");
  std::stringstream text;
  text << in.rdbuf();
  std::string yaml = text.str();
  const auto at = yaml.find("cosim:\n");
  yaml.insert(at + 7, "  trajectory_rate_hz: 25\n");
  const auto timeout = yaml.find("  timeout_s: 120");
  yaml.replace(timeout, 16, "  timeout_s: " + std::to_string(kShortTimeout_s));
  const fs::path path = dir / "short.yaml";
  std::ofstream(path) << yaml;
  return path;
}

/// The link model stored in every run's metrics, by index.
inline std::vector<std::string> stored_link_models(const fs::path& db) {
  SQLite::Database d(db.string(), SQLite::OPEN_READONLY);
  SQLite::Statement q(d, "SELECT metrics_json FROM runs ORDER BY run_index");
  std::vector<std::string> out;
  while (q.executeStep()) out.push_back(nlohmann::json::parse(q.getColumn(0).getString())["link"]["model"].get<std::string>());
  return out;
}

inline std::string campaign_hash(const fs::path& dir) {
  std::ifstream in(dir / "summary.json");
  return nlohmann::json::parse(in)["campaign_hash"].get<std::string>();
}

/// `shelfcross search`'s arguments (after the program) for the tests' small search of the short
/// scenario: 4 runs, rounds of 2, 2 for the estimate, the mission class (round 0 and the
/// estimation round: the fewest runs that draw from a refitted proposal).
inline std::vector<std::string> search_args(const std::string& scenario, const fs::path& out) {
  return {"search", "--scenario", scenario, "--budget", "4", "--seed", "77", "--jobs", "1",
          "--class", "mission", "--round-runs", "2", "--estimation-runs", "2", "--out", out.string()};
}

/// A whole file as text ("" if it cannot be read).
inline std::string read_text(const fs::path& path) {
  std::ifstream in(path);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

/// The processes whose parent is `parent`, from /proc/PID/stat ("pid (comm) state ppid ...";
/// comm may hold spaces, so it is read after the last ')').
inline std::vector<pid_t> children_of(pid_t parent) {
  std::vector<pid_t> out;
  for (const auto& entry : fs::directory_iterator("/proc")) {
    const std::string name = entry.path().filename().string();
    if (name.find_first_not_of("0123456789") != std::string::npos) continue;
    const std::string stat = read_text(entry.path() / "stat");
    const auto close = stat.rfind(')');
    if (close == std::string::npos) continue;
    std::istringstream rest(stat.substr(close + 1));
    std::string state;
    pid_t ppid = 0;
    rest >> state >> ppid;
    if (ppid == parent) out.push_back(static_cast<pid_t>(std::stoi(name)));
  }
  return out;
}

/// A fresh, empty folder under the temp directory, unique to this process.
inline fs::path fresh_dir(const std::string& name) {
  const fs::path root = fs::temp_directory_path() / ("shelfcross_" + name + "_" + std::to_string(getpid()));
  fs::remove_all(root);
  fs::create_directories(root);
  return root;
}

}  // namespace shelfcross::app::test
