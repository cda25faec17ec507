// `shelfcross campaign` as a user runs it: killed with SIGKILL mid-campaign and started again,
// it completes with every run present once and the campaign hash of an uninterrupted one;
// `replay` reproduces a stored run's hash; `report` writes the report.
#include <fcntl.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>

#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>
#include <SQLiteCpp/SQLiteCpp.h>

extern char** environ;

namespace {

namespace fs = std::filesystem;

pid_t spawn(const std::vector<std::string>& args) {
  std::vector<char*> argv;
  for (const auto& a : args) argv.push_back(const_cast<char*>(a.c_str()));
  argv.push_back(nullptr);
  pid_t pid = 0;
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, 1, "/dev/null", O_WRONLY, 0);
  posix_spawn_file_actions_addopen(&actions, 2, "/dev/null", O_WRONLY, 0);
  EXPECT_EQ(posix_spawn(&pid, argv[0], &actions, nullptr, argv.data(), environ), 0);
  posix_spawn_file_actions_destroy(&actions);
  return pid;
}

int wait_exit(pid_t pid) {
  int status = 0;
  waitpid(pid, &status, 0);
  return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
}

int stored_runs(const fs::path& db) {
  if (!fs::exists(db)) return 0;
  try {
    SQLite::Database d(db.string(), SQLite::OPEN_READONLY);
    d.exec("PRAGMA busy_timeout=5000");
    return d.execAndGet("SELECT COUNT(*) FROM runs").getInt();
  } catch (const std::exception&) {
    return 0;  // not created yet
  }
}

// The default scenario with runs cut at 4 s: start-up and take-off, enough to differ per seed.
fs::path short_scenario(const fs::path& dir) {
  std::ifstream in(std::string(SHELFCROSS_SOURCE_DIR) + "/scenarios/paper_test_shelf.yaml");
  std::stringstream text;
  text << in.rdbuf();
  std::string yaml = text.str();
  const auto at = yaml.find("cosim:\n");
  yaml.insert(at + 7, "  trajectory_rate_hz: 25\n");
  const auto timeout = yaml.find("  timeout_s: 120");
  yaml.replace(timeout, 16, "  timeout_s: 4");
  const fs::path path = dir / "short.yaml";
  std::ofstream(path) << yaml;
  return path;
}

std::string campaign_hash(const fs::path& dir) {
  std::ifstream in(dir / "summary.json");
  return nlohmann::json::parse(in)["campaign_hash"].get<std::string>();
}

TEST(CmdCampaign, KilledMidwayAndRestartedEqualsUninterrupted) {
  const fs::path root = fs::temp_directory_path() / "shelfcross_cmd_campaign";
  fs::remove_all(root);
  fs::create_directories(root);
  const std::string scenario = short_scenario(root).string();
  const auto command = [&](const fs::path& out) {
    return std::vector<std::string>{SHELFCROSS_PROGRAM, "campaign", "--scenario", scenario, "--runs", "4",
                                    "--seed", "77", "--jobs", "1", "--out", out.string()};
  };
  // Killed once the first run is committed (polled; the kill can land anywhere in run 2).
  const fs::path killed = root / "killed";
  const pid_t pid = spawn(command(killed));
  for (int i = 0; i < 6000 && stored_runs(killed / "results.sqlite") < 1; ++i) usleep(10000);
  ASSERT_GE(stored_runs(killed / "results.sqlite"), 1);
  kill(pid, SIGKILL);
  EXPECT_EQ(wait_exit(pid), 128 + SIGKILL);
  const int before = stored_runs(killed / "results.sqlite");
  EXPECT_LT(before, 4);
  EXPECT_EQ(wait_exit(spawn(command(killed))), 0);  // resumes
  SQLite::Database db((killed / "results.sqlite").string(), SQLite::OPEN_READONLY);
  SQLite::Statement q(db, "SELECT run_index FROM runs ORDER BY run_index");
  std::vector<int> indices;
  while (q.executeStep()) indices.push_back(q.getColumn(0).getInt());
  EXPECT_EQ(indices, (std::vector<int>{0, 1, 2, 3}));

  const fs::path whole = root / "whole";
  EXPECT_EQ(wait_exit(spawn(command(whole))), 0);
  EXPECT_EQ(campaign_hash(killed), campaign_hash(whole));
  EXPECT_EQ(campaign_hash(whole).size(), 32u);
  EXPECT_TRUE(fs::exists(whole / "report.md"));
  EXPECT_TRUE(fs::exists(whole / "top_view.png"));

  // Any run replays alone to its stored hash.
  EXPECT_EQ(wait_exit(spawn({SHELFCROSS_PROGRAM, "replay", whole.string(), "--run", "2"})), 0);
  // Bad input: another seed into the same folder is refused, not mixed.
  auto other = command(whole);
  other[7] = "78";
  EXPECT_EQ(wait_exit(spawn(other)), 2);
}

}  // namespace
