// `shelfcross diff` as a user or a CI script runs it: the exit status of a comparison (0), of a
// refused pairing or a missing campaign (2, nothing written) and of the gate (3), on campaigns
// with known flips written through the real results store.
#include <filesystem>

#include <gtest/gtest.h>

#include "campaign_helpers.hpp"
#include "run_shelfcross.hpp"
#include "verification/report/test/paired_campaigns_fixture.hpp"

namespace shelfcross::app::test {
namespace {

namespace fs = std::filesystem;
using verification::test::PlannedRun;

/// BASE: 40 successes. NEW: 6 of them abort (runs 3, 9, 15, 21, 27, 33): one-sided exact
/// McNemar p = 1/64.
PlannedRun base_run(std::int64_t) { return {}; }
PlannedRun new_run(std::int64_t k) {
  PlannedRun p;
  if (k % 6 == 3 && k < 36) {
    p.outcome = "mission_aborted";
    p.run_hash = "abababababababababababababab" + std::to_string(1000 + k);
  }
  return p;
}

struct Folders {
  fs::path dir, base, next, other_scenario;
};

Folders write_campaigns(const std::string& name) {
  const fs::path dir = fs::temp_directory_path() / ("shelfcross_cmd_diff_" + name);
  fs::remove_all(dir);
  const verification::Scenario s = verification::test::fixture_scenario();
  const verification::Scenario ideal = verification::test::fixture_scenario([](std::string& yaml) {
    const auto at = yaml.find("model: \"sdk\"");
    ASSERT_NE(at, std::string::npos);
    yaml.replace(at, 12, "model: \"ideal\"");
  });
  verification::test::write_planned_campaign(dir / "base" / "results.sqlite", s, 1, 40, base_run);
  verification::test::write_planned_campaign(dir / "new" / "results.sqlite", s, 1, 40, new_run);
  verification::test::write_planned_campaign(dir / "ideal" / "results.sqlite", ideal, 1, 40, new_run);
  return {dir, dir / "base", dir / "new", dir / "ideal"};
}

TEST(CmdDiff, ACampaignAgainstItselfReportsEveryRunIdentical) {
  const Folders f = write_campaigns("self");
  const ProgramResult r = run_shelfcross("diff", f.base.string() + " " + f.base.string() + " --out " +
                                                     (f.dir / "out").string() + " --fail-if-worse 0.05");
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("40 of 40 runs identical"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("gate passed"), std::string::npos) << r.output;
  EXPECT_TRUE(fs::exists(f.dir / "out" / "diff.md"));
  EXPECT_TRUE(fs::exists(f.dir / "out" / "diff.json"));
}

TEST(CmdDiff, TheGateExitsWithItsOwnStatusWhenNewIsWorse) {
  const Folders f = write_campaigns("gate");
  const std::string args = f.base.string() + " " + f.next.string() + " --out " + (f.dir / "out").string();
  // p = 1/64 = 0.0156: worse at 5 %, not at 1 %.
  ProgramResult r = run_shelfcross("diff", args + " --fail-if-worse 0.05");
  EXPECT_EQ(r.exit_code, 3) << r.output;
  EXPECT_NE(r.output.find("GATE FAILED"), std::string::npos) << r.output;
  EXPECT_TRUE(fs::exists(f.dir / "out" / "diff.md"));  // the report says why
  r = run_shelfcross("diff", args + " --fail-if-worse 0.01");
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("6 runs flipped"), std::string::npos) << r.output;
  // Without the gate a worse NEW is only reported.
  EXPECT_EQ(run_shelfcross("diff", args).exit_code, 0);
}

TEST(CmdDiff, RefusedPairingsExitWithTwoAndWriteNothing) {
  const Folders f = write_campaigns("refused");
  const fs::path out = f.dir / "out";
  // Another scenario (the link model) without --allow-different-scenarios.
  ProgramResult r = run_shelfcross("diff", f.base.string() + " " + f.other_scenario.string() + " --out " + out.string());
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("cosim.link.model: sdk in BASE, ideal in NEW"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("--allow-different-scenarios"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(out));
  // No such campaign.
  r = run_shelfcross("diff", f.base.string() + " " + (f.dir / "nothing").string() + " --out " + out.string());
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_FALSE(fs::exists(out));
  // A bad level.
  EXPECT_EQ(run_shelfcross("diff", f.base.string() + " " + f.next.string() + " --fail-if-worse 2").exit_code, 2);
  // Allowed: compared by run seed, the differing key listed in the report.
  r = run_shelfcross("diff", f.base.string() + " " + f.other_scenario.string() + " --allow-different-scenarios --out " +
                                 out.string());
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("by run seed"), std::string::npos) << r.output;
  EXPECT_NE(read_text(out / "diff.md").find("| cosim.link.model | sdk | ideal |"), std::string::npos);
}

}  // namespace
}  // namespace shelfcross::app::test
