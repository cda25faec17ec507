#include "verification/scenario/dispersion_table.hpp"

#include <numbers>

#include "shelfcross/random.hpp"

namespace shelfcross::verification {
namespace {

constexpr double kPi = std::numbers::pi;

/// A parameter's own stream: the dispersion stream of a seed mixed with the name's hash
/// (FNV-1a, fixed), so streams do not depend on which other parameters are dispersed.
RandomStream parameter_stream(std::uint64_t run_seed, const std::string& name) {
  std::uint64_t h = 0xcbf29ce484222325ull;
  for (unsigned char c : name) h = (h ^ c) * 0x100000001b3ull;
  return RandomStream(run_seed ^ mix64(h), StreamId::dispersion);
}

}  // namespace

const std::vector<DispersionParameter>& dispersion_parameters() {
  static const std::vector<DispersionParameter> table{
      {"start_distance_m", 0.5, 20.0},
      {"start_lateral_m", -5.0, 5.0},
      {"start_yaw_rad", -kPi, kPi},
      {"light_scale", 0.05, 3.0},
      {"box_fill_ratio", 0.0, 1.0},
      {"camera_focal_error_rel", -0.2, 0.2},
      {"camera_cx_error_px", -50.0, 50.0},
      {"camera_cy_error_px", -50.0, 50.0},
      {"rc_gain_scale", 0.2, 5.0},
      {"velocity_time_constant_s", 0.05, 3.0},
      {"vertical_time_constant_s", 0.05, 3.0},
      {"yaw_time_constant_s", 0.02, 3.0},
      {"mass_scale", 0.5, 2.0},
      {"ground_effect_coeff", 0.0, 2.0},
      {"ceiling_effect_coeff", 0.0, 2.0},
      {"wind_speed_mps", 0.0, 10.0},
      {"wind_direction_rad", -2.0 * kPi, 2.0 * kPi},
      {"gust_stddev_mps", 0.0, 5.0},
      {"video_latency_mean_s", 0.0, 5.0},
      {"frame_drop_probability", 0.0, 0.9},
      {"command_latency_mean_s", 0.0, 2.0},
      {"command_loss_probability", 0.0, 0.9},
      {"compute_latency_s", 0.0, 1.0},
      {"compute_latency_quantile", 0.0, 1.0},
      {"video_datagram_loss", 0.0, 0.9},
      {"state_loss", 0.0, 0.9},
      {"reply_loss", 0.0, 0.9},
      {"not_joystick_probability", 0.0, 1.0},
      {"video_stall_start_s", 0.0, 3600.0},
      {"video_stall_duration_s", 0.0, 3600.0},
      {"burst_loss", 0.0, 1.0},
      {"burst_mean_s", 0.0, 60.0},
      {"burst_interval_s", 0.1, 3600.0},
      {"outage_interval_s", 1.0, 3600.0},
      {"outage_start_s", 0.0, 3600.0},
      {"outage_duration_s", 0.0, 60.0},
      {"shelf_behind_distance_m", 0.1, 20.0},
      {"shelf_behind_lateral_m", -5.0, 5.0},
      {"ambient_scale", 0.0, 3.0},
      {"light_azimuth_rad", -2.0 * kPi, 2.0 * kPi},
      {"camera_readout_s", 0.0, 0.1},
      {"vps_noise_mps", 0.0, 1.0},
      {"vps_bias_stddev_mps", 0.0, 1.0},
      {"vps_min_range_m", 0.0, 10.0},
      {"vps_floor_texture", 0.0, 1.0},
      {"vps_box_texture", 0.0, 1.0},
      {"vps_bar_texture", 0.0, 1.0},
      {"tof_noise_m", 0.0, 1.0},
      {"height_noise_m", 0.0, 1.0},
      {"baro_noise_m", 0.0, 5.0},
      {"baro_drift_m_per_sqrt_s", 0.0, 1.0},
      {"height_hold_range_blend", 0.0, 1.0},
      {"height_hold_range_below_m", 0.0, 100.0},
      {"height_hold_time_constant_s", 0.01, 60.0},
  };
  return table;
}

DrawnValues draw_dispersions(const std::map<std::string, Distribution>& dispersions, std::uint64_t run_seed) {
  DrawnValues drawn;
  for (const auto& [name, distribution] : dispersions) {
    RandomStream stream = parameter_stream(run_seed, name);
    drawn[name] = distribution.sample(stream);
  }
  return drawn;
}

DrawnValues draw_dispersions(const std::map<std::string, ProposalDistribution>& proposals, std::uint64_t run_seed) {
  DrawnValues drawn;
  for (const auto& [name, proposal] : proposals) {
    RandomStream stream = parameter_stream(run_seed, name);
    drawn[name] = proposal.sample(stream);
  }
  return drawn;
}

}  // namespace shelfcross::verification
