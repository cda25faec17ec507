#pragma once
// The vehicle's dynamics (plant/dynamics.hpp) integrated by SUNDIALS CVODE, with a floor.
//
// Integration: rotor commands are inputs held constant between calls to set_rotor_commands
// (the autopilot ticks). advance_to(t) integrates from the current time to t with CVODE in
// CV_NORMAL mode and CVodeSetStopTime(t), so it never steps past the input change, and
// re-initialises CVODE (CVodeReInit on the one CVODE memory, never re-created) at the start of
// every segment, so no multistep history crosses an input discontinuity.
// Method: the system is not stiff (fastest mode: the 20 ms motor lag; the rigid body and the
// attitude loop are slower), so the default is variable-order Adams-Moulton with a
// fixed-point (functional) nonlinear solver: no Jacobian, no linear algebra, a few
// right-hand-side evaluations per step. BDF with Newton and a dense solver is selectable for a
// stiff parameter set (e.g. a very fast motor time constant).
//
// Floor: the vehicle starts landed. While airborne a CVODE root function g = z - z_rest
// (z_rest = floor + half the airframe height) stops the integration at touchdown; the contact
// is perfectly plastic (the vehicle comes to rest, level, keeping its yaw). While resting, the
// vehicle is held (p, q fixed, v = w = 0), only the rotors evolve, and a second root function
// (thrust along z_W minus weight) releases it at lift-off. So z >= z_rest always.
//
// Errors: a CVODE failure or a non-finite state throws NumericalFailure; the co-simulation
// catches it and records the run as failed. Bad parameters throw std::invalid_argument.

#include <cstdint>
#include <memory>
#include <stdexcept>
#include <string>

#include <Eigen/Core>

#include "plant/dynamics.hpp"
#include "plant/params.hpp"
#include "shelfcross/time.hpp"

namespace shelfcross::plant {

struct IntegratorSettings {
  enum class Method { adams_fixed_point, bdf_newton_dense };
  Method method = Method::adams_fixed_point;
  /// Tolerances. The defaults keep the autopilot's 10 s manoeuvre within 1e-4 m and 1e-4 m/s
  /// of a fine RK4 reference, steady or with commands jumping from tick to tick (local errors
  /// are re-corrected by the autopilot; plant integration test); tighter ones cost steps per tick.
  double rel_tol = 1e-5;
  double abs_tol = 1e-7;               ///< on p (m), v (m/s), q (unit)
  /// On the body rates w (rad/s), abs_tol's by default. w binds CVODE's error test when the
  /// rotor commands jump from tick to tick (a position hold on noisy velocity readings): at
  /// 1e-6 rad/s (an error held over a 2 ms tick turns the attitude by 2e-9 rad, below the
  /// attitude's 1e-7) a flight takes a sixth to a third fewer right-hand-side evaluations and
  /// stays as near the reference (plant integration test), but its floating-point path
  /// changes, and with it every closed-loop flight's details.
  double abs_tol_rate_radps = 1e-7;
  double abs_tol_rotor_radps = 1e-3;   ///< on the rotor speeds (thousands of rad/s)
  /// First step after each re-initialisation: > 0 this (capped at the segment); 0 the whole
  /// segment (one step per autopilot tick when the error test allows; CVODE shrinks it
  /// otherwise); < 0 CVODE's own estimate (costs extra right-hand-side evaluations).
  double initial_step_s = 0.0;
  long max_steps_per_segment = 50000;
  bool operator==(const IntegratorSettings&) const = default;
};

/// A numerical failure of the plant: CVODE's error flag, or a state that became non-finite.
class NumericalFailure : public std::runtime_error {
 public:
  NumericalFailure(TimeNs t_ns, int cvode_flag, const std::string& what)
      : std::runtime_error(what), t_ns_(t_ns), cvode_flag_(cvode_flag) {}
  TimeNs t_ns() const { return t_ns_; }   ///< start of the segment that failed
  int cvode_flag() const { return cvode_flag_; }  ///< 0 when the failure is a non-finite state

 private:
  TimeNs t_ns_;
  int cvode_flag_;
};

class Quadrotor {
 public:
  /// Throws std::invalid_argument for non-physical parameters (mass, inertia, coefficients <= 0).
  Quadrotor(const VehicleParams& vehicle, const WindParams& wind, std::uint64_t wind_seed,
            IntegratorSettings settings = {});
  ~Quadrotor();
  Quadrotor(Quadrotor&&) noexcept;
  Quadrotor& operator=(Quadrotor&&) noexcept;
  Quadrotor(const Quadrotor&) = delete;
  Quadrotor& operator=(const Quadrotor&) = delete;

  /// Landed at rest on the floor at (x, y) with the given yaw, rotors stopped.
  static RigidBodyState landed_state(const VehicleParams& vehicle, double x_m = 0.0, double y_m = 0.0,
                                     double yaw_rad = 0.0);

  /// Sets the state and the time. A state at or below the rest height is put on the floor
  /// (resting); rotor commands are set to the state's rotor speeds.
  void reset(const RigidBodyState& state, TimeNs t_ns);
  /// Rotor speed commands (rad/s), clamped to [0, rotor_speed_max_radps], held until the next
  /// call. With motor dynamics off the rotor speeds take these values at once.
  void set_rotor_commands(const Eigen::Vector4d& cmd_radps);
  /// Each rotor's thrust factor (plant/surface_effects.hpp; 1: open air, the default), held
  /// like the commands until the next call.
  void set_rotor_thrust_factors(const Eigen::Vector4d& factors);
  const Eigen::Vector4d& rotor_thrust_factors() const;
  /// Integrates to t_ns, which must be >= time_ns() (asserted). Throws NumericalFailure.
  void advance_to(TimeNs t_ns);

  const RigidBodyState& state() const;
  TimeNs time_ns() const;
  const Eigen::Vector4d& rotor_commands() const;
  /// True while resting on the floor.
  bool on_floor() const;
  /// Wind held over the current segment (sampled at its start).
  Eigen::Vector3d wind_W_mps() const;
  const VehicleParams& vehicle() const;
  /// Right-hand-side evaluations so far (a cost measure for benchmarks).
  long rhs_evaluations() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace shelfcross::plant
