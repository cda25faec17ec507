#include "verification/scenario/dispersion.hpp"

#include <algorithm>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "verification/scenario/scenario.hpp"

namespace shelfcross::verification {
namespace {

const std::string kDefault = std::string(SHELFCROSS_SOURCE_DIR) + "/scenarios/paper_test_shelf.yaml";

Scenario with_dispersions(const std::string& yaml_section) {
  Scenario s = load_scenario(kDefault);
  std::string text = write_scenario(s);
  text = text.substr(0, text.find("dispersions:")) + yaml_section;
  return parse_scenario(text, "d.yaml");
}

TEST(Dispersion, DrawsDependOnlyOnSeedAndParameter) {
  const Scenario a = with_dispersions(
      "dispersions:\n  start_distance_m: {uniform: {min: 2.5, max: 3.5}}\n"
      "  start_yaw_rad: {truncated_normal: {mean: 0, stddev: 0.05, min: -0.2, max: 0.2}}\n");
  const Scenario b = with_dispersions("dispersions:\n  start_distance_m: {uniform: {min: 2.5, max: 3.5}}\n");
  for (std::uint64_t seed : {1ull, 2ull, 99ull}) {
    const DrawnValues da = draw_dispersions(a.dispersions, seed);
    EXPECT_EQ(da, draw_dispersions(a.dispersions, seed));
    // Adding start_yaw_rad did not move the draw of start_distance_m.
    EXPECT_EQ(da.at("start_distance_m"), draw_dispersions(b.dispersions, seed).at("start_distance_m"));
  }
  EXPECT_NE(draw_dispersions(a.dispersions, 1), draw_dispersions(a.dispersions, 2));
}

TEST(Dispersion, AppliesDrawsToTruthAndBeliefs) {
  const Scenario s = with_dispersions(
      "dispersions:\n"
      "  start_distance_m: {uniform: {min: 2.0, max: 2.0}}\n"
      "  start_lateral_m: {choice: {values: [0.25]}}\n"
      "  camera_focal_error_rel: {choice: {values: [0.1]}}\n"
      "  camera_cx_error_px: {choice: {values: [-4]}}\n"
      "  rc_gain_scale: {choice: {values: [2]}}\n"
      "  light_scale: {choice: {values: [0.5]}}\n"
      "  wind_speed_mps: {choice: {values: [1.0]}}\n"
      "  wind_direction_rad: {choice: {values: [1.5707963267948966]}}\n"
      "  frame_drop_probability: {choice: {values: [0.2]}}\n");
  const RunSetup run = disperse(s, 5);
  const Scenario& d = *run.scenario;
  const double face_x = s.warehouse.shelves[0].origin_W_m.x();
  EXPECT_DOUBLE_EQ(d.start.p_WB_m.x(), face_x - 2.0);
  EXPECT_DOUBLE_EQ(d.start.p_WB_m.y(), s.start.p_WB_m.y() + 0.25);
  EXPECT_DOUBLE_EQ(run.believed_camera.fx_px, s.camera.fx_px * 1.1);
  EXPECT_DOUBLE_EQ(run.believed_camera.cx_px, s.camera.cx_px - 4.0);
  EXPECT_EQ(d.camera, s.camera);  // the truth's camera is untouched
  EXPECT_DOUBLE_EQ(d.autopilot.rc_horizontal_mps_at_100, 2.0 * s.autopilot.rc_horizontal_mps_at_100);
  EXPECT_DOUBLE_EQ(d.warehouse.lighting.ambient, 0.5 * s.warehouse.lighting.ambient);
  EXPECT_NEAR(d.wind.steady_W_mps.x(), 0.0, 1e-12);
  EXPECT_NEAR(d.wind.steady_W_mps.y(), 1.0, 1e-12);
  EXPECT_DOUBLE_EQ(d.cosim.link.frame_drop_probability, 0.2);
}

// The stress family: the shelf behind (shelf 1) placed by its draws in shelf 0's frame,
// uneven light; the shelf-behind parameters need two shelves.
TEST(Dispersion, DrawsSetTheLinksBurstsAndOutages) {
  const Scenario s = with_dispersions(
      "dispersions:\n"
      "  burst_loss: {choice: {values: [0.8]}}\n"
      "  burst_mean_s: {choice: {values: [0.2]}}\n"
      "  burst_interval_s: {choice: {values: [12]}}\n"
      "  outage_interval_s: {choice: {values: [60]}}\n"
      "  outage_start_s: {choice: {values: [18]}}\n"
      "  outage_duration_s: {choice: {values: [3]}}\n");
  const RunSetup run = disperse(s, 5);
  const LinkSpells& d = run.scenario->cosim.link.spells;
  EXPECT_DOUBLE_EQ(d.burst_loss, 0.8);
  EXPECT_DOUBLE_EQ(d.burst_mean_s, 0.2);
  EXPECT_DOUBLE_EQ(d.burst_interval_s, 12.0);
  EXPECT_DOUBLE_EQ(d.outage_interval_s, 60.0);
  EXPECT_DOUBLE_EQ(d.outage_start_s, 18.0);
  EXPECT_DOUBLE_EQ(d.outage_duration_s, 3.0);
  // A draw cannot leave the key's range: the random outages' interval is never drawn below 1 s.
  EXPECT_THROW(with_dispersions("dispersions:\n  outage_interval_s: {uniform: {min: 0.0, max: 10.0}}\n"),
               config::ConfigError);
}

TEST(Dispersion, PlacesTheShelfBehindAndTurnsTheLight) {
  const std::string row = std::string(SHELFCROSS_SOURCE_DIR) + "/scenarios/stress/row_shelf_behind.yaml";
  Scenario s = load_scenario(row);
  std::string text = write_scenario(s);
  text = text.substr(0, text.find("dispersions:")) +
         "dispersions:\n  shelf_behind_distance_m: {choice: {values: [1.5]}}\n"
         "  shelf_behind_lateral_m: {choice: {values: [-0.3]}}\n"
         "  ambient_scale: {choice: {values: [0.5]}}\n"
         "  light_azimuth_rad: {choice: {values: [1.5707963267948966]}}\n";
  s = parse_scenario(text, "row.yaml");
  const RunSetup setup = disperse(s, 3);  // owns the dispersed scenario
  const Scenario& d = *setup.scenario;
  const Eigen::Vector3d& front = s.warehouse.shelves[0].origin_W_m;
  EXPECT_DOUBLE_EQ(d.warehouse.shelves[1].origin_W_m.x(), front.x() + 1.5);
  EXPECT_DOUBLE_EQ(d.warehouse.shelves[1].origin_W_m.y(), s.warehouse.shelves[1].origin_W_m.y() - 0.3);
  EXPECT_EQ(d.warehouse.shelves[0].origin_W_m, front);
  EXPECT_EQ(d.warehouse.shelves[1].yaw_rad, d.warehouse.shelves[0].yaw_rad);
  EXPECT_DOUBLE_EQ(d.warehouse.lighting.ambient, 0.5 * s.warehouse.lighting.ambient);
  const Eigen::Vector3d& l0 = s.warehouse.lighting.direction_W;
  const Eigen::Vector3d& l = d.warehouse.lighting.direction_W;
  EXPECT_NEAR(l.x(), 0.0, 1e-12);
  EXPECT_NEAR(l.y(), l0.head<2>().norm(), 1e-12);
  EXPECT_DOUBLE_EQ(l.z(), l0.z());
  // One shelf: refused with the line of the dispersions.
  EXPECT_THROW(with_dispersions("dispersions:\n  shelf_behind_distance_m: {choice: {values: [1.5]}}\n"),
               config::ConfigError);
}

TEST(Dispersion, BoxPlacementIsRedrawnPerRun) {
  const Scenario s = with_dispersions("dispersions:\n  box_fill_ratio: {uniform: {min: 0.5, max: 0.5}}\n");
  const RunSetup a = disperse(s, 1), b = disperse(s, 2), a2 = disperse(s, 1);
  const auto& boxes = a.scenario->warehouse.shelves[0].boxes;
  EXPECT_EQ(boxes.size(), 8u);  // half of the 16 cells
  EXPECT_EQ(boxes, a2.scenario->warehouse.shelves[0].boxes);
  EXPECT_NE(boxes, b.scenario->warehouse.shelves[0].boxes);
}

TEST(Dispersion, ScenarioRoundTripsAndRefusesUnsafeSupports) {
  const Scenario s = load_scenario(kDefault);
  EXPECT_FALSE(s.dispersions.empty());
  EXPECT_EQ(parse_scenario(write_scenario(s), "w.yaml"), s);
  try {
    with_dispersions("dispersions:\n  frame_drop_probability: {normal: {mean: 0.1, stddev: 0.05}}\n");
    FAIL() << "a normal on a probability was accepted";
  } catch (const config::ConfigError& e) {
    EXPECT_THAT(e.reason(), ::testing::HasSubstr("allowed range"));
  }
  EXPECT_THROW(with_dispersions("dispersions:\n  start_distance_m: {uniform: {min: 0.1, max: 3}}\n"),
               config::ConfigError);
}

}  // namespace
}  // namespace shelfcross::verification

