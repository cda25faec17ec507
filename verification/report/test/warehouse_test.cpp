// The five-shelf warehouse (scenarios/warehouse_5_shelves.yaml, paper Table 2): the scenario is
// a row the co-simulation recognises, and each guidance strategy of the flight software
// inventories the shelves of a row without contact; through the cells is the shortest path,
// over the tops the next, around the ends the longest. A five-shelf flight is minutes of
// simulated time with a rendered camera (about 33 s of one core over the sdk link), so the
// strategies are compared on the row's first kRowShelves shelves (a row all the same: a transfer
// from shelf to shelf and a landing past the last), one test per link so that CTest runs them
// side by side, and the whole row of five is flown once, by the flight software's own strategy,
// over the ideal link.
#include <array>
#include <cstdint>
#include <iostream>
#include <string>

#include <gtest/gtest.h>

#include "verification/campaign/campaign.hpp"
#include "verification/cosim/cosim.hpp"
#include "verification/report/compare.hpp"
#include "verification/scenario/senses_dispersion.hpp"

namespace shelfcross::verification {
namespace {

const std::string kWarehouse = std::string(SHELFCROSS_SOURCE_DIR) + "/scenarios/warehouse_5_shelves.yaml";

TEST(Warehouse, FiveShelfScenarioIsARowWithRoomForEveryStrategy) {
  const Scenario s = load_scenario(kWarehouse);
  ASSERT_EQ(s.warehouse.shelves.size(), 5u);
  EXPECT_EQ(mission_shelf_count(s), 5);
  EXPECT_NEAR(mission_shelf_spacing_m(s), 4.20, 1e-12);
  const flight_sw::FlightConfig c = flight_config_for(s, s.camera);
  EXPECT_EQ(c.layout.shelf_count, 5);
  EXPECT_EQ(c.strategy.mode, flight_sw::Strategy::through_cells);
  // At least one empty cell per shelf; the true inventory lists every box with its shelf.
  std::size_t boxes = 0;
  for (const ShelfSpec& shelf : s.warehouse.shelves) {
    EXPECT_LT(shelf.boxes.size(), shelf.column_pitch_m.size() * shelf.row_pitch_m.size()) << shelf.name;
    boxes += shelf.boxes.size();
  }
  EXPECT_EQ(true_inventory(s).size(), boxes);
  // Room for the conventional strategies: headroom over the shelf tops (cruise at top + 0.4 m
  // clearance + the vehicle) and floor beside the shelf ends (0.85 m half width + 0.5 m
  // clearance + the vehicle), with 0.4 m to spare.
  const ShelfSpec& s0 = s.warehouse.shelves[0];
  const double top = beam_z_S_m(s0, 4) + 0.5 * s.warehouse.tag_size_m;
  EXPECT_GT(s.warehouse.arena_max_W_m.z() - (top + c.strategy.top_clearance_m + s.vehicle.size_m.z()), 0.4);
  const double end = post_y_S_m(s0, 0) + 0.5 * s.warehouse.tag_size_m + c.strategy.end_clearance_m + s.vehicle.size_m.x();
  EXPECT_GT(s.warehouse.arena_max_W_m.y() - end, 0.4);
  EXPECT_GT(-s.warehouse.arena_min_W_m.y() - end, 0.4);
  // Beyond the last shelf: the landing spot past its back face.
  const ShelfSpec& s4 = s.warehouse.shelves[4];
  EXPECT_GT(s.warehouse.arena_max_W_m.x() - (s4.origin_W_m.x() + s4.depth_m + 0.6), 1.0);
  EXPECT_TRUE(s.start.landed);
  // A row broken (one shelf moved sideways) is not a row: the mission is shelf 0 alone.
  Scenario broken = s;
  broken.warehouse.shelves[2].origin_W_m.y() += 0.5;
  EXPECT_EQ(mission_shelf_count(broken), 1);
  EXPECT_EQ(true_inventory(broken).size(), s0.boxes.size());
}

// The first `count` shelves of the scenario's row.
Scenario first_shelves(Scenario s, std::size_t count) {
  s.warehouse.shelves.resize(count);
  return s;
}

// One run of `strategy` over `link` with no video datagram lost. A lossy link makes each
// crossing a safe abort now and then (about one crossing in eight at the default scenario's 0
// to 2 % video loss): a lossy run's legitimate outcome, which campaigns measure, not what these
// tests are about. The same seed gives the same draws for every strategy. Flown in the world of
// the truth (without_senses): the paths the strategies take and the row's inventory are the
// flight software's guidance and perception, whatever the Tello senses.
RunResult fly(Scenario s, const std::string& strategy, const std::string& link, std::uint64_t seed) {
  s = without_senses(std::move(s));
  s.cosim.strategy = strategy;
  s.cosim.link.model = link;
  s.cosim.link.video_datagram_loss = 0.0;
  s.dispersions.erase("video_datagram_loss");
  const RunSetup setup = disperse(s, seed);
  render::Renderer renderer(setup.scenario->warehouse, setup.scenario->camera, render_options_for(*setup.scenario));
  RunResult r = run_cosimulation(setup, renderer);
  std::cout << "seed " << seed << ", " << link << " link, " << s.warehouse.shelves.size() << " shelves, " << strategy
            << ": " << outcome_name(r.outcome) << ", " << r.metrics.truth.path_length_m << " m, "
            << r.metrics.mission_time_s << " s" << std::endl;
  return r;
}

// Every shelf inventoried exactly, without contact; through the cells crosses each one, at
// its target cell, and the conventional strategies cross none.
void expect_row_inventoried(const RunResult& r, int shelves, bool through_cells) {
  EXPECT_EQ(r.outcome, RunOutcome::success) << outcome_name(r.outcome) << ": " << r.detail;
  EXPECT_FALSE(r.metrics.truth.contact.has_value());
  EXPECT_EQ(r.metrics.shelves, shelves);
  EXPECT_TRUE(r.metrics.inventory.exact());
  EXPECT_EQ(r.metrics.inventory.recall, 1.0);
  EXPECT_GE(r.metrics.inventory.truth, shelves * 7);  // box_fill_ratio >= 0.45 of 16 cells per shelf
  EXPECT_EQ(r.metrics.shelves_crossed, through_cells ? shelves : 0);
  EXPECT_EQ(r.metrics.shelves_crossed_target, through_cells ? shelves : 0);
}

constexpr int kRowShelves = 2;

// The three strategies on the row's first kRowShelves shelves with the same draws: each
// inventories them, through the cells is the shortest path and around the ends the longest.
void compare_strategies_on_the_row(std::uint64_t seed, const std::string& link) {
  const Scenario row = first_shelves(load_scenario(kWarehouse), kRowShelves);
  ASSERT_EQ(mission_shelf_count(row), kRowShelves);
  const auto& strategies = compared_strategies();
  std::array<RunResult, 3> results;
  for (size_t k = 0; k < 3; ++k) {
    results[k] = fly(row, strategies[k], link, seed);
    SCOPED_TRACE(strategies[k]);
    expect_row_inventoried(results[k], kRowShelves, k == 0);
  }
  EXPECT_LT(results[0].metrics.truth.path_length_m, results[1].metrics.truth.path_length_m);
  EXPECT_LT(results[1].metrics.truth.path_length_m, results[2].metrics.truth.path_length_m);
}

// Both links, each strategy flown on each: seed 12 over the shipped sdk link (the Tello's
// datagrams through tello_pilot's loop), seed 11 over the ideal link.
TEST(Warehouse, EveryStrategyInventoriesTheRowAndThroughTheCellsIsShortestOverTheSdkLink) {
  compare_strategies_on_the_row(12, "sdk");
}

TEST(Warehouse, EveryStrategyInventoriesTheRowAndThroughTheCellsIsShortestOverTheIdealLink) {
  compare_strategies_on_the_row(11, "ideal");
}

// The whole row of five, through the cells: every shelf crossed at its target and inventoried,
// without contact. Over the ideal link: what the sdk link does to a crossing and a transfer
// from shelf to shelf is flown above, on the row's first shelves (seed 12); this is the mission
// over five shelves, and the ideal link flies it without the H.264 encoding and decoding.
TEST(Warehouse, ThroughTheCellsCrossesAndInventoriesAllFiveShelves) {
  const Scenario nominal = load_scenario(kWarehouse);
  ASSERT_EQ(compared_strategies().front(), "through_cells");
  expect_row_inventoried(fly(nominal, "through_cells", "ideal", 12), 5, true);
}

}  // namespace
}  // namespace shelfcross::verification
