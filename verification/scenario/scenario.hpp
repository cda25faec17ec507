#pragma once
// Scenario files: the world (warehouse), the camera, the vehicle, its autopilot, the wind and
// the start state of one simulated flight, as a YAML file (format: scenarios/README.md).
//
//   Scenario s = load_scenario("scenarios/paper_test_shelf.yaml");   // throws config::ConfigError
//   std::string yaml = write_scenario(s);   // every value spelled out; parse(write(s)) == s
//
// Loading is strict: an unknown key, a value of the wrong type, a missing required key, a value
// out of its range, or an inconsistent whole (a box in a cell that does not exist, two boxes in
// one cell, a marker ID used twice or beyond its dictionary, a marker larger than the box face,
// a box that does not fit its cell, a tag larger than a cell, a start inside a shelf, ...) is
// refused with a config::ConfigError whose what() reads "file:line: reason".
// Random box placement ("random_boxes: {fill_ratio, seed}") is resolved at load time from a
// seeded stream, so a loaded Scenario holds explicit placements only and its written form lists
// them; the same file always gives the same boxes, on every machine.
// Top-level sections: version, name, warehouse, camera, vehicle, wind, autopilot, senses, start,
// cosim (co-simulation and link settings, cosim_settings.hpp) and dispersions (campaign
// distributions over the named parameters of dispersion.hpp).

#include <map>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "config/config_error.hpp"
#include "plant/params.hpp"
#include "plant/tello_senses.hpp"
#include "shelfcross/camera.hpp"
#include "shelfcross/random.hpp"
#include "shelfcross/warehouse.hpp"
#include "verification/scenario/cosim_settings.hpp"
#include "verification/scenario/distribution.hpp"

namespace shelfcross::verification {

/// Where the vehicle is when the run starts.
struct StartState {
  /// Landed: (x, y) of the body origin on the floor and z = 0 (the floor), i.e. the vehicle
  /// rests on the floor and its body origin is half its height up (the plant places it).
  /// Not landed (hovering): the body origin B itself, z above half the vehicle's height.
  Eigen::Vector3d p_WB_m = Eigen::Vector3d::Zero();
  double yaw_rad = 0.0;  ///< heading about z_W (0: facing +x_W, toward the shelves)
  bool landed = true;
  bool operator==(const StartState&) const = default;
};

struct Scenario {
  std::string name;  ///< a short id: letters, digits, '_', '-', '.'
  Warehouse warehouse;  ///< boxes resolved to explicit placements
  CameraIntrinsics camera;
  CameraMount camera_mount;
  double frame_rate_hz = 30.0;  ///< the video stream (docs/tello_sdk.md: 30 fps)
  /// Rolling shutter: the time from the first row's exposure to one row past the last (0: a
  /// global shutter; render/rolling_shutter.hpp).
  double readout_s = 0.0;
  plant::VehicleParams vehicle;
  plant::WindParams wind;
  plant::AutopilotParams autopilot;
  plant::SensesParams senses;  ///< the Tello's own senses (plant/tello_senses.hpp)
  StartState start;
  CosimSettings cosim;
  std::map<std::string, Distribution> dispersions;  ///< by parameter name (dispersion.hpp)
  bool operator==(const Scenario&) const = default;
};

/// Reads and validates a scenario file. Throws config::ConfigError ("file:line: reason").
Scenario load_scenario(const std::string& path);

/// The same from text; `name_for_errors` stands for the file name in messages.
Scenario parse_scenario(const std::string& yaml_text, const std::string& name_for_errors);

/// The fully resolved YAML of a scenario: every key written, defaults included, doubles with the
/// fewest digits that read back to the same value. parse_scenario(write_scenario(s)) == s, and
/// writing that again gives the same text.
std::string write_scenario(const Scenario& scenario);

/// Boxes for `shelf`: `fill_ratio` of the cells a box of the warehouse's size fits (rounded),
/// chosen without replacement from `stream`, with marker IDs drawn without replacement from
/// `free_ids`; listed bottom to top, left to right. Throws std::invalid_argument when
/// `free_ids` holds fewer IDs than boxes.
std::vector<BoxPlacement> place_random_boxes(const Warehouse& warehouse, const ShelfSpec& shelf,
                                             double fill_ratio, std::vector<int> free_ids,
                                             RandomStream& stream);

/// The number of markers of an OpenCV predefined ArUco dictionary ("DICT_4X4_50" -> 50), or
/// nullopt for a name OpenCV does not have.
std::optional<int> aruco_dictionary_size(const std::string& name);

/// The default scenario shipped with shelfcross: <source>/scenarios/paper_test_shelf.yaml.
inline constexpr const char* kDefaultScenarioFile = "scenarios/paper_test_shelf.yaml";

}  // namespace shelfcross::verification
