// `shelfcross search` as a user runs it, on the short scenario (4 s runs, all of which time
// out: the mission class fails in every run, so the search stops adapting after round 0):
// round 0 repeats the campaign of the same seed run for run; killed and restarted, the search
// ends with the runs and rounds of an uninterrupted one; a run of a later round replays to its
// stored hash; bad input exits with 2.
#include "campaign_helpers.hpp"

namespace {

using namespace shelfcross::app::test;

std::vector<std::string> search_command(const std::string& scenario, const fs::path& out) {
  std::vector<std::string> c{SHELFCROSS_PROGRAM};
  const std::vector<std::string> args = search_args(scenario, out);
  c.insert(c.end(), args.begin(), args.end());
  return c;
}

TEST(CmdSearch, ResumesToTheUninterruptedSearchAndRepeatsTheCampaignInRoundZero) {
  const fs::path root = fresh_dir("cmd_search");
  const std::string scenario = short_scenario(root).string();

  const fs::path whole = root / "whole";
  ASSERT_EQ(wait_exit(spawn(search_command(scenario, whole), (root / "whole.log").string())), 0);
  const auto hashes = stored_hashes(whole / "results.sqlite");
  ASSERT_EQ(hashes.size(), 4u);
  // Every run times out: mission margin -1 in round 0, so the level is 0 at once and the rest
  // of the budget (2 runs) is drawn from the refitted proposal for the estimate.
  const auto rounds = stored_rounds(whole / "results.sqlite");
  ASSERT_EQ(rounds.size(), 2u);
  EXPECT_EQ(rounds[1].substr(0, 8), "1 2 2 1 ");
  EXPECT_TRUE(fs::exists(whole / "report.md"));
  EXPECT_TRUE(fs::exists(whole / "search_progress.png"));
  EXPECT_TRUE(fs::exists(whole / "search_margin_start_distance_m.png"));
  std::ifstream summary_in(whole / "search_summary.json");
  const nlohmann::json summary = nlohmann::json::parse(summary_in);
  // Every run fails the mission: the estimate comes from the 2 estimation runs of round 1, all
  // failures (its value is the mean of their weights f / q, an unbiased estimate of 1).
  EXPECT_EQ(summary["estimates"]["mission"]["round"], 1);
  EXPECT_EQ(summary["estimates"]["mission"]["runs"], 2);
  EXPECT_EQ(summary["estimates"]["mission"]["failures"], 2);
  EXPECT_GT(summary["estimates"]["mission"]["p_hat"].get<double>(), 0.0);
  EXPECT_EQ(summary["failures"].size(), 4u);

  // Round 0 draws from the nominal dispersions: the campaign of the same seed, run for run.
  const fs::path campaign = root / "campaign";
  ASSERT_EQ(wait_exit(spawn({SHELFCROSS_PROGRAM, "campaign", "--scenario", scenario, "--runs", "2", "--seed", "77",
                             "--jobs", "1", "--out", campaign.string()})),
            0);
  const auto campaign_hashes = stored_hashes(campaign / "results.sqlite");
  ASSERT_EQ(campaign_hashes.size(), 2u);
  EXPECT_EQ(campaign_hashes[0], hashes[0]);
  EXPECT_EQ(campaign_hashes[1], hashes[1]);

  // Killed after its first run, and started again: the same runs and rounds.
  const fs::path killed = root / "killed";
  const pid_t pid = spawn(search_command(scenario, killed));
  for (int i = 0; i < 6000 && stored_runs(killed / "results.sqlite") < 1; ++i) usleep(10000);
  ASSERT_GE(stored_runs(killed / "results.sqlite"), 1);
  kill(pid, SIGKILL);
  EXPECT_EQ(wait_exit(pid), 128 + SIGKILL);
  EXPECT_LT(stored_runs(killed / "results.sqlite"), 4);
  EXPECT_EQ(wait_exit(spawn(search_command(scenario, killed))), 0);
  EXPECT_EQ(stored_hashes(killed / "results.sqlite"), hashes);
  EXPECT_EQ(stored_rounds(killed / "results.sqlite"), rounds);

  // A run of the estimation round (drawn from a proposal) replays to its stored hash.
  EXPECT_EQ(wait_exit(spawn({SHELFCROSS_PROGRAM, "replay", whole.string(), "--run", "3"})), 0);
  // The plain Monte Carlo column from the campaign of the same scenario.
  auto with_campaign = search_command(scenario, whole);
  with_campaign.insert(with_campaign.end(), {"--campaign", campaign.string()});
  EXPECT_EQ(wait_exit(spawn(with_campaign)), 0);
  std::ifstream again(whole / "search_summary.json");
  EXPECT_EQ(nlohmann::json::parse(again)["estimates"]["mission"]["plain_monte_carlo"]["failures"], 2);
}

TEST(CmdSearch, RefusesBadInput) {
  const fs::path root = fresh_dir("cmd_search_bad");
  const std::string scenario = short_scenario(root).string();
  const auto with = [&](const std::string& option, const std::string& value) {
    auto c = search_command(scenario, root / "out");
    for (size_t i = 0; i + 1 < c.size(); ++i) {
      if (c[i] == option) {
        c[i + 1] = value;
        return c;
      }
    }
    c.insert(c.end(), {option, value});
    return c;
  };
  EXPECT_EQ(wait_exit(spawn(with("--class", "speed"))), 2);
  EXPECT_EQ(wait_exit(spawn(with("--budget", "0"))), 2);
  EXPECT_EQ(wait_exit(spawn(with("--budget", "lots"))), 2);
  EXPECT_EQ(wait_exit(spawn(with("--estimation-runs", "7"))), 2);  // more than the budget
  EXPECT_EQ(wait_exit(spawn(with("--elite-fraction", "0.9"))), 2);
  EXPECT_EQ(wait_exit(spawn(with("--min-elites", "0"))), 2);
  EXPECT_EQ(wait_exit(spawn(with("--smoothing", "0"))), 2);
  EXPECT_EQ(wait_exit(spawn(with("--smoothing", "1.5"))), 2);
  EXPECT_EQ(wait_exit(spawn(with("--min-stddev-fraction", "0"))), 2);
  EXPECT_EQ(wait_exit(spawn(with("--nominal-share", "-0.1"))), 2);
  EXPECT_EQ(wait_exit(spawn(with("--parameter-share", "1.5"))), 2);
  auto no_defence = with("--nominal-share", "0");  // and no per-parameter share: weights unbounded
  no_defence.insert(no_defence.end(), {"--parameter-share", "0"});
  EXPECT_EQ(wait_exit(spawn(no_defence)), 2);
  EXPECT_EQ(wait_exit(spawn(with("--campaign", (root / "nowhere").string()))), 2);
  EXPECT_EQ(wait_exit(spawn(with("--parameters", "start_distance_m,not_a_parameter"))), 2);
  EXPECT_EQ(wait_exit(spawn({SHELFCROSS_PROGRAM, "search", "--scenario", scenario, "--frobnicate"})), 2);
  EXPECT_FALSE(fs::exists(root / "out" / "results.sqlite"));
}

}  // namespace
