#pragma once
// The Tello's flight modes and the references its inner loops track (plant/flight_controller.hpp):
// take-off, landing, emergency, free flight on the rc sticks, and the moves, each producing the
// reference for one tick. Driven by the SDK interpreter (plant/sdk_interpreter.hpp) and ticked by
// the autopilot (plant/autopilot.hpp), which documents the behaviour an SDK user sees.

#include <array>
#include <optional>
#include <string_view>
#include <vector>

#include <Eigen/Core>

#include "plant/dynamics.hpp"
#include "plant/flight_controller.hpp"
#include "plant/params.hpp"
#include "plant/tello_senses.hpp"
#include "sdk/command.hpp"
#include "shelfcross/sdk_messages.hpp"
#include "shelfcross/time.hpp"

namespace shelfcross::plant {

enum class FlightMode { landed, taking_off, flying, landing, emergency };
std::string_view to_string(FlightMode mode);

/// What the motors do after a tick of the flight modes.
enum class Drive {
  motors_off,  ///< stopped (landed, emergency, touchdown)
  idle,        ///< the take-off's spin-up at idle speed
  fly,         ///< the inner loops track the references
};

class FlightModes {
 public:
  FlightModes(const AutopilotParams& params, const VehicleParams& vehicle);

  FlightMode mode() const { return mode_; }
  bool manoeuvre_active() const { return manoeuvre_.active; }
  /// The references of the inner loops (the controller may move them: its leash).
  FlightReferences& references() { return ref_; }
  /// The take-off height (world z of the estimate at `takeoff`), from which `h` counts.
  double takeoff_z_m() const { return takeoff_z_m_; }
  /// Deferred replies that became due (stamped with the tick that produced them), oldest first.
  std::vector<SdkReply> take_replies();

  // The commands, carried out (the interpreter has checked that each is allowed). Each captures
  // the references from the estimate and the attitude (IMU) of the last tick where it says so.
  void take_off(TimeNs t_ns, const SensedState& sensed, const Eigen::Quaterniond& q_WB);
  void start_landing(bool reply_when_done);
  void emergency();
  void stop(const SensedState& sensed, const Eigen::Quaterniond& q_WB);
  void set_sticks(const std::array<int, 4>& sticks) { sticks_ = sticks; }
  /// A move of delta_H_m (heading frame of now: x forward, y left, z up) and dyaw_rad at speed_mps.
  void start_move(sdk::Verb verb, const Eigen::Vector3d& delta_H_m, double dyaw_rad, double speed_mps,
                  const SensedState& sensed, const Eigen::Quaterniond& q_WB);

  /// One tick at t_ns, dt after the last: the mode's transitions and references.
  Drive tick(TimeNs t_ns, double dt, const RigidBodyState& s, const SensedState& sensed, bool on_ground);

 private:
  struct Manoeuvre {
    bool active = false;
    sdk::Verb verb = sdk::Verb::forward;
    Eigen::Vector3d target_W_m = Eigen::Vector3d::Zero();
    double target_yaw_rad = 0.0;
    double speed_mps = 1.0;
  };
  /// The current phase: when it started, since when the take-off has been settled, which
  /// replies it owes.
  struct Phase {
    TimeNs start_ns = 0;
    std::optional<TimeNs> settled_since_ns;
    bool reply_takeoff = false;
    bool reply_land = false;
  };

  Drive take_off_tick(TimeNs t_ns, double dt, const SensedState& sensed, bool on_ground);
  void manoeuvre_references(TimeNs t_ns, double dt, const RigidBodyState& s, const SensedState& sensed);

  AutopilotParams params_;
  VehicleParams vehicle_;
  FlightMode mode_ = FlightMode::landed;
  std::array<int, 4> sticks_{};  // a b c d
  Phase phase_;
  Manoeuvre manoeuvre_;
  FlightReferences ref_;
  double takeoff_z_m_;
  std::vector<SdkReply> replies_;
};

}  // namespace shelfcross::plant
