#pragma once
// The Tello's own senses: what its firmware knows of its motion, and the readings it reports.
//
// A real Tello holds position with its downward vision positioning system (VPS: optical flow
// over the surface below, scaled by the range to it) and holds height on a fused estimate
// (barometer, IMU, the downward time-of-flight range). Each has its errors; this class gives
// the firmware (plant/autopilot.hpp) and the state record the same sensed values.
//
// Sampling: the sensors are sampled at sample_rate_hz on the autopilot's ticks (the first
// tick at or after each sample time); between samples their errors are held. The firmware's
// estimate at any instant is the truth plus the held errors, so with every error zero it is
// the truth exactly (the default: SensesParams{} changes nothing in the world).
//
// VPS. At each sample the range sensor looks down the body's -z axis from its belly (the body
// origin minus rest_height along z_B) for the first surface (CollisionWorld::ray_cast: floor,
// box top, beam, rail, tag, wall; without a world, the floor plane). The VPS is valid when a
// surface is found within [vps.min_range_m, vps.max_range_m] and its kind's texture times the
// light level (min(1, ambient + directional)) reaches vps.min_contrast. While valid, the
// velocity error in the heading frame H is e_H = b + n: b a first-order Gauss-Markov bias per
// axis (stationary standard deviation bias_stddev_mps, time constant bias_time_constant_s,
// drawn from its stationary law at the first sample), n white per sample (noise_mps). The
// position estimate dead-reckons that error: e_p += R_z(yaw) e_H dt each tick, so a hover held
// on it drifts at -b. While invalid the firmware has no horizontal velocity: the hold gives way
// (SensedState::horizontal_hold false; the autopilot flies attitude, and the drone drifts with
// the air) and vgx, vgy read 0.
//
// Height. The fused height follows the barometer's drift d (a random walk of intensity
// baro_drift_m_per_sqrt_s: d += sqrt(dt) q N(0, 1) per sample). The height hold's estimate is
// z_hold = z + d + o, where the range offset o follows, with time constant
// height_hold.time_constant_s, the target
//     beta * (z_range - (z + d))  while the range reading is valid and below range_below_m,
//     0                           otherwise,
// with z_range = floor + rest_height + (tof - tof_ground_m) cos(tilt) the height the range
// implies if the surface below were the floor, and beta = height_hold.range_blend. beta = 0:
// the fused hold ignores a step of the range reading; beta = 1: the hold follows it, so over a
// box of height dz the drone climbs dz.
//
// Readings (the state record and the read commands): vgx, vgy, vgz from the estimate (vz is the
// truth: the fused vertical speed has no modelled error), tof = tof_ground_m + the belly's range
// to the first surface (+ white noise tof_noise_m per sample), nothing beyond tof_max_range_m or
// 60 deg of tilt; h = z_hold - the take-off height (+ white noise height_noise_m per sample);
// baro = 100 m + z + d (+ white noise baro_noise_m per sample).
//
// Random streams: the VPS draws from StreamId::vps, the height sensors from
// StreamId::height_sensors, both seeded by the run's seed: no other stream is shifted. Every
// draw is taken whatever its standard deviation, so a draw's place never depends on a value.

#include <cstdint>
#include <optional>

#include <Eigen/Core>

#include "plant/collision.hpp"
#include "plant/dynamics.hpp"
#include "plant/params.hpp"
#include "shelfcross/random.hpp"
#include "shelfcross/time.hpp"

