#include "verification/scenario/scenario.hpp"

#include <cmath>
#include <set>
#include <sstream>
#include <tuple>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "config/strict_yaml.hpp"
#include "plant/collision.hpp"

namespace shelfcross::verification {
namespace {

using ::testing::HasSubstr;

const std::string kDefaultPath = std::string(SHELFCROSS_SOURCE_DIR) + "/" + kDefaultScenarioFile;

// A small valid scenario; tests edit one line and expect that line in the error.
const char* const kBase = R"(version: 1
name: small
warehouse:
  shelves:
    - origin_W_m: [3.0, 0.0, 0.0]
      column_pitch_m: [0.34, 0.48]
      row_pitch_m: [0.34, 0.34]
      boxes:
        - {level: 1, column: 1, marker_id: 3}
        - {level: 2, column: 2, marker_id: 4}
start:
  p_WB_m: [0.0, 0.0, 0.0]
)";

std::vector<std::string> lines_of(const std::string& text) {
  std::vector<std::string> lines;
  std::istringstream in(text);
  for (std::string l; std::getline(in, l);) lines.push_back(l);
  return lines;
}

std::string join(const std::vector<std::string>& lines) {
  std::string out;
  for (const std::string& l : lines) out += l + "\n";
  return out;
}

/// kBase with line `n` (from 1) replaced by `text`.
std::string replace_line(int n, const std::string& text) {
  auto lines = lines_of(kBase);
  lines.at(static_cast<size_t>(n - 1)) = text;
  return join(lines);
}

/// kBase with `text` inserted so that it becomes line `n`.
std::string insert_line(int n, const std::string& text) {
  auto lines = lines_of(kBase);
  lines.insert(lines.begin() + (n - 1), text);
  return join(lines);
}

/// Parsing `text` must fail at `line` with a reason containing `reason`.
void expect_refused(const std::string& text, int line, const std::string& reason) {
  try {
    parse_scenario(text, "bad.yaml");
    ADD_FAILURE() << "accepted:\n" << text;
  } catch (const config::ConfigError& e) {
    EXPECT_EQ(e.file(), "bad.yaml");
    EXPECT_EQ(e.line(), line) << e.what();
    EXPECT_THAT(e.reason(), HasSubstr(reason)) << e.what();
    EXPECT_THAT(std::string(e.what()), HasSubstr("bad.yaml:" + std::to_string(line) + ": "));
  }
}

TEST(Scenario, BaseIsValid) {
  const Scenario s = parse_scenario(kBase, "base.yaml");
  EXPECT_EQ(s.name, "small");
  ASSERT_EQ(s.warehouse.shelves.size(), 1u);
  EXPECT_EQ(s.warehouse.shelves[0].boxes.size(), 2u);
  // Everything not written is the structs' default.
  EXPECT_EQ(s.camera, CameraIntrinsics{});
  EXPECT_EQ(s.camera_mount, CameraMount{});
  EXPECT_EQ(s.vehicle, plant::VehicleParams{});
  EXPECT_EQ(s.wind, plant::WindParams{});
  EXPECT_EQ(s.autopilot, plant::AutopilotParams{});
  EXPECT_EQ(s.frame_rate_hz, 30.0);
  EXPECT_EQ(s.warehouse.tag_size_m, Warehouse{}.tag_size_m);
  EXPECT_EQ(s.warehouse.shelves[0].base_height_m, ShelfSpec{}.base_height_m);
  EXPECT_TRUE(s.start.landed);
}

// The shipped decked warehouse is the default scenario but for its decks and its name (the air
// near them, the ground and ceiling effect, is on in both: shipped_senses_test.cpp).
TEST(Scenario, DeckedWarehouseIsTheDefaultWithDecks) {
  Scenario decked = load_scenario(std::string(SHELFCROSS_SOURCE_DIR) + "/scenarios/warehouse_decked.yaml");
  const Scenario plain = load_scenario(kDefaultPath);
  EXPECT_EQ(plain.warehouse.shelves[0].deck_thickness_m, 0.0);
  EXPECT_EQ(decked.warehouse.shelves[0].deck_thickness_m, 0.018);
  EXPECT_NEAR(cell_clear_height_m(decked.warehouse.shelves[0], 2), 0.302, 1e-12);
  EXPECT_NEAR(cell_floor_z_S_m(decked.warehouse.shelves[0], 2), 0.668, 1e-12);
  decked.warehouse.shelves[0].deck_thickness_m = 0.0;
  decked.name = plain.name;
  EXPECT_EQ(decked, plain);
}

TEST(Scenario, DefaultScenarioIsThePaperTestShelf) {
  const Scenario s = load_scenario(kDefaultPath);
  EXPECT_EQ(s.name, "paper_test_shelf");
  ASSERT_EQ(s.warehouse.shelves.size(), 1u);
  const ShelfSpec& shelf = s.warehouse.shelves[0];
  EXPECT_EQ(shelf.column_pitch_m, (std::vector<double>{0.34, 0.48, 0.34, 0.48}));
  EXPECT_EQ(shelf.row_pitch_m, (std::vector<double>{0.34, 0.34, 0.34, 0.34}));
  EXPECT_EQ(shelf.depth_m, 0.34);
  EXPECT_EQ(shelf.origin_W_m, Eigen::Vector3d(3.0, 0.0, 0.0));
  EXPECT_EQ(shelf.yaw_rad, 0.0);
  EXPECT_EQ(s.warehouse.tag_size_m, 0.06);
  EXPECT_EQ(s.warehouse.marker_size_m, 0.10);
  EXPECT_EQ(s.warehouse.aruco_dictionary, "DICT_4X4_50");
  // 3 m from the start to the shelf face, landed, facing it.
  EXPECT_EQ(shelf.origin_W_m.x() - s.start.p_WB_m.x(), 3.0);
  EXPECT_TRUE(s.start.landed);
  EXPECT_EQ(s.start.p_WB_m.z(), 0.0);
  EXPECT_EQ(s.start.yaw_rad, 0.0);
  // The Tello stream, calibration A.
  EXPECT_EQ(s.camera.width_px, 960);
  EXPECT_EQ(s.camera.height_px, 720);
  EXPECT_EQ(s.camera.fx_px, 921.17);
  EXPECT_EQ(s.camera.fy_px, 919.02);
  EXPECT_EQ(s.camera.k1, -0.0335);
  EXPECT_EQ(s.frame_rate_hz, 30.0);
  EXPECT_EQ(s.vehicle.size_m, Eigen::Vector3d(0.098, 0.0925, 0.041));
  // Several cells hold boxes, several are empty, among them one in each middle level.
  EXPECT_GE(shelf.boxes.size(), 8u);
  EXPECT_LE(shelf.boxes.size(), 12u);
  for (int level : {2, 3}) {
    int occupied = 0;
    for (const BoxPlacement& b : shelf.boxes) occupied += b.level == level;
    EXPECT_LT(occupied, 4) << "level " << level << " has no empty cell";
  }
  // The middle levels straddle the takeoff height (level centres 0.81 and 1.15 m).
  EXPECT_NEAR(cell_centre_S_m(shelf, 2, 1).z(), 0.81, 1e-12);
  EXPECT_NEAR(cell_centre_S_m(shelf, 3, 1).z(), 1.15, 1e-12);
}

TEST(Scenario, WriteThenParseRoundTripsExactly) {
  const Scenario s = load_scenario(kDefaultPath);
  const std::string text = write_scenario(s);
  const Scenario again = parse_scenario(text, "written.yaml");
  EXPECT_EQ(again, s);
  EXPECT_EQ(write_scenario(again), text);
  // Doubles that need all 17 digits, negative zero, tiny and huge values survive too.
  Scenario odd = s;
  odd.vehicle.mass_kg = 0.1 + 0.2;
  odd.vehicle.inertia_kgm2 = {1.0 / 3.0, 1e-300, 6.02214076e23};
  odd.camera.k3 = -0.0;
  odd.camera.cx_px = std::nextafter(459.9, 500.0);
  odd.wind.steady_W_mps = {-1.0 / 7.0, 2.0 / 3.0, 0.0};
  odd.autopilot.tilt_limit_slow_rad = 0.123456789012345678;
  odd.warehouse.shelves[0].name = "quote \" and colon: here";
  odd.start = {{0.5, -0.25, 1.0}, 0.3, false};
  const std::string odd_text = write_scenario(odd);
  const Scenario odd_again = parse_scenario(odd_text, "odd.yaml");
  EXPECT_EQ(odd_again, odd);
  EXPECT_TRUE(std::signbit(odd_again.camera.k3));
  EXPECT_EQ(write_scenario(odd_again), odd_text);
}

TEST(Scenario, WrittenTextSpellsOutEveryDefault) {
  const std::string text = write_scenario(parse_scenario(kBase, "base.yaml"));
  for (const char* key : {"version: 1", "mass_kg: 0.08", "motor_dynamics: true", "rate_hz: 500",
                          "tilt_limit_fast_rad: ", "gust_time_constant_s: 1", "fx_px: 921.17",
                          "frame_rate_hz: 30", "pitch_rad: 0", "size_m: 0.06", "landed: true",
                          "aruco_dictionary: \"DICT_4X4_50\"", "- {level: 1, column: 1, marker_id: 3}"}) {
    EXPECT_THAT(text, HasSubstr(key));
  }
}

TEST(Scenario, RandomFillIsDeterministicAndExplicit) {
  // A 4 x 4 shelf with random boxes, and a second shelf whose explicit IDs must be avoided.
  const auto text_for = [&](const std::string& seed) {
    return std::string(R"(name: random
warehouse:
  shelves:
    - origin_W_m: [3.0, 0.0, 0.0]
      column_pitch_m: [0.34, 0.48, 0.34, 0.48]
      row_pitch_m: [0.34, 0.34, 0.34, 0.34]
      random_boxes: {fill_ratio: 0.5, seed: )") +
           seed + R"(}
    - origin_W_m: [3.0, 2.5, 0.0]
      column_pitch_m: [0.34]
      row_pitch_m: [0.34]
      boxes: [{level: 1, column: 1, marker_id: 0}]
start:
  p_WB_m: [0.0, 0.0, 0.0]
)";
  };
  const Scenario a = parse_scenario(text_for("42"), "a.yaml");
  const Scenario b = parse_scenario(text_for("42"), "b.yaml");
  const Scenario c = parse_scenario(text_for("43"), "c.yaml");
  EXPECT_EQ(a, b);
  const auto& boxes = a.warehouse.shelves[0].boxes;
  ASSERT_EQ(boxes.size(), 8u);  // half of 16 cells
  std::set<std::pair<int, int>> cells;
  std::set<int> ids;
  for (const BoxPlacement& box : boxes) {
    EXPECT_TRUE(cells.insert({box.level, box.column}).second);
    EXPECT_TRUE(ids.insert(box.marker_id).second);
    EXPECT_GE(box.level, 1);
    EXPECT_LE(box.level, 4);
    EXPECT_GE(box.column, 1);
    EXPECT_LE(box.column, 4);
    EXPECT_GE(box.marker_id, 1) << "ID 0 belongs to the other shelf's box";
    EXPECT_LT(box.marker_id, 50);
  }
  EXPECT_NE(a.warehouse.shelves[0].boxes, c.warehouse.shelves[0].boxes);
  // The resolved placements are written explicitly and read back the same.
  const std::string text = write_scenario(a);
  EXPECT_THAT(text, ::testing::Not(HasSubstr("random_boxes")));
  EXPECT_EQ(parse_scenario(text, "written.yaml"), a);
}

TEST(Scenario, RefusesUnknownKey) {
  expect_refused(insert_line(4, "  colour: red"), 4, "unknown key 'colour'");
  expect_refused(insert_line(12, "  height_m: 1.0"), 12, "unknown key 'height_m'");
  // Later issues add these sections; until then they are refused, not silently ignored.
  expect_refused(insert_line(11, "cosim: {rate_hz: 500}"), 11, "unknown key 'rate_hz'");
  expect_refused(insert_line(11, "dispersions: {gravity_mps2: {uniform: {min: 9, max: 10}}}"), 11,
                 "unknown key 'gravity_mps2'");
}

TEST(Scenario, RefusesAKeyGivenTwice) {
  // width_px twice in camera: one value would otherwise be silently ignored.
  expect_refused(insert_line(11, "camera:\n  width_px: 960\n  width_px: 961"), 13,
                 "key 'width_px' given twice (first on line 12)");
  expect_refused(insert_line(3, "name: again"), 3, "key 'name' given twice (first on line 2)");
  expect_refused(insert_line(11, "cosim: {link: {model: sdk, model: ideal}}"), 11, "key 'model' given twice");
}

TEST(Scenario, LinkModelIsSdkByDefaultAndRefusesUnknownModels) {
  EXPECT_EQ(parse_scenario(kBase, "small.yaml").cosim.link.model, "sdk");
  EXPECT_EQ(parse_scenario(insert_line(11, "cosim: {link: {model: ideal}}"), "ideal.yaml").cosim.link.model, "ideal");
  expect_refused(insert_line(11, "cosim: {link: {model: wifi}}"), 11, "unknown link model 'wifi' (sdk or ideal)");
  expect_refused(insert_line(11, "cosim: {link: {video_datagram_loss: 1.5}}"), 11, "video_datagram_loss");
  expect_refused(insert_line(11, "cosim: {pilot: {stop_rc_repeats: -1}}"), 11, "stop_rc_repeats");
}

TEST(Scenario, RefusesEachBurstAndOutageKeyOutOfRange) {
  const std::vector<std::pair<const char*, const char*>> keys{
      {"burst_loss", "1.01"},        {"burst_loss", "-0.1"},          {"burst_mean_s", "-0.1"},
      {"burst_mean_s", "61"},        {"burst_interval_s", "0.05"},    {"burst_interval_s", "3601"},
      {"outage_interval_s", "-1"},   {"outage_interval_s", "3601"},   {"outage_min_s", "0"},
      {"outage_max_s", "61"},        {"outage_start_s", "-2"},        {"outage_duration_s", "61"},
  };
  for (const auto& [key, value] : keys) {
    expect_refused(insert_line(11, std::string("cosim:\n  link:\n    ") + key + ": " + value), 13, "out of range");
  }
  expect_refused(insert_line(11, "cosim:\n  link:\n    outage_interval_s: 0.5"), 13, "at least 1 s");
  expect_refused(insert_line(11, "cosim:\n  link:\n    outage_min_s: 3\n    outage_max_s: 2"), 14,
                 "must not be below outage_min_s");
  // Off by default; every key read back as written, and on to the fault model.
  const LinkSettings off = parse_scenario(kBase, "small.yaml").cosim.link;
  EXPECT_EQ(off.spells.burst_mean_s, 0.0);
  EXPECT_EQ(off.spells.outage_interval_s, 0.0);
  EXPECT_LT(off.spells.outage_start_s, 0.0);
  const Scenario s = parse_scenario(
      insert_line(11, "cosim: {link: {burst_loss: 0.8, burst_mean_s: 0.3, burst_interval_s: 20, outage_interval_s: 60, "
                      "outage_min_s: 2, outage_max_s: 4, outage_start_s: 30, outage_duration_s: 3}}"),
      "bursts.yaml");
  EXPECT_EQ(s.cosim.link.spells.burst_loss, 0.8);
  EXPECT_EQ(s.cosim.link.spells.burst_mean_s, 0.3);
  EXPECT_EQ(s.cosim.link.spells.burst_interval_s, 20.0);
  EXPECT_EQ(s.cosim.link.spells.outage_interval_s, 60.0);
  EXPECT_EQ(s.cosim.link.spells.outage_min_s, 2.0);
  EXPECT_EQ(s.cosim.link.spells.outage_max_s, 4.0);
  EXPECT_EQ(s.cosim.link.spells.outage_start_s, 30.0);
  EXPECT_EQ(s.cosim.link.spells.outage_duration_s, 3.0);
  EXPECT_EQ(parse_scenario(write_scenario(s), "again.yaml"), s);
}

TEST(Scenario, RefusesWrongType) {
  expect_refused(insert_line(11, "camera: {frame_rate_hz: fast}"), 11, "expected a number");
  expect_refused(replace_line(9, "        - {level: one, column: 1, marker_id: 3}"), 9,
                 "expected an integer");
  expect_refused(insert_line(11, "vehicle: {switches: {wind: maybe}}"), 11, "expected a boolean");
  expect_refused(replace_line(5, "    - origin_W_m: [3.0, 0.0]"), 5, "expected a list of 3 values");
  auto lines = lines_of(kBase);
  lines.erase(lines.begin() + 4, lines.begin() + 10);  // the shelf's items
  lines[3] = "  shelves: {a: 1}";
  expect_refused(join(lines), 4, "expected a list of mappings");
}

TEST(Scenario, RefusesMissingRequiredField) {
  // No start: reported at the mapping that lacks it (the document's first line).
  auto lines = lines_of(kBase);
  lines.resize(10);
  expect_refused(join(lines), 1, "missing required section 'start'");
  expect_refused(replace_line(6, "      depth_m: 0.34"), 5, "missing required key 'column_pitch_m'");
  expect_refused(replace_line(2, "title: small"), 1, "missing required key 'name'");
}

TEST(Scenario, RefusesOutOfRangeValues) {
  expect_refused(insert_line(11, "vehicle: {mass_kg: -0.08}"), 11, "out of range");
  expect_refused(insert_line(11, "vehicle: {mass_kg: 0}"), 11, "out of range");
  expect_refused(insert_line(11, "camera: {fx_px: 0}"), 11, "out of range");
  expect_refused(insert_line(11, "camera: {fy_px: -900}"), 11, "out of range");
  expect_refused(insert_line(11, "camera: {width_px: 0}"), 11, "out of range");
  expect_refused(insert_line(11, "camera: {height_px: -720}"), 11, "out of range");
  expect_refused(insert_line(11, "camera: {frame_rate_hz: 241}"), 11, "out of range");
  expect_refused(insert_line(11, "camera: {frame_rate_hz: 0.5}"), 11, "out of range");
  expect_refused(insert_line(11, "vehicle: {surface_effects: {ground_coeff: -0.1}}"), 11, "out of range");
  expect_refused(insert_line(11, "vehicle: {surface_effects: {ground_coeff: 2.5}}"), 11, "out of range");
  expect_refused(insert_line(11, "vehicle: {surface_effects: {ceiling_coeff: 3}}"), 11, "out of range");
  expect_refused(insert_line(11, "vehicle: {surface_effects: {ceiling_range_radii: 0.1}}"), 11, "out of range");
  expect_refused(insert_line(11, "vehicle: {surface_effects: {rotor_radius_m: 0}}"), 11, "out of range");
  expect_refused(insert_line(11, "vehicle: {surface_effects: {rotor_radius_m: 0.5}}"), 11, "not a Tello-class rotor");
  expect_refused(insert_line(11, "dispersions: {ground_effect_coeff: {uniform: {min: 0.5, max: 2.5}}}"), 11, "ground_effect_coeff");
  expect_refused(insert_line(11, "cosim: {near_miss_m: -0.01}"), 11, "out of range");
  expect_refused(insert_line(11, "cosim: {near_miss_m: 0.6}"), 11, "out of range");
  expect_refused(insert_line(11, "camera: {width_px: 960, cx_px: 961}"), 11, "principal point");
  expect_refused(replace_line(6, "      column_pitch_m: [0.34, -0.48]"), 6, "out of range");
  expect_refused(insert_line(6, "      depth_m: -0.34"), 6, "out of range");
  expect_refused(insert_line(6, "      deck_thickness_m: -0.01"), 6, "out of range");
  expect_refused(insert_line(6, "      deck_thickness_m: 0.2"), 6, "out of range");
  // A 9 cm deck leaves 0.34 - 0.02 - 0.09 = 0.23 m: the 0.24 m boxes no longer fit.
  expect_refused(insert_line(6, "      deck_thickness_m: 0.09"), 10, "does not fit the clear height");
  expect_refused(insert_line(6, "      post_thickness_m: 0"), 6, "out of range");
  expect_refused(insert_line(11, "autopilot: {tilt_limit_slow_rad: 0.5, tilt_limit_fast_rad: 0.4}"),
                 11, "tilt_limit_slow_rad");
  expect_refused(insert_line(11, "wind: {gust_stddev_mps: -1}"), 11, "out of range");
}

TEST(Scenario, CameraReadoutTimeInRange) {
  EXPECT_EQ(parse_scenario(kBase, "base.yaml").readout_s, 0.0);  // a global shutter by default
  const Scenario s = parse_scenario(insert_line(11, "camera: {readout_s: 0.02}"), "rolling.yaml");
  EXPECT_EQ(s.readout_s, 0.02);
  EXPECT_EQ(parse_scenario(write_scenario(s), "again.yaml"), s);
  expect_refused(insert_line(11, "camera: {readout_s: -0.001}"), 11, "out of range");
  expect_refused(insert_line(11, "camera: {readout_s: 0.2}"), 11, "out of range");
  expect_refused(insert_line(11, "camera: {readout_s: 0.05}"), 11, "one frame period");
  expect_refused(insert_line(11, "camera: {readout_s: soon}"), 11, "expected a number");
}

TEST(Scenario, RefusesEachSensesKeyOutOfRange) {
  // Every key of the senses section, just outside its range, on its own line.
  expect_refused(insert_line(11, "senses:\n  sample_rate_hz: 0.5"), 12, "out of range");
  const std::vector<std::tuple<const char*, const char*, const char*>> keys{
      {"vps", "min_range_m", "10.5"},          {"vps", "max_range_m", "101"},
      {"vps", "min_contrast", "1.1"},          {"vps", "noise_mps", "-0.1"},
      {"vps", "bias_stddev_mps", "1.5"},       {"vps", "bias_time_constant_s", "0.05"},
      {"height", "tof_max_range_m", "0.05"},   {"height", "tof_ground_m", "-0.1"},
      {"height", "tof_noise_m", "1.5"},        {"height", "height_noise_m", "-1"},
      {"height", "baro_noise_m", "6"},         {"height", "baro_drift_m_per_sqrt_s", "2"},
      {"height_hold", "range_blend", "1.5"},   {"height_hold", "range_below_m", "-1"},
      {"height_hold", "time_constant_s", "0"},
  };
  for (const auto& [section, key, value] : keys) {
    expect_refused(insert_line(11, std::string("senses:\n  ") + section + ":\n    " + key + ": " + value), 13,
                   "out of range");
  }
  for (const char* kind : {"floor", "box", "bar", "tag", "wall"}) {
    expect_refused(insert_line(11, std::string("senses:\n  vps:\n    texture:\n      ") + kind + ": 1.01"), 14,
                   "out of range");
  }
  expect_refused(insert_line(11, "senses:\n  vps:\n    min_range_m: 0.5\n    max_range_m: 0.4"), 14,
                 "must not be below min_range_m");
  // The defaults sense the truth; every key read back as written.
  const Scenario s = parse_scenario(
      insert_line(11, "senses: {vps: {min_range_m: 0.3, texture: {box: 0.2}}, height_hold: {range_blend: 0.5}}"),
      "senses.yaml");
  EXPECT_EQ(s.senses.vps.min_range_m, 0.3);
  EXPECT_EQ(s.senses.vps.texture.box, 0.2);
  EXPECT_EQ(s.senses.height_hold.range_blend, 0.5);
  EXPECT_EQ(parse_scenario(kBase, "small.yaml").senses, plant::SensesParams{});
}

TEST(Scenario, RefusesBoxInNonExistentCell) {
  expect_refused(replace_line(10, "        - {level: 3, column: 2, marker_id: 4}"), 10,
                 "level 3 does not exist");
  expect_refused(replace_line(10, "        - {level: 2, column: 5, marker_id: 4}"), 10,
                 "column 5 does not exist");
  expect_refused(replace_line(10, "        - {level: 0, column: 1, marker_id: 4}"), 10, "out of range");
}

TEST(Scenario, RefusesTwoBoxesInOneCell) {
  expect_refused(replace_line(10, "        - {level: 1, column: 1, marker_id: 4}"), 10,
                 "two boxes in the cell at level 1, column 1");
}

TEST(Scenario, RefusesDuplicateMarkerId) {
  expect_refused(replace_line(10, "        - {level: 2, column: 2, marker_id: 3}"), 10,
                 "marker ID 3 is used by another box");
}

TEST(Scenario, RefusesMarkerIdBeyondDictionary) {
  expect_refused(replace_line(10, "        - {level: 2, column: 2, marker_id: 50}"), 10,
                 "beyond DICT_4X4_50");
  expect_refused(insert_line(4, "  boxes: {aruco_dictionary: DICT_9X9_50}"), 4,
                 "unknown ArUco dictionary");
}

TEST(Scenario, RefusesMarkerLargerThanBoxFace) {
  expect_refused(insert_line(4, "  boxes: {size_m: [0.2, 0.2, 0.2], marker_size_m: 0.21}"), 4,
                 "larger than the box face");
}

TEST(Scenario, RefusesBoxThatDoesNotFitItsCell) {
  // 0.33 m boxes fit the wide column (clear 0.46) but not the narrow one (clear 0.32).
  expect_refused(insert_line(4, "  boxes: {size_m: [0.3, 0.33, 0.3]}"), 9 + 1,
                 "does not fit the clear width");
  expect_refused(insert_line(4, "  boxes: {size_m: [0.3, 0.2, 0.33]}"), 9 + 1,
                 "does not fit the clear height");
  // Deeper than the room between the front and back posts: reported at the shelf (line 5 + 1).
  expect_refused(insert_line(4, "  boxes: {size_m: [0.33, 0.2, 0.2]}"), 5 + 1,
                 "do not fit between the front and back posts");
}

TEST(Scenario, RefusesTagLargerThanCell) {
  expect_refused(insert_line(4, "  tags: {size_m: 0.40}"), 6 + 1, "larger than the cell pitch");
}

TEST(Scenario, RefusesBoxesAndRandomBoxesTogether) {
  expect_refused(insert_line(8, "      random_boxes: {fill_ratio: 0.5, seed: 1}"), 8,
                 "either 'boxes' or 'random_boxes'");
  auto lines = lines_of(kBase);
  lines.erase(lines.begin() + 8, lines.begin() + 10);  // the two box items
  lines[7] = "      random_boxes: {fill_ratio: 1.5, seed: 1}";
  expect_refused(join(lines), 8, "out of range");
  lines[7] = "      random_boxes: {fill_ratio: 0.5}";
  expect_refused(join(lines), 8, "missing required key 'seed'");
  lines[7] = "      random_boxes: {fill_ratio: 0.5, seed: -3}";
  expect_refused(join(lines), 8, "expected an integer");
}

TEST(Scenario, RefusesBadStart) {
  expect_refused(replace_line(12, "  p_WB_m: [0.0, 0.0, 0.5]"), 12, "z must be 0");
  // Landed inside the post between the shelf's columns (y = 0.0 at x = 3.0).
  expect_refused(replace_line(12, "  p_WB_m: [3.0, 0.07, 0.0]"), 12,
                 "would start inside the shelf 0 post between columns 1 and 2, front face");
  expect_refused(replace_line(12, "  p_WB_m: [-2.0, 0.0, 0.0]"), 12, "would start inside the wall x-");
}

TEST(Scenario, RefusesBadNameVersionAndSyntax) {
  expect_refused(replace_line(2, "name: my scenario"), 2, "a name is");
  expect_refused(replace_line(1, "version: 2"), 1, "out of range");
  expect_refused(replace_line(9, "        - {level: 1, column: 1, marker_id: 3"), 10, "YAML syntax");
  expect_refused(replace_line(5, "    - origin_W_m: [3.0, 0.0, 0.5]"), 5, "stands on the floor");
  expect_refused(replace_line(5, "    - origin_W_m: [30.0, 0.0, 0.0]"), 5, "inside the arena");
}

TEST(Scenario, RefusesTextThatIsNotUtf8) {
  // Found by fuzz/scenario_fuzz: a shelf name with a byte that is not UTF-8 was accepted and
  // written back as U+FFFD ("a\xffb" -> "a\uFFFDb"), so parse(write(s)) != s. Any string key
  // is refused with its line instead: stray bytes, a truncated sequence, an overlong form, a
  // surrogate.
  for (const std::string bad : {"a\xff" "b", "a\xc3", "\xc0\xaf", "\xed\xa0\x80", "\xf4\x90\x80\x80"}) {
    expect_refused(insert_line(6, "      name: \"x" + bad + "\""), 6, "not valid UTF-8");
    expect_refused(insert_line(6, "      name: x" + bad), 6, "not valid UTF-8");
  }
  // UTF-8 text, multi-byte sequences up to four bytes, is kept and round-trips.
  const std::string utf8 = "Regal \xc3\x84 \xe2\x82\xac \xf0\x9f\x93\xa6";
  const Scenario s = parse_scenario(insert_line(6, "      name: \"" + utf8 + "\""), "utf8.yaml");
  EXPECT_EQ(s.warehouse.shelves.at(0).name, utf8);
  EXPECT_EQ(parse_scenario(write_scenario(s), "written.yaml"), s);
}

TEST(Scenario, MissingFileIsAConfigError) {
  try {
    load_scenario("/nonexistent/scenario.yaml");
    ADD_FAILURE();
  } catch (const config::ConfigError& e) {
    EXPECT_EQ(e.file(), "/nonexistent/scenario.yaml");
    EXPECT_THAT(e.reason(), HasSubstr("cannot open"));
  }
}

TEST(Scenario, DefaultScenarioBuildsACollisionWorld) {
  const Scenario s = load_scenario(kDefaultPath);
  const plant::CollisionWorld world(s.warehouse, s.vehicle.size_m, 0.0);
  Eigen::Isometry3d X_WB = Eigen::Isometry3d::Identity();
  X_WB.translation() = s.start.p_WB_m + Eigen::Vector3d(0, 0, 0.5 * s.vehicle.size_m.z());
  // From the start, the nearest shelf part is the post straight ahead (at y = 0, from the
  // floor up): 3 m less its half thickness and the vehicle's half length.
  const plant::Clearance c = world.clearance_to_shelves(X_WB);
  EXPECT_NEAR(c.distance_m, 3.0 - 0.01 - 0.5 * s.vehicle.size_m.x(), 1e-6);
  EXPECT_EQ(c.element.name, "shelf 0 post between columns 2 and 3, front face");
}

}  // namespace
}  // namespace shelfcross::verification
