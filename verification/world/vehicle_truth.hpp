#pragma once
// What the co-simulation and the Tello emulator both derive from the plant's truth: the
// Tello's state record (before the SDK's quantisation), the body pose, and the crossing of
// shelf 0 judged face to face on the body origin. One implementation, so the emulator reports
// crossings and state exactly as a co-simulated run does.

#include <optional>

#include <Eigen/Geometry>

#include "plant/dynamics.hpp"
#include "plant/params.hpp"
#include "plant/tello_senses.hpp"
#include "shelfcross/cell_index.hpp"
#include "shelfcross/rotation.hpp"
#include "shelfcross/sdk_messages.hpp"
#include "shelfcross/warehouse.hpp"
#include "verification/scenario/scenario.hpp"

namespace shelfcross::verification {

/// The simulated Tello's firmware parameters for a scenario: its autopilot section, with the
/// one battery of the vehicle set from cosim.battery_start_pct and cosim.endurance_s (the
/// autopilot answers `battery?` and fills every state record from it).
plant::AutopilotParams autopilot_params_for(const Scenario& scenario);

/// X_WB of a plant state.
Eigen::Isometry3d body_pose(const plant::RigidBodyState& s);

/// The cell of shelf `s` whose opening contains (y_S, z_S), if any (levels and columns from 1);
/// nothing outside the grid or for NaN coordinates. Does not throw.
std::optional<CellIndex> cell_at(const ShelfSpec& s, double y_S, double z_S);

/// The Tello's state record from the plant's truth and what the drone senses
/// (plant/tello_senses.hpp), before the SDK's quantisation (which format_state_record applies,
/// tello_state_format.hpp): attitude from R_WB, the sensed velocity in the heading frame, specific
/// force f_B = R^T (a_W - g_W), h = the sensed height above ground_z_m (the take-off height), the
/// sensed tof (to the first surface below), baro 100 m + the sensed barometric altitude, battery
/// floored.
StateRecord state_from_senses(const plant::RigidBodyState& s, const plant::SensedReadings& sensed,
                              const Eigen::Vector3d& a_W_mps2, double ground_z_m, double battery_pct,
                              double motor_time_s, TimeNs t_ns);

/// The light level the vision positioning system sees: ambient + directional, at most 1.
double light_level(const Lighting& lighting);

/// The crossing of one shelf, judged on the body origin in the shelf frame S: the front face
/// (x_S = 0) crossed forward inside a cell's opening, then the back face (x_S = depth) crossed
/// forward inside the same cell's opening, is a crossing of that cell.
class ShelfCrossingMonitor {
 public:
  struct Faces {
    bool front = false;  ///< this update crossed the front face forward
    bool back = false;   ///< ... the back face
  };
  /// Keeps a reference to `shelf`, which must outlive the monitor.
  ShelfCrossingMonitor(const ShelfSpec& shelf, const Eigen::Vector3d& p_WB_m);
  /// The body origin's next position; returns the faces crossed since the previous one.
  Faces update(const Eigen::Vector3d& p_WB_m);

  /// The latest body origin in S.
  const Eigen::Vector3d& p_S_m() const { return p_S_m_; }
  /// The cell entered and left face to face (the latest such crossing).
  const std::optional<CellIndex>& crossed() const { return crossed_; }
  /// Body origin - cell centre at the latest front-face crossing inside a cell.
  const std::optional<double>& entry_offset_y_m() const { return entry_offset_y_m_; }
  const std::optional<double>& entry_offset_z_m() const { return entry_offset_z_m_; }

 private:
  const ShelfSpec& shelf_;
  Eigen::Isometry3d X_SW_;
  Eigen::Vector3d p_S_m_;
  std::optional<CellIndex> entry_cell_, crossed_;
  std::optional<double> entry_offset_y_m_, entry_offset_z_m_;
};

}  // namespace shelfcross::verification
