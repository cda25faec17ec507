#pragma once
// The approach's control errors and what was flown, for the telemetry (mission/telemetry.hpp).

#include "flight_sw/control/control.hpp"
#include "flight_sw/control/stick_response.hpp"
#include "flight_sw/guidance/line_hold.hpp"
#include "shelfcross/sdk_messages.hpp"

namespace shelfcross::flight_sw {

/// The approach's control errors and what was flown (the approach's laws, Sticks, the
/// line-hold gate and the in-crossing watch).
struct ControlTelemetry {
  double e_z_m = 0.0;
  double e_psi_rad = 0.0;
  double psi_cell_rad = 0.0;   ///< heading relative to the cell normal (lateral law input)
  double lateral_mps = 0.0;    ///< bang-off-bang output
  double yaw_cell_rad = 0.0;   ///< the vehicle's own heading relative to the cell normal
  bool settled = false;        ///< still and centred long enough to commit to the crossing
  bool holding_short = false;  ///< forward speed held at 0 (off the normal, or settling)
  double forward_gain = 1.0;   ///< measured forward speed per nominal stick speed (crossing timing)
  LineHoldForecast line_hold;  ///< what the blind crossing may add to the line's offsets (line_hold.hpp)
  int crossings_backed_out = 0;  ///< crossings stopped by the in-crossing watch before the cell
  /// The Tello's measured answer to its sticks per StickAxis, once measured, with the scale
  /// each axis's sticks are sent at (stick_response.hpp).
  StickEstimates sticks;
  VelocityCommand velocity;    ///< last commanded
  RcSticks rc;                 ///< last sent
};

}  // namespace shelfcross::flight_sw
