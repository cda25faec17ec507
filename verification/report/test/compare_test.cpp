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

}  // namespace
}  // namespace shelfcross::verification
