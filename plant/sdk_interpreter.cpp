#include "plant/sdk_interpreter.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <variant>

#include "sdk/state_record.hpp"
#include "shelfcross/rotation.hpp"

namespace shelfcross::plant {
namespace {

constexpr double kDegPerRad = 57.29577951308232;

std::string mode_description(const FlightModes& modes) {
  if (modes.mode() == FlightMode::flying && modes.manoeuvre_active()) return "a manoeuvre is running";
  return "the drone is " + std::string(to_string(modes.mode()));
}

}  // namespace

std::optional<std::string> SdkInterpreter::on_command(TimeNs t_ns, std::string_view text, FlightModes& modes,
                                                      const DroneReadout& drone) {
  last_refusal_.clear();
  const auto parsed = sdk::parse(text);
  if (const auto* err = std::get_if<sdk::ParseError>(&parsed)) {
    // rc is never answered, even when malformed; nothing is answered outside SDK mode.
    const bool is_rc = sdk::is_rc_text(text);
    if (!sdk_mode_) {
      last_refusal_ = "ignored: not in SDK mode ('command' not received yet), no reply";
      return std::nullopt;
    }
    if (is_rc) return refuse("ignored: " + err->reason + ", no reply (rc is never answered)", std::nullopt);
    return refuse("refused: " + err->reason, err->reply);
  }
  const auto& c = std::get<sdk::Command>(parsed);
  if (!sdk_mode_ && c.verb != sdk::Verb::command) {
    last_refusal_ = "ignored: not in SDK mode ('command' not received yet), no reply";
    return std::nullopt;
  }
  return execute(t_ns, c, modes, drone);
}

std::optional<std::string> SdkInterpreter::refuse(std::string why, std::optional<std::string> reply) {
  last_refusal_ = std::move(why);
  return reply;
}

std::optional<std::string> SdkInterpreter::execute(TimeNs t_ns, const sdk::Command& c, FlightModes& modes,
                                                   const DroneReadout& drone) {
  using sdk::Verb;
  const FlightMode mode = modes.mode();
  const std::string mode_text = mode_description(modes);
  const bool airborne = mode == FlightMode::taking_off || mode == FlightMode::flying || mode == FlightMode::landing;
  const bool flying_free = mode == FlightMode::flying && !modes.manoeuvre_active();
  switch (c.verb) {
    case Verb::command:
      sdk_mode_ = true;
      return "ok";
    case Verb::takeoff:
      if (mode != FlightMode::landed) return refuse("refused: " + mode_text, "error");
      if (drone.battery_pct < 10) {
        return refuse("refused: battery at " + std::to_string(drone.battery_pct) + " % (takeoff needs 10 %)", "error");
      }
      modes.take_off(t_ns, drone.sensed, drone.q_WB);
      return std::nullopt;
    case Verb::land:
      if (mode != FlightMode::taking_off && mode != FlightMode::flying) {
        return refuse("refused: " + mode_text, "error");
      }
      modes.start_landing(true);
      return std::nullopt;
    case Verb::emergency:
      if (airborne) modes.emergency();
      return "ok";
    case Verb::stop:
      if (mode != FlightMode::flying) return refuse("refused: " + mode_text, "error");
      modes.stop(drone.sensed, drone.q_WB);
      return "ok";
    case Verb::streamon:
      stream_on_ = true;
      return "ok";
    case Verb::streamoff:
      stream_on_ = false;
      return "ok";
    case Verb::speed:
      move_speed_mps_ = c.args[0] / 100.0;
      return "ok";
    case Verb::rc:
      if (!flying_free) {
        return refuse("ignored: " + mode_text + " (rc acts only while flying free), no reply", std::nullopt);
      }
      modes.set_sticks({c.args[0], c.args[1], c.args[2], c.args[3]});
      return std::nullopt;
    case Verb::up: case Verb::down: case Verb::left: case Verb::right: case Verb::forward: case Verb::back:
    case Verb::cw: case Verb::ccw: case Verb::go:
      if (!flying_free) return refuse("refused: " + mode_text, "error");
      return move(c, modes, drone);
    case Verb::flip: case Verb::curve:
      return refuse("refused: flip and curve are not simulated", "error");
    default:
      return read_reply(c.verb, drone);
  }
}

std::optional<std::string> SdkInterpreter::move(const sdk::Command& c, FlightModes& modes, const DroneReadout& drone) {
  using sdk::Verb;
  const double d = c.args[0] / 100.0;
  Eigen::Vector3d delta_H = Eigen::Vector3d::Zero();
  double dyaw = 0.0;
  double speed = move_speed_mps_;
  switch (c.verb) {
    case Verb::up: delta_H.z() = d; break;
    case Verb::down: delta_H.z() = -d; break;
    case Verb::left: delta_H.y() = d; break;
    case Verb::right: delta_H.y() = -d; break;
    case Verb::forward: delta_H.x() = d; break;
    case Verb::back: delta_H.x() = -d; break;
    case Verb::cw: dyaw = -c.args[0] / kDegPerRad; break;
    case Verb::ccw: dyaw = c.args[0] / kDegPerRad; break;
    default:  // go x y z speed
      delta_H = Eigen::Vector3d(c.args[0], c.args[1], c.args[2]) / 100.0;
      speed = c.args[3] / 100.0;
  }
  modes.start_move(c.verb, delta_H, dyaw, speed, drone.sensed, drone.q_WB);
  return std::nullopt;
}

std::string SdkInterpreter::read_reply(sdk::Verb verb, const DroneReadout& drone) const {
  using sdk::Verb;
  char buf[96];
  const Eigen::Vector3d rpy = euler_zyx_from_quaternion(drone.q_WB) * kDegPerRad;
  switch (verb) {
    case Verb::speed_q: std::snprintf(buf, sizeof buf, "%.1f", move_speed_mps_ * 100.0); break;
    case Verb::battery_q: std::snprintf(buf, sizeof buf, "%d", drone.battery_pct); break;
    case Verb::time_q: std::snprintf(buf, sizeof buf, "%llds", static_cast<long long>(drone.motor_on_ns / kNsPerSecond)); break;
    case Verb::height_q:
      std::snprintf(buf, sizeof buf, "%lddm", std::lround(std::max(0.0, drone.height_above_takeoff_m) * 10.0));
      break;
    case Verb::tof_q: {
      // Out of range: the state record's invalid reading, in millimetres.
      const std::optional<double>& tof = drone.tof_m;
      std::snprintf(buf, sizeof buf, "%ldmm", tof ? std::lround(*tof * 1000.0) : 10L * sdk::kTofInvalid_cm);
      break;
    }
    case Verb::attitude_q:
      // The Tello's yaw is clockwise-positive (sdk_messages.hpp).
      std::snprintf(buf, sizeof buf, "pitch:%ld;roll:%ld;yaw:%ld;", std::lround(rpy.y()), std::lround(rpy.x()),
                    std::lround(-rpy.z()));
      break;
    case Verb::baro_q: std::snprintf(buf, sizeof buf, "%.6f", drone.baro_m); break;
    case Verb::temp_q: return "60~62C";  // no thermal model: the nominal board temperature
    case Verb::wifi_q: return "90";      // no radio model: a good link
    case Verb::sdk_q: return "20";
    case Verb::sn_q: return "0TQZSIM0000001";
    case Verb::acceleration_q: {
      const Eigen::Vector3d a_mg = drone.specific_force_B_mps2 / drone.gravity_mps2 * 1000.0;
      // The Tello's body axes are x forward, y right, z down: agz ~ -1000 at rest.
      std::snprintf(buf, sizeof buf, "agx:%.2f;agy:%.2f;agz:%.2f;", a_mg.x(), -a_mg.y(), -a_mg.z());
      break;
    }
    default: return "error";
  }
  return buf;
}

}  // namespace shelfcross::plant