namespace shelfcross::plant {

/// How much pattern the VPS finds on each kind of surface, 0 (plain) to 1 (rich texture).
struct SurfaceTextures {
  double floor = 1.0;
  double box = 1.0;
  double bar = 1.0;   ///< posts, beams, rails and solid decks
  double tag = 1.0;
  double wall = 1.0;  ///< walls and ceiling
  double of(ElementKind kind) const;
  bool operator==(const SurfaceTextures&) const = default;
};

struct VpsParams {
  double min_range_m = 0.0;    ///< below this range to the surface the VPS is invalid
  double max_range_m = 100.0;  ///< above it, invalid
  double min_contrast = 0.0;   ///< texture x light needed for a valid VPS
  SurfaceTextures texture;
  double noise_mps = 0.0;             ///< white noise per axis, per sample
  double bias_stddev_mps = 0.0;       ///< Gauss-Markov bias per axis, stationary deviation
  double bias_time_constant_s = 60.0;
  bool operator==(const VpsParams&) const = default;
};

struct HeightSensorParams {
  double tof_max_range_m = 8.0;  ///< no reading beyond
  double tof_ground_m = 0.1;     ///< the reading on the ground
  double tof_noise_m = 0.0;
  double height_noise_m = 0.0;   ///< on h
  double baro_noise_m = 0.0;
  double baro_drift_m_per_sqrt_s = 0.0;
  bool operator==(const HeightSensorParams&) const = default;
};

struct HeightHoldParams {
  double range_blend = 0.0;      ///< 0: fused, ignores the range; 1: follows it
  double range_below_m = 2.0;    ///< follows only while the range reading is below this
  double time_constant_s = 0.5;  ///< of the range offset
  bool operator==(const HeightHoldParams&) const = default;
};

struct SensesParams {
  double sample_rate_hz = 50.0;
  VpsParams vps;
  HeightSensorParams height;
  HeightHoldParams height_hold;
  bool operator==(const SensesParams&) const = default;
};

/// What the firmware flies on at one tick.
struct SensedState {
  Eigen::Vector3d p_W_m = Eigen::Vector3d::Zero();    ///< x, y: the VPS's dead reckoning; z: z_hold
  Eigen::Vector3d v_W_mps = Eigen::Vector3d::Zero();  ///< x, y: 0 while the VPS is invalid
  bool horizontal_hold = true;                        ///< the VPS is valid
};

/// The values the Tello reports (state record, read commands), before the SDK's rounding.
struct SensedReadings {
  Eigen::Vector3d v_W_mps = Eigen::Vector3d::Zero();  ///< vgx, vgy, vgz before the heading frame
  std::optional<double> tof_m;                        ///< nothing out of range
  double height_W_m = 0.0;  ///< z_hold plus the h noise: h is this minus the take-off height
  double baro_m = 0.0;      ///< z + d + noise (the state record's baro adds its 100 m)
};

class TelloSenses {
 public:
  /// `world` (may be null: the floor plane alone) must outlive the senses. light_level in
  /// [0, 1]. Throws std::invalid_argument for a non-positive rate or time constant.
  TelloSenses(const SensesParams& params, const VehicleParams& vehicle, const CollisionWorld* world,
              double light_level, std::uint64_t seed);

  /// Advances the errors to the tick t_ns (non-decreasing), sampling the sensors when due, and
  /// returns the firmware's estimate at the tick.
  SensedState sense(TimeNs t_ns, const RigidBodyState& s);
  /// The readings for the state s (any instant after the last tick), with the held errors.
  SensedReadings readings(const RigidBodyState& s) const;

  bool vps_valid() const { return vps_.valid; }
  /// The VPS bias in the heading frame (x forward, y left) now.
  const Eigen::Vector2d& vps_bias_H_mps() const { return vps_.bias_H_mps; }
  /// The range offset o of the height hold now.
  double range_offset_m() const { return height_.range_offset_m; }
  const SensesParams& params() const { return params_; }

 private:
  struct Surface {
    double range_m;
    ElementKind kind;
  };
  std::optional<Surface> surface_below(const RigidBodyState& s, double max_range_m) const;
  void sample(const RigidBodyState& s, double dt_s);
  Eigen::Vector3d velocity_W(const RigidBodyState& s) const;

  /// The VPS's held errors.
  struct Vps {
    bool valid = true;
    Eigen::Vector2d bias_H_mps = Eigen::Vector2d::Zero();
    Eigen::Vector2d error_H_mps = Eigen::Vector2d::Zero();  ///< bias + held noise
    Eigen::Vector2d error_p_W_m = Eigen::Vector2d::Zero();  ///< dead-reckoned position error
  };
  /// The height sensors' held errors.
  struct Height {
    double baro_drift_m = 0.0;
    double range_offset_m = 0.0, range_target_m = 0.0;
    double tof_noise_m = 0.0, height_noise_m = 0.0, baro_noise_m = 0.0;
  };

  SensesParams params_;
  VehicleParams vehicle_;
  const CollisionWorld* world_;
  double light_;
  RandomStream vps_stream_;
  RandomStream height_stream_;
  std::int64_t rate_mhz_;
  std::int64_t k_sample_ = 0;
  std::optional<TimeNs> last_tick_ns_;
  Vps vps_;
  Height height_;
};

}  // namespace shelfcross::plant
