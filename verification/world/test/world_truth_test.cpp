// The world's truth in JSON: the keys a run's metrics and the emulator's report share, written
// and read back, and the report printing the same facts under the same keys.

#include "verification/world/world_truth.hpp"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "config/strict_json.hpp"
#include "verification/world/tello_emulator_settings.hpp"

namespace shelfcross::verification {
namespace {

using nlohmann::json;

WorldTruth full_truth() {
  WorldTruth t;
  t.path_length_m = 6.0625;
  t.floor_touches = 2;
  plant::Contact c;
  c.t_ns = 12'345'678'901;
  c.element.name = "shelf 0 beam 2";
  c.element.kind = plant::ElementKind::beam;
  c.point_W_m = {1.5, -0.25, 0.75};
  c.depth_m = 0.003;
  t.contact = c;
  t.crossed = CellIndex{1, 2};
  t.entry_offset_y_m = -0.0425;
  t.entry_offset_z_m = 0.0175;
  t.min_clearance_m = 0.0925;
  return t;
}

TEST(WorldTruthJson, TheSharedKeysReadBackToTheSameText) {
  json j = json::object();
  write_world_truth(j, full_truth());
  EXPECT_EQ(j.size(), 6u);  // floor_touches is the run's alone
  EXPECT_FALSE(j.contains("floor_touches"));
  config::StrictObject o(j, "truth");
  const WorldTruth back = read_world_truth(o);
  o.finish();
  json again = json::object();
  write_world_truth(again, back);
  EXPECT_EQ(again.dump(), j.dump());
  EXPECT_EQ(back.crossed, (CellIndex{1, 2}));
  ASSERT_TRUE(back.contact.has_value());
  EXPECT_EQ(back.contact->t_ns, 12'345'678'901);
  EXPECT_EQ(back.contact->element.kind, plant::ElementKind::beam);

  // Nothing measured: null, not missing.
  json none = json::object();
  write_world_truth(none, WorldTruth{});
  EXPECT_EQ(none.dump(), R"({"contact":null,"crossed":null,"entry_offset_y_m":null,"entry_offset_z_m":null,)"
                         R"("min_clearance_m":null,"path_length_m":0.0})");
}

TEST(WorldTruthJson, TheEmulatorReportPrintsTheTruthUnderTheSameKeys) {
  EmulatorReport r;
  r.truth = full_truth();
  const json report = json::parse(emulator_report_json(r));
  json shared = json::object();
  write_world_truth(shared, r.truth);
  for (const auto& [key, value] : shared.items()) EXPECT_EQ(report.at(key), value) << key;
  EXPECT_FALSE(report.contains("floor_touches"));
}

}  // namespace
}  // namespace shelfcross::verification
