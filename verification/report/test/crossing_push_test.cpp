// The crossing's push from a stored trace: the pass that crossed, measured against the cell's
// centre line where the vehicle is within the shelf's depth; the room to the posts; the trace
// read back as campaign.cpp wrote it, and refused, naming the run, when it does not read.
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <string>

#include <gtest/gtest.h>

#include "verification/campaign/campaign.hpp"
#include "verification/campaign/stored_run.hpp"
#include "verification/report/crossing_push.hpp"
#include "verification/report/report.hpp"
#include "verification/report/test/paired_campaigns_fixture.hpp"

namespace shelfcross::verification {
namespace {

StoredMetrics crossed_cell(int level, int column) {
  RunMetrics m;
  m.truth.crossed = CellIndex{level, column};
  return {m, "", std::nullopt};
}

RunRecord stored(const RunResult& result) {
  RunRecord r;
  r.index = 7;
  r.trace_json = trace_json(result);
  return r;
}

TEST(StoredTrace, ReadsBackWhatTheCampaignWrote) {
  const Scenario s = test::fixture_scenario();
  const RunResult result = test::crossing_trajectory(s, [](double x_S) { return 0.01 * x_S; });
  const StoredTrace t = stored_trace(stored(result));
  ASSERT_EQ(t.t_s.size(), result.trajectory.size());
  for (std::size_t k = 0; k < t.t_s.size(); ++k) {
    EXPECT_NEAR(t.t_s[k], result.trajectory[k].t_s, 5e-4);  // stored to 1 ms and 1 mm
    EXPECT_NEAR(t.x_W_m[k], result.trajectory[k].p_WB_m.x(), 5e-4);
    EXPECT_NEAR(t.y_W_m[k], result.trajectory[k].p_WB_m.y(), 5e-4);
    EXPECT_NEAR(t.z_W_m[k], result.trajectory[k].p_WB_m.z(), 5e-4);
  }
  EXPECT_EQ(t.approach_start_s, 2.0);
  EXPECT_EQ(t.cross_start_s, 13.0);

  RunRecord r;
  r.index = 7;
  r.trace_json = "{}";  // a worker that crashed stored no trajectory
  EXPECT_TRUE(stored_trace(r).t_s.empty());
  r.trace_json = R"({"t":[0,0.1],"x":[1,null],"y":[0,0],"z":[1,1],"yaw":[0,0]})";  // a diverged run's NaN
  EXPECT_TRUE(std::isnan(stored_trace(r).x_W_m[1]));
  const auto error_of = [&r] {
    try {
      stored_trace(r);
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  r.trace_json = R"({"t":[0,0.1],"x":[1,1],"z":[1,1],"yaw":[0,0]})";
  EXPECT_EQ(error_of(), "stored run 7: trace_json has no array \"y\"");
  r.trace_json = R"({"t":[0,0.1],"x":[1],"y":[0,0],"z":[1,1],"yaw":[0,0]})";
  EXPECT_EQ(error_of(), "stored run 7: trace_json \"x\" has a different length from \"t\"");
  r.trace_json = "[";
  EXPECT_EQ(error_of(), "stored run 7: trace_json is not an object");
}

TEST(CrossingPush, IsTheLargestOffsetInsideTheShelfsDepthOfThePassThatCrossed) {
  const Scenario s = test::fixture_scenario();
  const double depth_m = s.warehouse.shelves.front().depth_m;
  const double half_length_m = 0.5 * s.vehicle.size_m.x();
  // 2 cm off the line before the shelf, drifting from 0 at the front face to 5 cm at the back
  // face, 12 cm after it: only the part within the depth (+- half the vehicle's length) counts.
  const RunResult drift = test::crossing_trajectory(s, [&](double x_S) {
    if (x_S < -half_length_m - 0.01) return 0.02;
    if (x_S > depth_m + half_length_m + 0.01) return 0.12;
    return 0.05 * std::clamp(x_S / depth_m, 0.0, 1.0);
  });
  const std::optional<double> push = crossing_push_m(s, crossed_cell(2, 3), stored_trace(stored(drift)));
  ASSERT_TRUE(push.has_value());
  EXPECT_NEAR(*push, 0.05, 1e-3);
  // To the right of the line it is the same distance.
  const RunResult right = test::crossing_trajectory(s, [](double x_S) { return x_S > 0.0 && x_S < 0.3 ? -0.04 : 0.0; });
  EXPECT_NEAR(crossing_push_m(s, crossed_cell(2, 3), stored_trace(stored(right))).value(), 0.04, 1e-3);
  // No crossing of shelf 0, no push.
  EXPECT_FALSE(crossing_push_m(s, StoredMetrics{RunMetrics{}, "", std::nullopt}, stored_trace(stored(drift))));
  EXPECT_FALSE(crossing_push_m(s, StoredMetrics{std::nullopt, "worker died", 11}, stored_trace(stored(drift))));
}

TEST(CrossingPush, APassStoppedAtTheFrontFaceIsNotTheCrossing) {
  const Scenario s = test::fixture_scenario();
  const RunResult crossing = test::crossing_trajectory(s, [](double) { return 0.03; });
  RunResult stopped_then_crossed = test::crossing_trajectory(s, [](double) { return 0.09; });
  // First a pass 9 cm off the line that reaches 5 cm into the shelf and backs out to 0.5 m
  // before it, then the crossing 3 cm off the line.
  std::vector<TrajectorySample> stopped;
  for (const TrajectorySample& p : stopped_then_crossed.trajectory) {
    const Eigen::Vector3d p_S = shelf_pose_W(s.warehouse.shelves.front()).inverse() * p.p_WB_m;
    if (p_S.x() > 0.05) break;
    stopped.push_back(p);
  }
  for (auto it = stopped.rbegin(); it != stopped.rend(); ++it) {
    const Eigen::Vector3d p_S = shelf_pose_W(s.warehouse.shelves.front()).inverse() * it->p_WB_m;
    if (p_S.x() < -0.5) break;
    stopped.push_back(*it);
  }
  for (std::size_t k = 0; k < stopped.size(); ++k) stopped[k].t_s = 0.1 * static_cast<double>(k);
  for (TrajectorySample p : crossing.trajectory) {
    p.t_s += stopped.back().t_s;
    stopped.push_back(p);
  }
  RunResult both;
  both.trajectory = stopped;
  EXPECT_NEAR(crossing_push_m(s, crossed_cell(2, 3), stored_trace(stored(both))).value(), 0.03, 1e-3);
  // A trace that never reaches mid-depth has no crossing to measure, whatever the metrics say.
  RunResult only_stopped;
  only_stopped.trajectory.assign(stopped.begin(), stopped.end() - static_cast<std::ptrdiff_t>(crossing.trajectory.size()));
  EXPECT_FALSE(crossing_push_m(s, crossed_cell(2, 3), stored_trace(stored(only_stopped))));
}

TEST(CrossingPush, TheRoomIsHalfTheColumnLessHalfAPostAndHalfTheVehicle) {
  const Scenario s = test::fixture_scenario();  // columns 34, 48, 34, 48 cm; posts 2 cm; vehicle 9.25 cm wide
  EXPECT_NEAR(crossing_room_m(s, 1), 0.17 - 0.01 - 0.04625, 1e-12);
  EXPECT_NEAR(crossing_room_m(s, 2), 0.24 - 0.01 - 0.04625, 1e-12);
  EXPECT_NEAR(crossing_room_m(s, 3), 0.17 - 0.01 - 0.04625, 1e-12);
}

TEST(CrossingPush, TheCampaignReportSetsThePushAgainstTheRoom) {
  const std::filesystem::path dir = std::filesystem::temp_directory_path() / "shelfcross_crossing_push_report";
  std::filesystem::remove_all(dir);
  // 20 runs through the 34 cm column 3, pushed 1.0 to 2.9 cm; run 13 aborts (no crossing).
  test::write_planned_campaign(dir / "results.sqlite", test::fixture_scenario(), 1, 20, [](std::int64_t k) {
    test::PlannedRun p;
    p.push_m = 0.010 + 0.001 * static_cast<double>(k);
    if (k == 13) p.outcome = "mission_aborted";
    return p;
  });
  write_campaign_report(dir);
  std::ifstream in(dir / "report.md");
  std::stringstream text;
  text << in.rdbuf();
  // 19 crossings, mean (39.0 - 2.3) / 19 = 1.93 cm; the largest, run 19's.
  EXPECT_NE(text.str().find("| 34 cm | 11.4 cm | 19 | 1.9 cm |"), std::string::npos) << text.str();
  EXPECT_NE(text.str().find("| 2.9 cm | 19 |"), std::string::npos);
  EXPECT_TRUE(std::filesystem::exists(dir / "crossing_push.png"));
}

}  // namespace
}  // namespace shelfcross::verification
