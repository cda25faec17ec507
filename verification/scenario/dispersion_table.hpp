#pragma once
// Dispersed parameters of a campaign: the scenario's `dispersions:` section maps names from a
// fixed table to distributions (distribution.hpp). Each run draws every listed parameter from
// its own stream, derived from (run seed, parameter name), so adding a parameter to a
// scenario never changes the draws of the others, and a run's draws depend on nothing but its
// seed.
//
// The table (name: what a draw does; allowed range of a draw):
//   start_distance_m        start this far in front of shelf 0's front face      [0.5, 20]
//   start_lateral_m         start offset along the shelf (y_S), added            [-5, 5]
//   start_yaw_rad           initial heading, added to the start yaw              [-pi, pi]
//   light_scale             ambient and directional light intensities, times     [0.05, 3]
//   box_fill_ratio          re-place boxes: this fraction of the cells that fit  [0, 1]
//   camera_focal_error_rel  the flight software's fx, fy are (1 + e) x the truth [-0.2, 0.2]
//   camera_cx_error_px      the flight software's cx is off by e                 [-50, 50]
//   camera_cy_error_px      the flight software's cy is off by e                 [-50, 50]
//   rc_gain_scale           autopilot rc-to-velocity gains (all axes), times     [0.2, 5]
//   velocity_time_constant_s  autopilot horizontal velocity time constant       [0.05, 3]
//   vertical_time_constant_s  autopilot vertical time constant                  [0.05, 3]
//   yaw_time_constant_s     autopilot yaw-rate time constant                     [0.02, 3]
//   mass_scale              vehicle mass, times                                  [0.5, 2]
//   ground_effect_coeff     vehicle.surface_effects.ground_coeff                 [0, 2]
//   ceiling_effect_coeff    vehicle.surface_effects.ceiling_coeff                [0, 2]
//   wind_speed_mps          steady wind speed                                    [0, 10]
//   wind_direction_rad      steady wind direction, from +x_W toward +y_W         [-2pi, 2pi]
//   gust_stddev_mps         gust intensity                                       [0, 5]
//   video_latency_mean_s    link: mean video latency                             [0, 5]
//   frame_drop_probability  link: dropped frames                                 [0, 0.9]
//   command_latency_mean_s  link: mean command latency                           [0, 2]
//   command_loss_probability link: lost commands                                 [0, 0.9]
//   compute_latency_s       flight software step time                            [0, 1]
//   compute_latency_quantile  flight software step time drawn from its measured  [0, 1]
//                           distribution (cosim_settings.hpp, kMeasuredStepLatency): the
//                           draw is a quantile q, the step time its inverse CDF at q; so
//                           {uniform: {min: 0, max: 1}} draws from the measured distribution
//   burst_loss              link: loss in a burst (cosim.link.burst_loss)        [0, 1]
//   burst_mean_s            link: mean burst length, s (0: no bursts)            [0, 60]
//   burst_interval_s        link: mean good spell between bursts, s              [0.1, 3600]
//   outage_interval_s       link: mean quiet spell between random outages, s     [1, 3600]
//   outage_start_s          link: the fixed outage's start, s since the start    [0, 3600]
//   outage_duration_s       link: the fixed outage's length, s (0: none)         [0, 60]
//   shelf_behind_distance_m shelf 1's front face this far behind shelf 0's      [0.1, 20]
//                           (along shelf 0's normal; shelf 1 takes shelf 0's heading)
//   shelf_behind_lateral_m  shelf 1 moved along shelf 0's y_S, added             [-5, 5]
//                           (both: only with two shelves or more; refused otherwise)
//   ambient_scale           the ambient light alone, times (uneven light: harder [0, 3]
//                           shading); capped at 1
//   light_azimuth_rad       the directional light's azimuth (direction in x_W y_W [-2pi, 2pi]
//                           turned to it, elevation kept)
//   The Tello's senses (senses: section, plant/tello_senses.hpp), each replacing its key:
//   vps_noise_mps           senses.vps.noise_mps                                 [0, 1]
//   vps_bias_stddev_mps     senses.vps.bias_stddev_mps                           [0, 1]
//   vps_min_range_m         senses.vps.min_range_m                               [0, 10]
//   vps_floor_texture       senses.vps.texture.floor (box, bar: likewise)        [0, 1]
//   tof_noise_m             senses.height.tof_noise_m                            [0, 1]
//   height_noise_m          senses.height.height_noise_m                         [0, 1]
//   baro_noise_m            senses.height.baro_noise_m                           [0, 5]
//   baro_drift_m_per_sqrt_s senses.height.baro_drift_m_per_sqrt_s                [0, 1]
//   height_hold_range_blend senses.height_hold.range_blend                       [0, 1]
//   height_hold_range_below_m  senses.height_hold.range_below_m                  [0, 100]
//   height_hold_time_constant_s  senses.height_hold.time_constant_s              [0.01, 60]
// Values outside a distribution's support cannot be drawn; a distribution whose support
// leaves the allowed range (a normal on a bounded parameter, say) is refused at load time.

#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "verification/scenario/distribution.hpp"

namespace shelfcross::verification {

struct DispersionParameter {
  const char* name;
  double lowest;   ///< the range a draw must stay in
  double highest;
};

/// The table above, in a fixed order.
const std::vector<DispersionParameter>& dispersion_parameters();

/// One run's drawn values, by parameter name (the scenario's dispersed parameters only).
using DrawnValues = std::map<std::string, double>;

DrawnValues draw_dispersions(const std::map<std::string, Distribution>& dispersions, std::uint64_t run_seed);
/// The same from proposals (rare_event.hpp), with the same per-parameter streams: a proposal
/// equal to the nominal (nominal_share 1) draws what draw_dispersions draws.
DrawnValues draw_dispersions(const std::map<std::string, ProposalDistribution>& proposals, std::uint64_t run_seed);

}  // namespace shelfcross::verification
