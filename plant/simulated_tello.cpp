#include "plant/simulated_tello.hpp"

#include <cassert>

#include "plant/surface_effects.hpp"

namespace shelfcross::plant {

SimulatedTello::SimulatedTello(const VehicleParams& vehicle, const AutopilotParams& autopilot,
                               const WindParams& wind, std::uint64_t wind_seed, IntegratorSettings settings,
                               double x_m, double y_m, double yaw_rad, const SensesSetup& senses)
    : plant_(vehicle, wind, wind_seed, settings),
      autopilot_(autopilot, vehicle,
                 TelloSenses(senses.params, vehicle, senses.world, senses.light_level, senses.seed)),
      world_(senses.world),
      rate_hz_(static_cast<std::int64_t>(autopilot.rate_hz)) {
  plant_.reset(Quadrotor::landed_state(vehicle, x_m, y_m, yaw_rad), 0);
}

void SimulatedTello::step_to(TimeNs t_ns) {
  assert(t_ns >= plant_.time_ns());
  for (;;) {
    const TimeNs t_tick = tick_time_ns(next_tick_, rate_hz_);
    if (t_tick > t_ns) break;
    plant_.advance_to(t_tick);
    // The air near the surfaces around each rotor, measured once per tick and held over it.
    const VehicleParams& v = plant_.vehicle();
    if (world_ && v.surface_effects.any()) {
      plant_.set_rotor_thrust_factors(
          rotor_thrust_factors(v.surface_effects, rotor_surface_distances(v, *world_, plant_.state())));
    }
    plant_.set_rotor_commands(autopilot_.update(t_tick, plant_.state()));
    ++next_tick_;
  }
  plant_.advance_to(t_ns);
  for (auto& r : autopilot_.take_replies()) replies_.push_back(std::move(r));
}

std::optional<std::string> SimulatedTello::submit(TimeNs t_ns, std::string_view text) {
  step_to(t_ns);
  return autopilot_.on_command(t_ns, text);
}

std::vector<SdkReply> SimulatedTello::take_replies() {
  for (auto& r : autopilot_.take_replies()) replies_.push_back(std::move(r));
  std::vector<SdkReply> out;
  out.swap(replies_);
  return out;
}

}  // namespace shelfcross::plant
