// Configuration: the shipped sample reads to the defaults; the mission layout (several shelves
// in a row) and the guidance strategy are read and checked; bad input is refused with file:line.

#include <gtest/gtest.h>

#include "config/strict_yaml.hpp"
#include "flight_sw/config.hpp"
#include "flight_sw/mission/flight_software.hpp"

namespace shelfcross::flight_sw {
namespace {

TEST(FlightConfigYaml, SampleFileReadsToTheDocumentedDefaults) {
  const FlightConfig c = load_flight_config(SHELFCROSS_SOURCE_DIR "/flight_sw/config/paper_test_shelf.yaml");
  const FlightConfig d;
  EXPECT_EQ(c.shelf.column_pitch_m, d.shelf.column_pitch_m);
  EXPECT_EQ(c.shelf.row_pitch_m, d.shelf.row_pitch_m);
  EXPECT_EQ(c.camera, d.camera);
  EXPECT_EQ(c.mount, d.mount);
  EXPECT_EQ(c.perception.tag_hsv.hue_min, d.perception.tag_hsv.hue_min);
  EXPECT_DOUBLE_EQ(c.control.psi_lateral_threshold_rad, d.control.psi_lateral_threshold_rad);
  EXPECT_DOUBLE_EQ(c.rc.rc_per_radps_yaw, d.rc.rc_per_radps_yaw);
  EXPECT_DOUBLE_EQ(c.timeouts.video_land_s, d.timeouts.video_land_s);
  EXPECT_DOUBLE_EQ(c.mission.line_hold.separation_min_m, d.mission.line_hold.separation_min_m);
  EXPECT_EQ(c.mission.line_hold.trim_drift, d.mission.line_hold.trim_drift);
  EXPECT_DOUBLE_EQ(c.mission.crossing.height_hold_range_blend, d.mission.crossing.height_hold_range_blend);
  EXPECT_DOUBLE_EQ(c.mission.crossing.height_hold_time_constant_s, d.mission.crossing.height_hold_time_constant_s);
  EXPECT_EQ(c.mission.vehicle_size_m, d.mission.vehicle_size_m);
  EXPECT_EQ(c.perception.pipeline, PerceptionPipeline::fast);
  EXPECT_EQ(c.perception.tag_seed_stride_px, d.perception.tag_seed_stride_px);
  FlightSoftware fsw(c);  // valid for the entry point
}

void expect_refused(const std::string& yaml, int line, const std::string& words) {
  try {
    parse_flight_config(yaml, "test.yaml");
    ADD_FAILURE() << "accepted: " << yaml;
  } catch (const config::ConfigError& e) {
    EXPECT_EQ(e.line(), line) << e.what();
    EXPECT_NE(std::string(e.what()).find(words), std::string::npos) << e.what();
    EXPECT_EQ(std::string(e.what()).rfind("test.yaml:", 0), 0u) << e.what();
  }
}

TEST(FlightConfigYaml, BadInputIsRefusedWithFileAndLine) {
  const std::string shelf = "shelf:\n  column_pitch_m: [0.34, 0.48]\n  row_pitch_m: [0.34]\n";
  EXPECT_NO_THROW(parse_flight_config(shelf, "test.yaml"));
  expect_refused(shelf + "  aruco_dictionary: DICT_9X9\n", 4, "unknown ArUco dictionary");
  expect_refused(shelf + "control:\n  kp_z: fast\n", 5, "kp_z");
  expect_refused(shelf + "control:\n  kp_zz: 1.0\n", 5, "kp_zz");
  expect_refused(shelf + "timeouts:\n  video_hover_s: 4.0\n", 5, "video_land_s");
  expect_refused(shelf + "perception:\n  tag_hsv: {hue_min: 200}\n", 5, "hue_min");
  expect_refused(shelf + "perception:\n  pipeline: quick\n", 5, "unknown pipeline 'quick'");
  expect_refused(shelf + "perception:\n  tag_seed_stride_px: 0\n", 5, "tag_seed_stride_px");
  expect_refused(shelf + "mission:\n  separation_min_m: 0.2\n", 5, "separation_min_m");
  expect_refused(shelf + "mission:\n  separation_min_m: -0.01\n", 5, "separation_min_m");
  expect_refused(shelf + "mission:\n  height_hold_range_blend: 1.5\n", 5, "height_hold_range_blend");
  expect_refused(shelf + "mission:\n  height_hold_time_constant_s: 0\n", 5, "height_hold_time_constant_s");
  expect_refused(shelf + "mission:\n  trim_drift: sometimes\n", 5, "trim_drift");
  EXPECT_FALSE(parse_flight_config(shelf + "mission:\n  trim_drift: false\n", "test.yaml").mission.line_hold.trim_drift);
  EXPECT_DOUBLE_EQ(parse_flight_config(shelf + "mission:\n  separation_min_m: 0.03\n", "test.yaml")
                       .mission.line_hold.separation_min_m,
                   0.03);
  EXPECT_EQ(parse_flight_config(shelf + "perception:\n  pipeline: reference\n", "test.yaml").perception.pipeline,
            PerceptionPipeline::reference);
  expect_refused("shelf:\n  column_pitch_m: [0.34, -1]\n  row_pitch_m: [0.34]\n", 2, "column_pitch_m");
  expect_refused("shelf:\n  row_pitch_m: [0.34]\n", 2, "column_pitch_m");  // the mapping's line
}

TEST(FlightConfigCode, InvalidConfigBuiltByCodeIsRefused) {
  FlightConfig c;
  c.shelf.column_pitch_m.clear();
  EXPECT_THROW(FlightSoftware{c}, std::invalid_argument);
  FlightConfig d;
  d.timeouts.video_land_s = 0.1;
  EXPECT_THROW(validate_flight_config(d), std::invalid_argument);
  FlightConfig e;
  e.mission.line_hold.separation_min_m = -0.01;
  EXPECT_THROW(validate_flight_config(e), std::invalid_argument);
  FlightConfig b;
  b.mission.crossing.height_hold_range_blend = 1.2;
  EXPECT_THROW(validate_flight_config(b), std::invalid_argument);
}

// ---- The mission layout and the guidance strategy ----

const std::string kShelf = "shelf:\n  column_pitch_m: [0.34, 0.48]\n  row_pitch_m: [0.34]\n";

TEST(StrategyConfig, DefaultsAreOneShelfThroughTheCells) {
  const FlightConfig c = parse_flight_config(kShelf, "test.yaml");
  EXPECT_EQ(c.layout.shelf_count, 1);
  EXPECT_EQ(c.strategy.mode, Strategy::through_cells);
  FlightSoftware fsw(c);
  EXPECT_EQ(fsw.inventory_json().rfind("{\"shelf\":0,", 0), 0u);  // one shelf: the single-shelf JSON
}

TEST(StrategyConfig, LayoutAndStrategyRead) {
  const FlightConfig c = parse_flight_config(
      kShelf + "layout: {shelf_count: 5, shelf_spacing_m: 4.2}\n"
               "strategy: {mode: around_ends, end_clearance_m: 0.6, transfer_speed_mps: 0.3}\n",
      "test.yaml");
  EXPECT_EQ(c.layout.shelf_count, 5);
  EXPECT_DOUBLE_EQ(c.layout.shelf_spacing_m, 4.2);
  EXPECT_EQ(c.strategy.mode, Strategy::around_ends);
  EXPECT_DOUBLE_EQ(c.strategy.end_clearance_m, 0.6);
  EXPECT_DOUBLE_EQ(c.strategy.transfer_speed_mps, 0.3);
  FlightSoftware fsw(c);
  EXPECT_EQ(fsw.inventory_json(), "{\"shelves\":[" + fsw.inventory().to_json() + "]}");
  EXPECT_EQ(fsw.shelf_index(), 0);
  EXPECT_TRUE(fsw.all_boxes().empty());
}

TEST(StrategyConfig, NamesRoundTrip) {
  for (Strategy s : {Strategy::through_cells, Strategy::over_tops, Strategy::around_ends}) {
    EXPECT_EQ(parse_strategy(strategy_name(s)), s);
  }
  EXPECT_FALSE(parse_strategy("sideways").has_value());
}

TEST(StrategyConfig, BadInputRefusedWithLine) {
  expect_refused(kShelf + "strategy:\n  mode: sideways\n", 5, "unknown strategy");
  expect_refused(kShelf + "layout:\n  shelf_count: 0\n", 5, "shelf_count");
  expect_refused(kShelf + "layout:\n  shelf_count: 3\n", 5, "shelf_spacing_m");
  expect_refused(kShelf + "layout:\n  shelf_count: 3\n  shelf_spacing_m: 0.3\n", 1, "shelf_spacing_m");  // <= depth
  expect_refused(kShelf + "strategy:\n  transfer_speed_mps: -1\n", 5, "transfer_speed_mps");
  expect_refused(kShelf + "layout:\n  shelf_count: 2\n  shelf_spacing_m: 3\n  spacing: 3\n", 7, "spacing");
}

}  // namespace
}  // namespace shelfcross::flight_sw
