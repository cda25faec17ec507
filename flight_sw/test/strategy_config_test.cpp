// The mission layout (several shelves in a row) and the guidance strategy: read from YAML,
// checked, refused with file:line when wrong.

#include <gtest/gtest.h>

#include "config/strict_yaml.hpp"
#include "flight_sw/config.hpp"
#include "flight_sw/flight_software.hpp"

namespace shelfcross::flight_sw {
namespace {

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

void expect_refused(const std::string& yaml, int line, const std::string& words) {
  try {
    parse_flight_config(yaml, "test.yaml");
    ADD_FAILURE() << "accepted: " << yaml;
  } catch (const config::ConfigError& e) {
    EXPECT_EQ(e.line(), line) << e.what();
    EXPECT_NE(std::string(e.what()).find(words), std::string::npos) << e.what();
  }
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