namespace shelfcross::verification {
namespace {

// The beyond-envelope family (scenarios/README.md): each file loads, keeps the default
// scenario's dispersions except its own family, and widens that family past the certified
// range as documented.
TEST(Dispersion, BeyondEnvelopeScenariosWidenTheirFamilyOnly) {
  const std::string dir = std::string(SHELFCROSS_SOURCE_DIR) + "/scenarios/";
  const Scenario nominal = load_scenario(dir + "paper_test_shelf.yaml");
  struct Widened {
    const char* file;
    std::vector<std::pair<const char*, std::pair<double, double>>> ranges;  // name: (lowest, highest)
  };
  const std::vector<Widened> family = {
      {"beyond_gusts.yaml", {{"gust_stddev_mps", {0.5, 1.5}}}},
      {"beyond_drafts.yaml", {{"wind_speed_mps", {0.5, 1.2}}}},
      {"beyond_autopilot.yaml",
       {{"rc_gain_scale", {0.5, 2.0}}, {"velocity_time_constant_s", {0.15, 1.4}},
        {"vertical_time_constant_s", {0.15, 1.2}}, {"yaw_time_constant_s", {0.1, 0.9}}}},
      {"beyond_calibration.yaml",
       {{"camera_focal_error_rel", {-0.09, 0.09}}, {"camera_cx_error_px", {-27.0, 27.0}},
        {"camera_cy_error_px", {-27.0, 27.0}}}},
      {"beyond_link.yaml",
       {{"video_latency_mean_s", {0.12, 0.6}}, {"video_datagram_loss", {0.0, 0.1}}, {"state_loss", {0.0, 0.1}},
        {"reply_loss", {0.0, 0.1}}}},
  };
  for (const Widened& w : family) {
    const Scenario s = load_scenario(dir + "stress/" + w.file);
    for (const auto& [name, range] : w.ranges) {
      ASSERT_TRUE(s.dispersions.count(name)) << w.file << ": " << name;
      EXPECT_NEAR(s.dispersions.at(name).lowest(), range.first, 1e-12) << w.file << ": " << name;
      EXPECT_NEAR(s.dispersions.at(name).highest(), range.second, 1e-12) << w.file << ": " << name;
    }
    for (const auto& [name, d] : nominal.dispersions) {
      const bool own = std::any_of(w.ranges.begin(), w.ranges.end(), [&](const auto& r) { return name == r.first; });
      if (!own) {
        EXPECT_EQ(s.dispersions.at(name), d) << w.file << ": " << name << " changed";
      }
    }
    EXPECT_EQ(s.cosim.link.model, nominal.cosim.link.model) << w.file;
  }
}

// The default scenario draws the senses (scenarios/README.md, section `senses`; every shipped
// scenario carries them as it does: shipped_senses_test.cpp); each senses draw lands in its key.
TEST(Dispersion, EachSensesDrawLandsInItsKey) {
  const Scenario s = load_scenario(kDefault);
  EXPECT_NE(s.senses, plant::SensesParams{});
  const RunSetup r = disperse(s, 7);
  const plant::SensesParams& p = r.scenario->senses;
  const std::vector<std::pair<std::string, double>> applied{
      {"vps_noise_mps", p.vps.noise_mps},
      {"vps_bias_stddev_mps", p.vps.bias_stddev_mps},
      {"vps_min_range_m", p.vps.min_range_m},
      {"vps_floor_texture", p.vps.texture.floor},
      {"vps_box_texture", p.vps.texture.box},
      {"vps_bar_texture", p.vps.texture.bar},
      {"tof_noise_m", p.height.tof_noise_m},
      {"height_noise_m", p.height.height_noise_m},
      {"baro_noise_m", p.height.baro_noise_m},
      {"baro_drift_m_per_sqrt_s", p.height.baro_drift_m_per_sqrt_s},
      {"height_hold_range_blend", p.height_hold.range_blend},
      {"height_hold_range_below_m", p.height_hold.range_below_m},
      {"height_hold_time_constant_s", p.height_hold.time_constant_s}};
  for (const auto& [key, value] : applied) EXPECT_EQ(value, r.drawn.at(key)) << key;
}

}  // namespace
}  // namespace shelfcross::verification
