// The strategy comparison's table: means over successful runs, recall over every run, the
// success rate's Clopper-Pearson bound, the paper's numbers beside them.
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "verification/cosim/run_metrics_json.hpp"
#include "verification/report/compare.hpp"
#include "verification/statistics/statistics.hpp"

namespace shelfcross::verification {
namespace {

RunRecord record(std::int64_t index, const std::string& outcome, double distance_m, double time_s, double recall) {
  RunRecord r;
  r.index = index;
  r.outcome = outcome;
  RunMetrics m;
  m.truth.path_length_m = distance_m;
  m.mission_time_s = time_s;
  m.inventory.recall = recall;
  r.metrics_json = stored_metrics_json({m, "", std::nullopt});
  return r;
}

TEST(CompareTable, RowFromRuns) {
  const std::vector<RunRecord> runs{record(0, "success", 20.0, 80.0, 1.0), record(1, "success", 24.0, 90.0, 1.0),
                                    record(2, "collision", 3.0, 10.0, 0.25), record(3, "success", 99.0, 99.0, 1.0)};
  const StrategyRow row = summarize_strategy("over_tops", runs, 3);  // run 3 is beyond the request
  EXPECT_EQ(row.runs, 3);
  EXPECT_EQ(row.successes, 2);
  EXPECT_DOUBLE_EQ(row.success_rate, 2.0 / 3.0);
  EXPECT_DOUBLE_EQ(row.success_lower_95, clopper_pearson_lower(2, 3, 0.95));
  EXPECT_DOUBLE_EQ(*row.mean_distance_m, 22.0);
  EXPECT_DOUBLE_EQ(*row.mean_time_s, 85.0);
  EXPECT_DOUBLE_EQ(*row.mean_recall, 0.75);
  EXPECT_EQ(row.paper_distance_m, 22.0);
  EXPECT_EQ(row.paper_time_s, 300.0);
  const std::string md = comparison_table_markdown({row});
  EXPECT_NE(md.find("| over the shelf tops | 3 | 22.00 | 22 | 85.0 | 300 | 2/3 = 0.667 |"), std::string::npos) << md;
  EXPECT_THROW(summarize_strategy("sideways", runs, 3), std::invalid_argument);
  // Safety apart from success: run 2's collision is a contact, with its upper bound (the 0.95
  // quantile of Beta(2, 2), 3 p^2 - 2 p^3 = 0.95: p = 0.86465).
  EXPECT_EQ(row.contacts, 1);
  EXPECT_DOUBLE_EQ(row.contact_upper_95, clopper_pearson_upper(1, 3, 0.95));
  EXPECT_EQ(row.safe_aborts, 0);
  EXPECT_NE(md.find(" | 1 | 0.8646 | 0 | 0 | 0.7500 |"), std::string::npos) << md;
}

TEST(CompareTable, NoSuccessLeavesMeansEmpty) {
  const StrategyRow row = summarize_strategy("around_ends", {record(0, "timeout", 5.0, 900.0, 0.0)}, 1);
  EXPECT_FALSE(row.mean_distance_m.has_value());
  EXPECT_EQ(row.success_lower_95, 0.0);
  EXPECT_NE(comparison_table_markdown({row}).find("| around the shelf sides | 1 | - | 28 | - | 360 | 0/1"), std::string::npos);
  EXPECT_EQ(compared_strategies().size(), 3u);
}

TEST(CompareRunByRun, CountsTheRunsTheMethodWasShortestAndFastestOnTheRunsAllFinished) {
  // Five runs. Run 2: over the tops faster; run 3: around the ends fails (not counted in the
  // three-way share, counted against over the tops); run 4: around the ends as fast (a tie is
  // not a win).
  const std::vector<RunRecord> cells{record(0, "success", 20.0, 80.0, 1.0), record(1, "success", 21.0, 85.0, 1.0),
                                     record(2, "success", 22.0, 99.0, 1.0), record(3, "success", 20.0, 82.0, 1.0),
                                     record(4, "success", 20.0, 90.0, 1.0)};
  const std::vector<RunRecord> tops{record(0, "success", 30.0, 95.0, 1.0), record(1, "success", 31.0, 97.0, 1.0),
                                    record(2, "success", 30.0, 92.0, 1.0), record(3, "success", 30.0, 96.0, 1.0),
                                    record(4, "success", 30.0, 100.0, 1.0)};
  const std::vector<RunRecord> ends{record(0, "success", 35.0, 100.0, 1.0), record(1, "success", 36.0, 101.0, 1.0),
                                    record(2, "success", 35.0, 104.0, 1.0), record(3, "timeout", 9.0, 120.0, 0.5),
                                    record(4, "success", 35.0, 90.0, 1.0)};
  const RunByRun r = compare_run_by_run(compared_strategies(), {cells, tops, ends}, 5);
  EXPECT_EQ(r.first, "through_cells");
  EXPECT_EQ(r.runs, 4);  // 0, 1, 2, 4
  EXPECT_EQ(r.shortest, 4);
  EXPECT_EQ(r.fastest, 2);
  EXPECT_EQ(r.not_fastest, (std::vector<std::int64_t>{2, 4}));
  EXPECT_DOUBLE_EQ(r.fastest_lower_95, clopper_pearson_lower(2, 4, 0.95));
  ASSERT_EQ(r.against.size(), 2u);
  EXPECT_EQ(r.against[0].strategy, "over_tops");
  EXPECT_EQ(r.against[0].pairs, 5);
  EXPECT_EQ(r.against[0].faster, 4);
  EXPECT_EQ(r.against[0].shorter, 5);
  // Over the tops - through the cells: +15, +12, -7, +14, +10 s; the 15 Walsh averages' median
  // (the 8th of -7, 1.5, 2.5, 3.5, 4, 10, 11, 12, 12, 12.5, ...) is 12.
  EXPECT_DOUBLE_EQ(r.against[0].time_s.median, 12.0);
  EXPECT_DOUBLE_EQ(r.against[0].time_s.hodges_lehmann, 12.0);
  EXPECT_EQ(r.against[1].pairs, 4);
  EXPECT_EQ(r.against[1].faster, 3);
  const std::string md = run_by_run_markdown(r);
  EXPECT_NE(md.find("the shortest in 4 of 4 (100.0 %"), std::string::npos) << md;
  EXPECT_NE(md.find("the fastest in 2 of 4 (50.0 %"), std::string::npos) << md;
  EXPECT_NE(md.find("| over_tops | 5 | 5 | 4 | 12.0 s |"), std::string::npos) << md;
  EXPECT_NE(md.find("was not the fastest (replay them in `through_cells/`): 2 4."), std::string::npos) << md;
  // Nothing flown by all: no section; one strategy alone is no comparison.
  EXPECT_EQ(run_by_run_markdown(compare_run_by_run(compared_strategies(), {cells, tops, {}}, 5)), "");
  EXPECT_THROW(compare_run_by_run({"through_cells"}, {cells}, 5), std::invalid_argument);
}

}  // namespace
}  // namespace shelfcross::verification
