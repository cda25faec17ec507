// `shelfcross compare` as a user runs it: three campaigns (one per strategy) with the same
// seed, the Table 2 markdown and JSON, and the path plots; bad input exits 2. The runs are
// cut short (campaign_helpers.hpp's short scenario): the command's plumbing is under test here;
// the strategies' flights are tested in verification/report/test/warehouse_test.cpp.
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <sstream>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>
#include <SQLiteCpp/SQLiteCpp.h>

#include "campaign_helpers.hpp"
#include "run_shelfcross.hpp"

namespace {

namespace fs = std::filesystem;
using shelfcross::app::test::run_shelfcross;
using shelfcross::app::test::short_scenario;

TEST(CompareCommand, WritesTableAndPlotsForThreeStrategiesWithTheSameDraws) {
  const fs::path dir = fs::temp_directory_path() / ("shelfcross_compare_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  const fs::path scenario = short_scenario(dir);

  const auto r = run_shelfcross("compare", "--scenario " + scenario.string() + " --runs 2 --seed 5 --jobs 2 --out " +
                                               (dir / "out").string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const nlohmann::json j = nlohmann::json::parse(std::ifstream(dir / "out" / "compare.json"));
  ASSERT_EQ(j["rows"].size(), 3u);
  EXPECT_EQ(j["rows"][0]["strategy"], "through_cells");
  EXPECT_EQ(j["rows"][1]["strategy"], "over_tops");
  EXPECT_EQ(j["rows"][2]["strategy"], "around_ends");
  EXPECT_EQ(j["rows"][1]["paper_distance_m"], 22.0);
  EXPECT_TRUE(j["complete"].get<bool>());
  for (const auto& row : j["rows"]) {
    EXPECT_EQ(row["runs"], 2);
    EXPECT_EQ(row["successes"], 0);  // cut short: every run a timeout
    EXPECT_EQ(row["success_lower_95"], 0.0);
  }
  // Same campaign seed: the same dispersion draws run by run in every strategy's store.
  std::vector<std::string> draws;
  for (int k = 0; k < 3; ++k) {
    const std::string s = j["rows"][k]["strategy"];
    ASSERT_TRUE(fs::exists(dir / "out" / s / "results.sqlite"));
    SQLite::Database db((dir / "out" / s / "results.sqlite").string(), SQLite::OPEN_READONLY);
    SQLite::Statement q(db, "SELECT dispersion_json FROM runs ORDER BY run_index");
    std::string all;
    while (q.executeStep()) all += q.getColumn(0).getString() + "\n";
    draws.push_back(all);
    EXPECT_TRUE(fs::exists(dir / "out" / s / "report.md"));
    std::ifstream summary(dir / "out" / s / "summary.json");
    EXPECT_TRUE(summary.good());
  }
  EXPECT_FALSE(draws[0].empty());
  EXPECT_EQ(draws[0], draws[1]);
  EXPECT_EQ(draws[0], draws[2]);
  std::stringstream md;
  md << std::ifstream(dir / "out" / "compare.md").rdbuf();
  EXPECT_NE(md.str().find("| over the shelf tops | 2 |"), std::string::npos) << md.str();
  // Run by run needs runs every strategy finished: none here, so no section and no share.
  EXPECT_EQ(j["run_by_run"]["runs"], 0);
  EXPECT_EQ(j["run_by_run"]["against"].size(), 2u);
  EXPECT_EQ(md.str().find("## Run by run"), std::string::npos);
  EXPECT_TRUE(fs::exists(dir / "out" / "compare_top_view.png"));
  EXPECT_TRUE(fs::exists(dir / "out" / "compare_side_view.png"));
  // Run again: nothing missing, nothing re-run, same table.
  const auto again = run_shelfcross("compare", "--scenario " + scenario.string() +
                                                   " --runs 2 --seed 5 --jobs 1 --out " + (dir / "out").string());
  EXPECT_EQ(again.exit_code, 0) << again.output;
  fs::remove_all(dir);
}

TEST(CompareCommand, BadScenarioExitsTwo) {
  const auto r = run_shelfcross("compare", "--scenario /nonexistent/x.yaml --runs 1 --out /tmp/unused_compare");
  EXPECT_EQ(r.exit_code, 2) << r.output;
}

}  // namespace
