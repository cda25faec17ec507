#pragma once
// The world's truth about a flight: what the one world tick (TelloWorld::tick, tello_world.hpp)
// measures of the vehicle against the warehouse, defined once. The world fills it; a
// co-simulated run stores it in its metrics (RunMetrics::truth, run_metrics_json.hpp) and the
// Tello emulator reports it (EmulatorReport::truth, printed by `tello-sim`). Its JSON keys are
// written and read here, so a stored run and the emulator's report spell each fact alike.

#include <optional>
#include <string>

#include <nlohmann/json_fwd.hpp>  // the JSON functions are declared here, defined in the .cpp

#include "plant/collision.hpp"
#include "shelfcross/cell_index.hpp"

namespace shelfcross::config {
class StrictObject;  // config/strict_json.hpp
}  // namespace shelfcross::config

namespace shelfcross::verification {

struct WorldTruth {
  double path_length_m = 0.0;             ///< of the body origin: the sum of |p(t) - p(t_last)| over the observed ticks
  int floor_touches = 0;                  ///< airborne-to-floor contacts (landings included)
  std::optional<plant::Contact> contact;  ///< the first contact with a shelf part or a wall (it ends the flight)
  // Shelf 0's crossing, judged face to face on the body origin in shelf 0's frame S
  // (ShelfCrossingMonitor, vehicle_truth.hpp).
  std::optional<CellIndex> crossed;         ///< the cell entered and left face to face (the latest such crossing)
  std::optional<double> entry_offset_y_m;   ///< body origin - cell centre at the latest front-face crossing
  std::optional<double> entry_offset_z_m;   ///< inside a cell, y_S and z_S
  /// The least signed distance of the vehicle's box (its margin included) to any shelf part
  /// (CollisionWorld::clearance_to_shelves), taken at the observed ticks while the body origin
  /// is near a mission shelf (within half the vehicle's length plus its margin and 5 cm of the
  /// faces); none when it never was.
  std::optional<double> min_clearance_m;
};

/// A first contact as stored: time, element name and kind, point, depth. The element's index
/// and the contact normal are not stored, so they read back as -1 and zero.
nlohmann::json contact_json(const plant::Contact& contact);
/// A cell as stored: {"level", "column"}, or null for none.
nlohmann::json cell_json(const std::optional<CellIndex>& cell);
/// The cell at `key` of `parent` (null: none). Throws std::invalid_argument naming the key
/// when it is missing or is neither null nor an object of two integers.
std::optional<CellIndex> read_cell(config::StrictObject& parent, const std::string& key);

/// Writes the truth's keys that a run's metrics and the emulator's report share into the
/// object `j`: path_length_m, contact (contact_json or null), crossed (cell_json),
/// entry_offset_y_m, entry_offset_z_m, min_clearance_m (a number or null). floor_touches is
/// the run's alone: run_metrics_json writes it, `tello-sim` does not print it.
void write_world_truth(nlohmann::json& j, const WorldTruth& truth);
/// Reads the keys write_world_truth writes from `o` (floor_touches stays 0: the caller that
/// stores it reads it); the caller finishes `o`. Throws std::invalid_argument naming the key on
/// a missing or mistyped key or an unknown contact element kind.
WorldTruth read_world_truth(config::StrictObject& o);

}  // namespace shelfcross::verification
