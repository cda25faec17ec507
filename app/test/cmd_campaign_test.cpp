// `shelfcross campaign` as a user runs it: killed with SIGKILL mid-campaign and started again,
// it completes with every run present once and the campaign hash of an uninterrupted one;
// `replay` reproduces a stored run's hash; `report` writes the report; shards of a campaign
// (`--shard I/N`) merged with `merge` equal the campaign run by one process.
#include <set>

#include "campaign_helpers.hpp"

namespace {

using namespace shelfcross::app::test;

TEST(CmdCampaign, KilledMidwayAndRestartedEqualsUninterrupted) {
  const fs::path root = fresh_dir("cmd_campaign");
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

TEST(CmdCampaign, ShardsMergedEqualOneProcess) {
  const fs::path root = fresh_dir("cmd_campaign_shards");
  const std::string scenario = short_scenario(root).string();
  const auto command = [&](const fs::path& out, const std::string& shard) {
    std::vector<std::string> c{SHELFCROSS_PROGRAM, "campaign", "--scenario", scenario, "--runs", "4",
                               "--seed",           "31",       "--jobs",     "1",      "--out",  out.string()};
    if (!shard.empty()) c.insert(c.end(), {"--shard", shard});
    return c;
  };
  EXPECT_EQ(wait_exit(spawn(command(root / "whole", ""))), 0);
  // Shard 0/2 holds runs 0, 2 and shard 1/2 runs 1, 3: disjoint, together all.
  EXPECT_EQ(wait_exit(spawn(command(root / "s0", "0/2"))), 0);
  EXPECT_EQ(wait_exit(spawn(command(root / "s1", "1/2"))), 0);
  const auto indices = [](const fs::path& db) {
    std::vector<int> out;
    for (const auto& [index, hash] : stored_hashes(db)) out.push_back(index);
    return out;
  };
  EXPECT_EQ(indices(root / "s0" / "results.sqlite"), (std::vector<int>{0, 2}));
  EXPECT_EQ(indices(root / "s1" / "results.sqlite"), (std::vector<int>{1, 3}));
  EXPECT_EQ(campaign_hash(root / "s0"), "");  // a shard alone is not the campaign
  EXPECT_NE(read_text(root / "s0" / "report.md").find("Campaign hash: once every run is stored."), std::string::npos);
  EXPECT_NE(read_text(root / "whole" / "report.md").find("Campaign hash `" + campaign_hash(root / "whole") + "`."),
            std::string::npos);

  // Merging the first shard only: incomplete; then the second too (the first again is harmless).
  const std::string merged = (root / "merged").string();
  EXPECT_EQ(wait_exit(spawn({SHELFCROSS_PROGRAM, "merge", (root / "s0").string(), "--out", merged})), 0);
  EXPECT_EQ(campaign_hash(merged), "");
  EXPECT_EQ(wait_exit(spawn({SHELFCROSS_PROGRAM, "merge", (root / "s0").string(), (root / "s1").string(), "--out",
                             merged})),
            0);
  EXPECT_EQ(stored_hashes(fs::path(merged) / "results.sqlite"), stored_hashes(root / "whole" / "results.sqlite"));
  EXPECT_EQ(campaign_hash(merged), campaign_hash(root / "whole"));
  EXPECT_EQ(campaign_hash(merged).size(), 32u);
  EXPECT_TRUE(fs::exists(fs::path(merged) / "report.md"));

  // Bad input exits 2: a malformed shard, a shard number out of range, a missing source, and a
  // shard of another campaign (other seed).
  EXPECT_EQ(wait_exit(spawn(command(root / "bad", "2/2"))), 2);
  EXPECT_EQ(wait_exit(spawn(command(root / "bad", "one/2"))), 2);
  EXPECT_EQ(wait_exit(spawn({SHELFCROSS_PROGRAM, "merge", (root / "nowhere").string(), "--out", merged})), 2);
  auto other = command(root / "other", "1/2");
  other[5] = "1";  // runs 1, shard 1/2: no run, only the campaign's database (seed 32)
  other[7] = "32";
  EXPECT_EQ(wait_exit(spawn(other)), 0);
  EXPECT_EQ(wait_exit(spawn({SHELFCROSS_PROGRAM, "merge", (root / "s0").string(), (root / "other").string(), "--out",
                             (root / "mixed").string()})),
            2);
}

}  // namespace
