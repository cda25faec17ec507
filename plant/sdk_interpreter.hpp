#pragma once
// The Tello's SDK interpreter: command text in (parsed by sdk/command.hpp, as the drone does),
// the real reply strings out, the command carried out on the flight modes
// (plant/flight_modes.hpp). Its own state is the SDK's: SDK mode, the video stream, the speed of
// the moves, and why the last command had no effect. The behaviour: plant/autopilot.hpp.

#include <optional>
#include <string>
#include <string_view>

#include <Eigen/Geometry>

#include "plant/flight_modes.hpp"
#include "plant/tello_senses.hpp"
#include "sdk/command.hpp"
#include "shelfcross/gravity.hpp"
#include "shelfcross/time.hpp"

namespace shelfcross::plant {

/// What the drone knows at a command: its senses at the last tick and what the read commands
/// report.
struct DroneReadout {
  SensedState sensed;
  Eigen::Quaterniond q_WB = Eigen::Quaterniond::Identity();  ///< the IMU's attitude
  int battery_pct = 100;
  TimeNs motor_on_ns = 0;
  double height_above_takeoff_m = 0.0;
  std::optional<double> tof_m;
  double baro_m = 0.0;
  Eigen::Vector3d specific_force_B_mps2 = Eigen::Vector3d::Zero();
  double gravity_mps2 = kStandardGravity_mps2;
};

class SdkInterpreter {
 public:
  explicit SdkInterpreter(double move_speed_default_mps) : move_speed_mps_(move_speed_default_mps) {}

  /// One command datagram received at t_ns: the immediate reply, if any (manoeuvres answer later
  /// through the flight modes' replies).
  std::optional<std::string> on_command(TimeNs t_ns, std::string_view text, FlightModes& modes,
                                        const DroneReadout& drone);
  bool sdk_mode() const { return sdk_mode_; }
  bool stream_on() const { return stream_on_; }
  /// Why the command of the last on_command call was ignored (no reply, no effect) or refused
  /// (answered with an error), for people; empty when it was carried out.
  const std::string& last_refusal() const { return last_refusal_; }

 private:
  std::optional<std::string> execute(TimeNs t_ns, const sdk::Command& c, FlightModes& modes,
                                     const DroneReadout& drone);
  std::optional<std::string> move(const sdk::Command& c, FlightModes& modes, const DroneReadout& drone);
  // Records why the command had no effect (last_refusal) and returns its reply.
  std::optional<std::string> refuse(std::string why, std::optional<std::string> reply);
  std::string read_reply(sdk::Verb verb, const DroneReadout& drone) const;

  bool sdk_mode_ = false;
  bool stream_on_ = false;
  double move_speed_mps_;
  std::string last_refusal_;
};

}  // namespace shelfcross::plant
