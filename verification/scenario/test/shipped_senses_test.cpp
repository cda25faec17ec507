// The Tello's own senses in every shipped scenario (scenarios/README.md, section `senses`): each
// mission scenario, and the calibration flights' open space, carries the default scenario's
// `senses` section, rolling shutter (`camera.readout_s`), air near surfaces
// (`vehicle.surface_effects`) and their dispersions, unless setting a sense is its purpose. The
// documented values live in every file (each scenario is self-contained); this test makes a
// change to them one deliberate edit of every file, and names the file an edit missed.

#include <algorithm>
#include <filesystem>
#include <functional>
#include <map>
#include <set>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "plant/params.hpp"
#include "plant/tello_senses.hpp"
#include "verification/scenario/dispersion_table.hpp"
#include "verification/scenario/scenario.hpp"
#include "verification/scenario/senses_dispersion.hpp"

namespace shelfcross::verification {
namespace {

const std::string kScenarios = std::string(SHELFCROSS_SOURCE_DIR) + "/scenarios/";

// What a scenario says of the Tello's senses, and nothing else of it.
struct Senses {
  plant::SensesParams senses;
  double readout_s = 0.0;
  plant::SurfaceEffectParams surface_effects;
  std::map<std::string, Distribution> dispersions;
  bool operator==(const Senses&) const = default;
};

Senses senses_of(const Scenario& s) {
  Senses out{s.senses, s.readout_s, s.vehicle.surface_effects, {}};
  for (const auto& [name, d] : s.dispersions) {
    if (is_senses_dispersion(name)) out.dispersions.emplace(name, d);
  }
  return out;
}

// A scenario whose purpose is a sense set otherwise: the file, why, and what it changes of the
// default scenario's senses.
struct Purpose {
  const char* file;
  const char* reason;
  std::function<void(Senses&)> apply;
};

const std::vector<Purpose>& purposes() {
  static const std::vector<Purpose> list{
      {"stress/beyond_height_follow.yaml",
       "beyond the envelope: the height hold follows the range reading fully below 2 m, not drawn",
       [](Senses& s) {
         s.senses.height_hold.range_blend = 1.0;
         s.senses.height_hold.range_below_m = 2.0;
         s.dispersions.erase("height_hold_range_blend");
         s.dispersions.erase("height_hold_range_below_m");
       }},
  };
  return list;
}

// Every mission scenario shipped (scenarios/*.yaml, scenarios/stress/*.yaml) and the calibration
// flights' open space (a real Tello calibrated has its senses), relative to scenarios/.
std::vector<std::string> shipped_scenarios() {
  std::vector<std::string> files{"calibration/open_space.yaml", "calibration/open_space_wide.yaml"};
  for (const std::string dir : {"", "stress/"}) {
    for (const auto& entry : std::filesystem::directory_iterator(kScenarios + dir)) {
      if (entry.is_regular_file() && entry.path().extension() == ".yaml")
        files.push_back(dir + entry.path().filename().string());
    }
  }
  std::sort(files.begin(), files.end());
  return files;
}

// The default scenario draws every dispersion of the senses the format has, at documented values
// other than the truth: comparing the others with it is comparing with the documented senses.
TEST(ShippedSenses, TheDefaultScenarioCarriesEverySense) {
  const Scenario def = load_scenario(kScenarios + "paper_test_shelf.yaml");
  EXPECT_NE(def.senses, plant::SensesParams{});
  EXPECT_GT(def.readout_s, 0.0);
  EXPECT_NE(def.vehicle.surface_effects, plant::SurfaceEffectParams{});
  int senses_parameters = 0;
  for (const DispersionParameter& p : dispersion_parameters()) {
    if (!is_senses_dispersion(p.name)) continue;
    ++senses_parameters;
    EXPECT_EQ(def.dispersions.count(p.name), 1u) << p.name << " is not drawn by the default scenario";
  }
  EXPECT_EQ(senses_parameters, 16);
}

// The world of the truth (tests of a mechanism the senses do not bear on fly their runs there):
// every sense at the identity and its draws gone, every other key and draw kept.
TEST(ShippedSenses, WithoutTheSensesIsTheWorldOfTheTruth) {
  const Scenario def = load_scenario(kScenarios + "paper_test_shelf.yaml");
  Scenario truth = without_senses(def);
  EXPECT_EQ(senses_of(truth), Senses{});
  EXPECT_EQ(truth.dispersions.size(), def.dispersions.size() - 16);
  for (const auto& [name, d] : truth.dispersions) EXPECT_EQ(def.dispersions.at(name), d) << name;
  truth.senses = def.senses;
  truth.readout_s = def.readout_s;
  truth.vehicle.surface_effects = def.vehicle.surface_effects;
  truth.dispersions = def.dispersions;
  EXPECT_EQ(truth, def);
}

TEST(ShippedSenses, EveryShippedScenarioSensesAsTheDefaultOneButForItsPurpose) {
  const Senses documented = senses_of(load_scenario(kScenarios + "paper_test_shelf.yaml"));
  const std::vector<std::string> files = shipped_scenarios();
  ASSERT_GE(files.size(), 20u);
  std::set<std::string> purposes_met;
  for (const std::string& file : files) {
    Senses expected = documented;
    for (const Purpose& p : purposes()) {
      if (file != p.file) continue;
      p.apply(expected);
      purposes_met.insert(file);
      ASSERT_NE(expected, documented) << file << ": the purpose changes nothing (" << p.reason << ")";
    }
    const Senses actual = senses_of(load_scenario(kScenarios + file));
    EXPECT_EQ(actual.senses, expected.senses) << file << ": the senses section";
    EXPECT_EQ(actual.readout_s, expected.readout_s) << file << ": camera.readout_s";
    EXPECT_EQ(actual.surface_effects, expected.surface_effects) << file << ": vehicle.surface_effects";
    for (const auto& [name, d] : expected.dispersions) {
      const auto it = actual.dispersions.find(name);
      if (it == actual.dispersions.end()) {
        ADD_FAILURE() << file << ": the dispersion " << name << " is missing";
      } else {
        EXPECT_EQ(it->second, d) << file << ": the dispersion " << name;
      }
    }
    for (const auto& [name, d] : actual.dispersions) {
      EXPECT_EQ(expected.dispersions.count(name), 1u) << file << ": the dispersion " << name << " is not the default's";
    }
  }
  for (const Purpose& p : purposes()) EXPECT_EQ(purposes_met.count(p.file), 1u) << p.file << " is not shipped";
}

}  // namespace
}  // namespace shelfcross::verification
