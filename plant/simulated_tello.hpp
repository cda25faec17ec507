#pragma once
// A simulated Tello: the plant (Quadrotor on CVODE) and its firmware (Autopilot) stepped in
// lockstep at the autopilot's rate. The unit the co-simulation, the CLI and the emulator use.
//
// Timeline: autopilot ticks at t_k = tick_time_ns(k, rate_hz) (integers, no drift). At each
// tick the autopilot reads the plant's state at t_k and sets rotor commands, which the plant
// holds over [t_k, t_k+1). A command submitted at t is handed to the firmware at t; it acts
// from the next tick on. Deferred replies are stamped with the tick that produced them.
// At each tick, too, the ground and ceiling effect on each rotor (plant/surface_effects.hpp,
// VehicleParams::surface_effects) are measured by ray casts in the senses' world and held over
// the tick like the commands; with no world, or both coefficients 0, every rotor is in open air.

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "plant/autopilot.hpp"
#include "plant/quadrotor.hpp"
#include "shelfcross/sdk_messages.hpp"

namespace shelfcross::plant {

/// The firmware's senses (plant/tello_senses.hpp): their parameters, the world they look at
/// (null: the floor alone; it must outlive the Tello), the light level in [0, 1] and the seed
/// of their random streams. The default senses the truth exactly.
struct SensesSetup {
  SensesParams params;
  const CollisionWorld* world = nullptr;
  double light_level = 1.0;
  std::uint64_t seed = 0;
};

class SimulatedTello {
 public:
  /// Starts landed at (x, y) with the given yaw, at t = 0, motors off.
  SimulatedTello(const VehicleParams& vehicle, const AutopilotParams& autopilot, const WindParams& wind,
                 std::uint64_t wind_seed, IntegratorSettings settings = {}, double x_m = 0.0, double y_m = 0.0,
                 double yaw_rad = 0.0, const SensesSetup& senses = {});

  /// Advances to t_ns (>= time_ns()), then gives the command text to the firmware. Returns
  /// its immediate reply, if any. Throws NumericalFailure.
  std::optional<std::string> submit(TimeNs t_ns, std::string_view text);
  /// Advances plant and autopilot to t_ns, which must be >= time_ns() (asserted). Throws
  /// NumericalFailure.
  void step_to(TimeNs t_ns);
  /// Deferred replies produced so far (oldest first), removed from the queue.
  std::vector<SdkReply> take_replies();

  const RigidBodyState& state() const { return plant_.state(); }
  FlightMode mode() const { return autopilot_.mode(); }
  TimeNs time_ns() const { return plant_.time_ns(); }
  const Quadrotor& plant() const { return plant_; }
  const Autopilot& autopilot() const { return autopilot_; }
  std::int64_t ticks() const { return next_tick_; }

 private:
  Quadrotor plant_;
  Autopilot autopilot_;
  const CollisionWorld* world_;  ///< the senses' world (null: none), for the surface effects
  std::int64_t rate_hz_;
  std::int64_t next_tick_ = 0;  // index of the next autopilot tick not yet run
  std::vector<SdkReply> replies_;
};

}  // namespace shelfcross::plant
