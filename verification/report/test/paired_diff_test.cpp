// The paired comparison of two campaigns (shelfcross diff) on stored results with known flips:
// the pairing and its refusals, the 2 x 2 tables and McNemar p-values against their closed
// forms, the metrics' paired differences, the flips, and the report.
#include <filesystem>
#include <fstream>
#include <sstream>

#include <gtest/gtest.h>

#include "verification/report/diff_report.hpp"
#include "verification/report/paired_diff.hpp"
#include "verification/report/test/paired_campaigns_fixture.hpp"

namespace shelfcross::verification {
namespace {

namespace fs = std::filesystem;
using test::PlannedRun;

fs::path fresh_dir(const std::string& name) {
  const fs::path dir = fs::temp_directory_path() / ("shelfcross_paired_diff_" + name);
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

/// BASE: 60 runs, all successes but 10 and 20 (safe aborts); clearance 8.0 to 8.6 cm.
PlannedRun base_plan(std::int64_t k) {
  PlannedRun p;
  p.outcome = (k == 10 || k == 20) ? "mission_aborted" : "success";
  p.min_clearance_m = 0.080 + 0.001 * static_cast<double>(k % 7);
  return p;
}

/// NEW: run 10 recovers; 5, 15, 25, 35, 45, 55 abort and 50 touches the shelf (7 lost, 1
/// gained); runs 0-39 pass 1 cm closer to the shelf, pushed 1 cm further (other hashes); 40-59
/// are unchanged but for the flips.
PlannedRun new_plan(std::int64_t k) {
  PlannedRun p = base_plan(k);
  if (k == 10) p.outcome = "success";
  if (k % 10 == 5) p.outcome = "mission_aborted";
  if (k == 50) p.outcome = "collision";
  if (k < 40) {
    p.min_clearance_m -= 0.010;
    p.push_m += 0.010;
    p.run_hash = "ffffffffffffffffffffffffffff" + std::to_string(1000 + k);
  }
  if (p.outcome != base_plan(k).outcome) p.run_hash = "eeeeeeeeeeeeeeeeeeeeeeeeeeee" + std::to_string(1000 + k);
  return p;
}

struct Campaigns {
  fs::path base, next;
};

Campaigns write_known_flips(const std::string& name) {
  const fs::path dir = fresh_dir(name);
  const Scenario s = test::fixture_scenario();
  test::write_planned_campaign(dir / "base" / "results.sqlite", s, 1, 60, base_plan);
  test::write_planned_campaign(dir / "new" / "results.sqlite", s, 1, 60, new_plan);
  return {dir / "base", dir / "new"};
}

TEST(PairedDiff, CountsTheKnownFlipsAndMatchesTheClosedForms) {
  const Campaigns c = write_known_flips("flips");
  const PairedDiff d = pair_campaigns(load_diff_side(c.base), load_diff_side(c.next), {});
  EXPECT_FALSE(d.paired_by_seed);
  EXPECT_EQ(d.pairs, 60);
  EXPECT_EQ(d.identical, 17);  // runs 40-59 but the flips 45, 50, 55
  // Failures: both 1 (20), BASE only 1 (10), NEW only 7, neither 51.
  const PairedTable& f = d.failures.table;
  EXPECT_EQ(f.both, 1);
  EXPECT_EQ(f.base_only, 1);
  EXPECT_EQ(f.new_only, 7);
  EXPECT_EQ(f.neither, 51);
  // Exact McNemar on 8 discordant pairs, 7 NEW's way: P(X >= 7) = (8 + 1) / 256, two-sided twice.
  EXPECT_NEAR(d.failures.mcnemar.p_new_worse, 9.0 / 256.0, 1e-15);
  EXPECT_NEAR(d.failures.mcnemar.p_two_sided, 18.0 / 256.0, 1e-15);
  EXPECT_TRUE(new_is_worse(d, 0.05));
  EXPECT_FALSE(new_is_worse(d, 0.01));
  // The failure rate rose by 6 in 60: the interval holds it and, here, not 0.
  EXPECT_NEAR(d.failures.new_rate - d.failures.base_rate, 0.1, 1e-12);
  EXPECT_TRUE(d.failures.difference.contains(0.1));
  // One new contact: p = 1/2, not a finding alone.
  EXPECT_EQ(d.contacts.table.new_only, 1);
  EXPECT_DOUBLE_EQ(d.contacts.mcnemar.p_new_worse, 0.5);
  // The flips, in run order, with both outcomes, the draws and what changed.
  ASSERT_EQ(d.flips.size(), 8u);
  const std::int64_t expected_runs[] = {5, 10, 15, 25, 35, 45, 50, 55};
  for (std::size_t i = 0; i < d.flips.size(); ++i) {
    EXPECT_EQ(d.flips[i].base_run, expected_runs[i]);
    EXPECT_EQ(d.flips[i].new_run, expected_runs[i]);
    EXPECT_TRUE(d.flips[i].success_changed);
    EXPECT_FALSE(d.flips[i].base_draws.empty());
    EXPECT_EQ(d.flips[i].base_draws, d.flips[i].new_draws);
  }
  EXPECT_EQ(d.flips[1].base_outcome, "mission_aborted");
  EXPECT_EQ(d.flips[1].new_outcome, "success");
  EXPECT_EQ(d.flips[6].new_outcome, "collision");
  EXPECT_TRUE(d.flips[6].contact_changed);
}

TEST(PairedDiff, MetricsArePairedOverTheRunsBothHave) {
  const Campaigns c = write_known_flips("metrics");
  const PairedDiff d = pair_campaigns(load_diff_side(c.base), load_diff_side(c.next), {});
  const auto metric = [&d](const std::string& name) {
    for (const MetricComparison& m : d.metrics) {
      if (m.name == name) return m;
    }
    ADD_FAILURE() << name;
    return MetricComparison{};
  };
  // Clearance exists where both succeeded: 51 pairs, 34 of them (runs 0-39) 1 cm closer.
  const MetricComparison clearance = metric("min_clearance_m");
  EXPECT_EQ(clearance.pairs, 51);
  EXPECT_EQ(clearance.moved_down, 34);
  EXPECT_EQ(clearance.moved_up, 0);
  EXPECT_EQ(clearance.paired.nonzero, 34);
  EXPECT_NEAR(clearance.paired.median, -0.010, 1e-12);
  EXPECT_LT(clearance.paired.interval.upper, 0.0);
  EXPECT_LT(clearance.paired.p_two_sided, 1e-6);
  EXPECT_DOUBLE_EQ(clearance.tolerance, 0.005);
  // The push, from the stored traces, where both crossed: 2 cm, 3 cm for runs 0-39 in NEW.
  const MetricComparison push = metric("crossing_push_m");
  EXPECT_EQ(push.pairs, 51);
  EXPECT_EQ(push.moved_up, 34);
  EXPECT_EQ(push.moved_down, 0);
  EXPECT_NEAR(push.paired.median, 0.010, 1.5e-3);
  // Each side's values over every pair where it crossed: 58 successes in BASE, 52 in NEW.
  EXPECT_EQ(push.base_each.size(), 58u);
  EXPECT_EQ(push.new_each.size(), 52u);
  // Mission time and CPU seconds did not move.
  for (const char* name : {"mission_time_s", "cpu_s"}) {
    const MetricComparison m = metric(name);
    EXPECT_EQ(m.pairs, 60) << name;
    EXPECT_EQ(m.paired.nonzero, 0) << name;
    EXPECT_EQ(m.paired.p_two_sided, 1.0) << name;
    EXPECT_EQ(m.paired.hodges_lehmann, 0.0) << name;
  }
}

TEST(PairedDiff, ACampaignAgainstItselfIsIdenticalRunForRun) {
  const Campaigns c = write_known_flips("self");
  const PairedDiff d = pair_campaigns(load_diff_side(c.base), load_diff_side(c.base), {});
  EXPECT_EQ(d.pairs, 60);
  EXPECT_EQ(d.identical, 60);
  EXPECT_TRUE(d.flips.empty());
  EXPECT_EQ(d.failures.mcnemar.discordant, 0);
  EXPECT_EQ(d.failures.mcnemar.p_new_worse, 1.0);
  EXPECT_TRUE(d.failures.difference.contains(0.0));
  EXPECT_FALSE(new_is_worse(d, 0.05));
  for (const MetricComparison& m : d.metrics) EXPECT_EQ(m.paired.nonzero, 0) << m.name;
  EXPECT_TRUE(d.scenario_differences.empty());
}

TEST(PairedDiff, RefusesRunsDrawnDifferentlyNamingTheFirstDraw) {
  const fs::path dir = fresh_dir("draws");
  const Scenario s = test::fixture_scenario();
  test::write_planned_campaign(dir / "base.sqlite", s, 1, 12, base_plan);
  test::write_planned_campaign(dir / "new.sqlite", s, 1, 12, [](std::int64_t k) {
    PlannedRun p = base_plan(k);
    if (k >= 7) p.other_draw = {"start_distance_m", 3.4};
    return p;
  });
  try {
    pair_campaigns(load_diff_side(dir / "base.sqlite"), load_diff_side(dir / "new.sqlite"), {});
    FAIL() << "paired runs with other draws";
  } catch (const PairingRefused& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("run 7"), std::string::npos) << what;
    EXPECT_NE(what.find("start_distance_m"), std::string::npos) << what;
    EXPECT_NE(what.find("3.4 in NEW"), std::string::npos) << what;
  }
  // Allowed: paired by run seed, the draw listed with its count and first pair.
  const PairedDiff d = pair_campaigns(load_diff_side(dir / "base.sqlite"), load_diff_side(dir / "new.sqlite"),
                                      {.allow_different_scenarios = true});
  EXPECT_TRUE(d.paired_by_seed);
  EXPECT_EQ(d.pairs, 12);
  EXPECT_EQ(d.pairs_with_other_draws, 5);
  ASSERT_EQ(d.draw_differences.size(), 1u);
  EXPECT_EQ(d.draw_differences[0].name, "start_distance_m");
  EXPECT_EQ(d.draw_differences[0].pairs, 5);
  EXPECT_EQ(d.draw_differences[0].first_base_run, 7);
  EXPECT_EQ(d.draw_differences[0].first_new, 3.4);
}

TEST(PairedDiff, RefusesAnotherScenarioOrSeedUnlessAllowed) {
  const fs::path dir = fresh_dir("scenario");
  const Scenario s = test::fixture_scenario();
  const Scenario no_level_check = test::fixture_scenario([](std::string& yaml) {
    const auto at = yaml.find("level_check: true");
    ASSERT_NE(at, std::string::npos);
    yaml.replace(at, 17, "level_check: false");
  });
  test::write_planned_campaign(dir / "base.sqlite", s, 1, 10, base_plan);
  test::write_planned_campaign(dir / "switch.sqlite", no_level_check, 1, 10, base_plan);
  test::write_planned_campaign(dir / "seed2.sqlite", s, 2, 10, base_plan);
  const DiffSide base = load_diff_side(dir / "base.sqlite");
  try {
    pair_campaigns(base, load_diff_side(dir / "switch.sqlite"), {});
    FAIL() << "paired campaigns of other scenarios";
  } catch (const PairingRefused& e) {
    EXPECT_NE(std::string(e.what()).find("cosim.pilot.level_check: true in BASE, false in NEW"), std::string::npos)
        << e.what();
  }
  const PairedDiff d = pair_campaigns(base, load_diff_side(dir / "switch.sqlite"), {.allow_different_scenarios = true});
  EXPECT_EQ(d.pairs, 10);
  ASSERT_EQ(d.scenario_differences.size(), 1u);
  EXPECT_EQ(d.scenario_differences[0].key, "cosim.pilot.level_check");
  EXPECT_TRUE(d.draw_differences.empty());  // the switch draws nothing else
  // Another campaign seed: other runs altogether; refused, and by run seed nothing is shared.
  EXPECT_THROW(pair_campaigns(base, load_diff_side(dir / "seed2.sqlite"), {}), PairingRefused);
  EXPECT_THROW(pair_campaigns(base, load_diff_side(dir / "seed2.sqlite"), {.allow_different_scenarios = true}),
               PairingRefused);
  EXPECT_THROW(load_diff_side(dir / "none"), ResultsMismatch);
}

// A campaign still running (or stopped) is compared on the runs both sides have stored.
TEST(PairedDiff, ComparesOnlyTheRunsBothSidesHave) {
  const fs::path dir = fresh_dir("partial");
  const Scenario s = test::fixture_scenario();
  test::write_planned_campaign(dir / "base.sqlite", s, 1, 60, base_plan);
  test::write_planned_campaign(dir / "new.sqlite", s, 1, 25, new_plan, 60);
  const PairedDiff d = pair_campaigns(load_diff_side(dir / "base.sqlite"), load_diff_side(dir / "new.sqlite"), {});
  EXPECT_EQ(d.pairs, 25);
  EXPECT_EQ(d.next.meta.runs_requested, 60);
  EXPECT_EQ(d.flips.size(), 3u);  // 5, 10, 15
}

TEST(PairedDiff, ReportStatesTheVerdictFlipsAndReplayCommands) {
  const Campaigns c = write_known_flips("report");
  const PairedDiff d = pair_campaigns(load_diff_side(c.base), load_diff_side(c.next), {});
  const fs::path out = c.base.parent_path() / "diff";
  const nlohmann::json j = write_diff_report(d, out, {.fail_if_worse_alpha = 0.05});
  for (const char* file : {"diff.md", "diff.json", "clearance_base_vs_new.png", "difference_min_clearance_m.png",
                           "difference_crossing_push_m.png", "difference_mission_time_s.png", "difference_cpu_s.png"}) {
    EXPECT_TRUE(fs::exists(out / file)) << file;
  }
  EXPECT_EQ(j["pairs"], 60);
  EXPECT_EQ(j["identical_runs"], 17);
  EXPECT_EQ(j["mission_success"]["base_only_succeeds"], 7);
  EXPECT_EQ(j["mission_success"]["new_only_succeeds"], 1);
  EXPECT_NEAR(j["mission_success"]["difference"].get<double>(), -0.1, 1e-12);
  EXPECT_NEAR(j["mission_success"]["p_new_worse"].get<double>(), 9.0 / 256.0, 1e-15);
  EXPECT_EQ(j["gate"]["new_worse"], true);
  ASSERT_EQ(j["flips"].size(), 8u);
  EXPECT_EQ(j["flips"][0]["replay"][0], "shelfcross replay " + c.base.string() + " --run 5 --video");
  EXPECT_EQ(j["flips"][0]["replay"][1], "shelfcross replay " + c.next.string() + " --run 5 --video");
  // The closest calls: run 0, the first of the least clearance and the largest push on each side.
  EXPECT_NEAR(j["metrics"]["min_clearance_m"]["new_min"]["value"].get<double>(), 0.070, 1e-12);
  EXPECT_EQ(j["metrics"]["min_clearance_m"]["new_min"]["run"], 0);
  EXPECT_NEAR(j["metrics"]["crossing_push_m"]["base_max"]["value"].get<double>(), 0.020, 1e-3);
  EXPECT_EQ(j["metrics"]["crossing_push_m"]["new_runs_with_it"], 52);
  std::ifstream in(out / "diff.md");
  std::stringstream text;
  text << in.rdbuf();
  const std::string md = text.str();
  EXPECT_NE(md.find("**17 of 60 runs identical**"), std::string::npos);
  EXPECT_NE(md.find("FAILED: NEW is worse than BASE at this level"), std::string::npos);
  EXPECT_NE(md.find("| 50 | 50 | success | collision (planned collision) | **lost** | **new contact** |"),
            std::string::npos);
  EXPECT_NE(md.find("shelfcross replay " + c.next.string() + " --run 50 --video"), std::string::npos);
  EXPECT_NE(md.find("| least clearance to the shelf | 8.0 cm | 0 | 7.0 cm | 0 |"), std::string::npos);
  EXPECT_NE(md.find("| largest crossing push | 2.0 cm | 0 | 3.0 cm | 0 |"), std::string::npos);
}

// Near misses (no contact, clearance below cosim.near_miss_m, 2 cm) are a class of their own in
// the comparison: BASE's run 3 passes at 1.5 cm; in NEW it passes at 3 cm (gone), runs 6 and 7
// pass at 1 cm (new, both still successes) and run 8 touches the shelf (a contact, not a near
// miss). Every change of class is a flip, with its replay commands.
TEST(PairedDiff, NearMissesAreComparedApartFromContacts) {
  const fs::path dir = fresh_dir("near_misses");
  const Scenario s = test::fixture_scenario();
  const auto base = [](std::int64_t k) {
    PlannedRun p;
    p.min_clearance_m = k == 3 ? 0.015 : 0.05;
    return p;
  };
  const auto next = [&base](std::int64_t k) {
    PlannedRun p = base(k);
    if (k == 3) p.min_clearance_m = 0.03;
    if (k == 6 || k == 7) p.min_clearance_m = 0.01;
    if (k == 8) p.outcome = "collision";
    if (k == 3 || k >= 6) p.run_hash = "dddddddddddddddddddddddddddd" + std::to_string(1000 + k);
    return p;
  };
  test::write_planned_campaign(dir / "base" / "results.sqlite", s, 1, 10, base);
  test::write_planned_campaign(dir / "new" / "results.sqlite", s, 1, 10, next);
  const PairedDiff d = pair_campaigns(load_diff_side(dir / "base"), load_diff_side(dir / "new"), {});
  EXPECT_EQ(d.near_misses.table.both, 0);
  EXPECT_EQ(d.near_misses.table.base_only, 1);
  EXPECT_EQ(d.near_misses.table.new_only, 2);
  EXPECT_EQ(d.near_misses.table.neither, 7);
  EXPECT_EQ(d.contacts.table.new_only, 1);
  ASSERT_EQ(d.flips.size(), 4u);
  EXPECT_EQ(d.flips[0].base_run, 3);
  EXPECT_TRUE(d.flips[0].near_miss_changed);
  EXPECT_FALSE(d.flips[0].new_near_miss);
  EXPECT_FALSE(d.flips[0].success_changed);
  EXPECT_TRUE(d.flips[1].near_miss_changed && d.flips[1].new_near_miss);
  EXPECT_EQ(d.flips[3].base_run, 8);
  EXPECT_TRUE(d.flips[3].contact_changed);
  EXPECT_FALSE(d.flips[3].near_miss_changed);
  EXPECT_FALSE(new_is_worse(d, 0.05));  // reported, not gated
  const nlohmann::json j = write_diff_report(d, dir / "diff", {});
  EXPECT_EQ(j["near_misses"]["new_only"], 2);
  EXPECT_EQ(j["near_miss_m"]["base"], 0.02);
  EXPECT_EQ(j["flips"][1]["new_near_miss"], true);
  std::ifstream in(dir / "diff" / "diff.md");
  std::stringstream text;
  text << in.rdbuf();
  const std::string md = text.str();
  EXPECT_NE(md.find("| 6 | 6 | success | success |  |  | **new near miss** |"), std::string::npos) << md;
  EXPECT_NE(md.find("| 3 | 3 | success | success |  |  | near miss gone |"), std::string::npos) << md;
  EXPECT_NE(md.find("| BASE: near miss | 0 | 1 |"), std::string::npos) << md;
  EXPECT_NE(md.find("- **Near misses** (no contact, least clearance below 2.0 cm in BASE, 2.0 cm in NEW): BASE 1, NEW 2"),
            std::string::npos)
      << md;
}

}  // namespace
}  // namespace shelfcross::verification
