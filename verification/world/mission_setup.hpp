#pragma once
// A scenario as a run is set up from it: the shelves the mission covers, the flight software's
// configuration (what it is told and the camera it believes), the true box list its inventory
// is scored against, and the renderer's options (the simulated camera's noise and blur). The
// co-simulation and the emulator set a run up alike from these.

#include <set>

#include "flight_sw/config.hpp"
#include "render/renderer.hpp"
#include "shelfcross/camera.hpp"
#include "shelfcross/warehouse.hpp"
#include "verification/scenario/scenario.hpp"
#include "verification/world/metrics.hpp"

namespace shelfcross::verification {

/// The shelves the mission covers: all of the scenario's when they form a row (the geometry of
/// shelf 0, the same heading, each origin shelf_spacing_m behind the previous one along shelf
/// 0's normal, the same spacing throughout, > depth), else 1 (shelf 0 only, as before).
int mission_shelf_count(const Scenario& scenario);
/// Front face to front face along the normal in that row (0 for a single shelf).
double mission_shelf_spacing_m(const Scenario& scenario);

/// The flight software's configuration for a scenario: the known geometry of shelf 0, the
/// layout (mission_shelf_count shelves at their spacing), the strategy (cosim.strategy), the
/// camera it believes (calibration error included), the mount; the mission's time budget from
/// cosim.timeout_s (less a give-up's reserve); tunables at their defaults.
/// Requires at least one shelf; throws std::invalid_argument for an unknown cosim.strategy.
flight_sw::FlightConfig flight_config_for(const Scenario& scenario, const CameraIntrinsics& believed_camera);

/// The true box list of the mission's shelves as the flight software should report it.
std::set<InventoryEntry> true_inventory(const Scenario& scenario);

/// The renderer options a scenario asks for (noise, blur).
render::RenderOptions render_options_for(const Scenario& scenario);

}  // namespace shelfcross::verification
