// The pieces of the search that touch a scenario: disperse() with given draws, the run margins
// from stored metrics, proposals stored as JSON, searches stored by an older format.
#include <cmath>
#include <filesystem>

#include <SQLiteCpp/SQLiteCpp.h>
#include <gtest/gtest.h>

#include "verification/scenario/dispersion.hpp"
#include "verification/scenario/scenario.hpp"
#include "verification/search/margin.hpp"
#include "verification/search/rare_event.hpp"
#include "verification/search/search.hpp"

namespace shelfcross::verification {
namespace {

const std::string kDefault = std::string(SHELFCROSS_SOURCE_DIR) + "/scenarios/paper_test_shelf.yaml";

TEST(SearchPieces, DisperseWithTheSeedsOwnDrawsIsDisperse) {
  const Scenario nominal = load_scenario(kDefault);
  for (std::uint64_t seed : {1ull, 42ull}) {
    const RunSetup a = disperse(nominal, seed);
    const RunSetup b = disperse(nominal, seed, draw_dispersions(nominal.dispersions, seed));
    EXPECT_EQ(a.drawn, b.drawn);
    EXPECT_EQ(*a.scenario, *b.scenario);
    EXPECT_EQ(a.believed_camera.cx_px, b.believed_camera.cx_px);
    // The nominal as a proposal draws the same values (round 0 of a search is a campaign).
    EXPECT_EQ(draw_dispersions(nominal_proposals({nominal.dispersions.begin(), nominal.dispersions.end()}), seed),
              a.drawn);
    EXPECT_EQ(RoundProposal::of_nominal({nominal.dispersions.begin(), nominal.dispersions.end()}).sample(seed), a.drawn);
  }
  // Given draws are applied: the start 2.6 m in front of the shelf.
  DrawnValues drawn = draw_dispersions(nominal.dispersions, 1);
  drawn["start_distance_m"] = 2.6;
  const RunSetup c = disperse(nominal, 1, drawn);
  EXPECT_NEAR(nominal.warehouse.shelves[0].origin_W_m.x() - c.scenario->start.p_WB_m.x(), 2.6, 1e-12);
}

TEST(SearchPieces, DisperseRefusesDrawsThatAreNotTheScenarios) {
  const Scenario nominal = load_scenario(kDefault);
  DrawnValues drawn = draw_dispersions(nominal.dispersions, 1);
  DrawnValues extra = drawn;
  extra["mass_kg"] = 1.0;
  EXPECT_THROW(disperse(nominal, 1, extra), std::invalid_argument);
  DrawnValues missing = drawn;
  missing.erase("start_distance_m");
  EXPECT_THROW(disperse(nominal, 1, missing), std::invalid_argument);
  DrawnValues out_of_range = drawn;
  out_of_range["start_distance_m"] = 25.0;  // allowed 0.5..20
  EXPECT_THROW(disperse(nominal, 1, out_of_range), std::invalid_argument);
}

TEST(SearchPieces, MarginsFromStoredMetrics) {
  const Scenario s = load_scenario(kDefault);  // columns 0.34/0.48, rows 0.34, bars 0.02, vehicle 0.0925 x 0.041
  // A clean crossing of level 2 column 2 (0.48 wide), 3 cm left and 1 cm up of its centre.
  RunMetrics m;
  m.mission_time_s = 24.0;
  m.shelves = 1;
  m.shelves_crossed_target = 1;
  m.truth.crossed = CellIndex{2, 2};
  m.target = CellIndex{2, 2};
  m.truth.entry_offset_y_m = 0.03;
  m.truth.entry_offset_z_m = -0.01;
  m.truth.min_clearance_m = 0.09;
  RunMargins r = run_margins(s, "success", m);
  EXPECT_DOUBLE_EQ(r.contact_m, 0.09);
  // y: (0.48 - 0.02) / 2 - 0.0925 / 2 - 0.03 = 0.15375; z: (0.34 - 0.02) / 2 - 0.041 / 2 - 0.01 = 0.1295
  EXPECT_NEAR(r.crossing_m, 0.1295, 1e-12);
  EXPECT_NEAR(r.mission, 1.0 - 24.0 / 120.0, 1e-12);
  EXPECT_FALSE(r.failed(FailureClass::contact) || r.failed(FailureClass::crossing) || r.failed(FailureClass::mission));
  // A success that landed in the grace after the run's 120 s limit: no time to spare, not failed.
  m.mission_time_s = 125.0;
  EXPECT_DOUBLE_EQ(run_margins(s, "success", m).mission, 0.0);
  EXPECT_FALSE(run_margins(s, "success", m).failed(FailureClass::mission));
  m.mission_time_s = 24.0;
  // Wide off the centre of a narrow column (0.34): y room 0.16 - 0.04625 - 0.13 < 0.
  m.truth.crossed = CellIndex{2, 1};
  m.truth.entry_offset_y_m = -0.13;
  EXPECT_NEAR(run_margins(s, "success", m).crossing_m, 0.16 - 0.04625 - 0.13, 1e-12);
  // A contact 4 mm deep: contact and mission fail; no crossing: the crossing margin says nothing.
  RunMetrics hit;
  hit.mission_time_s = 12.0;
  hit.truth.contact = plant::Contact{};
  hit.truth.contact->depth_m = 0.004;
  hit.truth.min_clearance_m = 0.01;
  r = run_margins(s, "collision", hit);
  EXPECT_DOUBLE_EQ(r.contact_m, -0.004);
  EXPECT_TRUE(std::isnan(r.crossing_m));
  EXPECT_FALSE(r.failed(FailureClass::crossing));
  EXPECT_DOUBLE_EQ(r.mission, -1.0);
  // Touching (depth 0) is still a contact.
  hit.truth.contact->depth_m = 0.0;
  EXPECT_LT(run_margins(s, "collision", hit).contact_m, 0.0);
  // Crossed and then failed (a wrong inventory): mission -0.1; never near a shelf: no contact margin.
  RunMetrics wrong;
  wrong.mission_time_s = 30.0;
  wrong.shelves_crossed_target = 1;
  r = run_margins(s, "inventory_mismatch", wrong);
  EXPECT_NEAR(r.mission, -0.1, 1e-12);
  EXPECT_TRUE(std::isnan(r.contact_m));
  // A run lost with its worker (no metrics): no contact or crossing margin, the mission failed.
  r = run_margins(s, "crashed", std::nullopt);
  EXPECT_TRUE(std::isnan(r.contact_m) && std::isnan(r.crossing_m));
  EXPECT_DOUBLE_EQ(r.mission, -1.0);
  EXPECT_EQ(parse_failure_class("crossing"), FailureClass::crossing);
  EXPECT_FALSE(parse_failure_class("speed"));
}

// The near-miss margin is the clearance less the scenario's cosim.near_miss_m (2 cm); a run
// below it is a near miss only where it touched nothing, so the class is apart from contacts,
// while a contact's margin still lies below zero (the search is drawn toward both).
TEST(SearchPieces, NearMissMarginAndClass) {
  const Scenario s = load_scenario(kDefault);
  ASSERT_EQ(s.cosim.near_miss_m, 0.02);
  RunMetrics m;
  m.mission_time_s = 24.0;
  m.truth.min_clearance_m = 0.015;
  RunMargins r = run_margins(s, "success", m);
  EXPECT_NEAR(r.near_miss_m, -0.005, 1e-15);
  EXPECT_TRUE(r.failed(FailureClass::near_miss));
  EXPECT_FALSE(r.failed(FailureClass::contact) || r.failed(FailureClass::mission));
  m.truth.min_clearance_m = 0.05;
  r = run_margins(s, "success", m);
  EXPECT_NEAR(r.of(FailureClass::near_miss), 0.03, 1e-15);
  EXPECT_FALSE(r.failed(FailureClass::near_miss));
  RunMetrics hit = m;
  hit.truth.contact = plant::Contact{};
  hit.truth.contact->depth_m = 0.004;
  r = run_margins(s, "collision", hit);
  EXPECT_NEAR(r.near_miss_m, -0.024, 1e-15);
  EXPECT_TRUE(r.failed(FailureClass::contact));
  EXPECT_FALSE(r.failed(FailureClass::near_miss));
  EXPECT_FALSE(run_margins(s, "crashed", std::nullopt).failed(FailureClass::near_miss));
  EXPECT_EQ(parse_failure_class("near_miss"), FailureClass::near_miss);
  EXPECT_STREQ(failure_class_name(FailureClass::near_miss), "near_miss");
}

TEST(SearchPieces, DistributionsRoundTripThroughJson) {
  const Scenario s = load_scenario(kDefault);
  for (const auto& [name, d] : s.dispersions) EXPECT_EQ(distribution_from_json(distribution_json(d)), d) << name;
  Distribution c;
  c.kind = Distribution::Kind::choice;
  c.values = {0.5, 1.0};
  c.weights = {0.25, 0.75};
  EXPECT_EQ(distribution_from_json(distribution_json(c)), c);
}

/// A round's proposal on the scenario's dispersions: start_distance_m fitted, the rest nominal.
RoundProposal fitted_round(const Scenario& s, double nominal_share) {
  RoundProposal q = RoundProposal::of_nominal({s.dispersions.begin(), s.dispersions.end()});
  q.nominal_share = nominal_share;
  const Distribution& f = s.dispersions.at("start_distance_m");
  q.parameters["start_distance_m"] = {continuous_proposal(f, f.highest(), 0.1), f, 0.1};
  return q;
}

TEST(SearchPieces, RoundProposalsRoundTripThroughJsonAndFormatOneReadsWithoutTheJointShare) {
  const Scenario s = load_scenario(kDefault);
  const RoundProposal q = fitted_round(s, 0.2);
  EXPECT_EQ(proposals_from_json(proposals_json(q)), q);
  EXPECT_DOUBLE_EQ(proposals_from_json(proposals_json(q)).least_ratio(), 0.2 + 0.8 * 0.1);
  // Format 1 stored the parameters' proposals alone: read with no joint share, so its bound
  // is what it was (c = prod_j s_j).
  const nlohmann::json format_one = proposals_json(q).at("parameters");
  const RoundProposal old = proposals_from_json(format_one);
  EXPECT_EQ(old.parameters, q.parameters);
  EXPECT_EQ(old.nominal_share, 0.0);
  EXPECT_DOUBLE_EQ(old.least_ratio(), 0.1);
}

// A search stored by format 1 (per-parameter shares only) is refused on resume with the reason,
// and its rounds still read (for its report).
TEST(SearchPieces, AFormatOneSearchIsNotResumedButReads) {
  const Scenario s = load_scenario(kDefault);
  const auto dir = std::filesystem::temp_directory_path() / "shelfcross_search_format_one";
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  const auto db_path = dir / "results.sqlite";
  SearchSettings settings;
  nlohmann::json old_settings = search_settings_json(settings);
  old_settings["format_version"] = "1";
  old_settings.erase("parameter_share");
  {
    SQLite::Database db(db_path.string(), SQLite::OPEN_READWRITE | SQLite::OPEN_CREATE);
    db.exec("CREATE TABLE search(key TEXT PRIMARY KEY, value TEXT NOT NULL)");
    db.exec(
        "CREATE TABLE search_rounds(round INTEGER PRIMARY KEY, first_run INTEGER NOT NULL, runs INTEGER NOT NULL,"
        " estimation INTEGER NOT NULL, level REAL, elites INTEGER NOT NULL, proposal_json TEXT NOT NULL)");
    SQLite::Statement q(db, "INSERT INTO search(key, value) VALUES('settings', ?)");
    q.bind(1, old_settings.dump());
    q.exec();
    SQLite::Statement r(db, "INSERT INTO search_rounds VALUES(1, 10, 10, 0, 0.5, 3, ?)");
    r.bind(1, proposals_json(fitted_round(s, 0.2)).at("parameters").dump());
    r.exec();
  }
  try {
    SearchStore::open_or_create(db_path, settings);
    ADD_FAILURE() << "a format 1 search was reopened";
  } catch (const ResultsMismatch& e) {
    EXPECT_NE(std::string(e.what()).find("format 1"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("cannot be resumed"), std::string::npos) << e.what();
  }
  const std::vector<CeRound> rounds = SearchStore::open_existing(db_path).rounds();
  ASSERT_EQ(rounds.size(), 1u);
  EXPECT_EQ(rounds[0].proposal.nominal_share, 0.0);
  EXPECT_EQ(rounds[0].proposal.parameters.at("start_distance_m").nominal_share, 0.1);
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace shelfcross::verification
