#include "plant/tello_senses.hpp"

#include <cmath>
#include <stdexcept>

#include "shelfcross/rotation.hpp"

namespace shelfcross::plant {
namespace {

/// R_z(yaw) v_H: a heading-frame horizontal vector in W.
Eigen::Vector2d heading_to_world(double yaw, const Eigen::Vector2d& v_H) {
  const double c = std::cos(yaw), s = std::sin(yaw);
  return {c * v_H.x() - s * v_H.y(), s * v_H.x() + c * v_H.y()};
}

/// Beyond 60 deg of tilt the downward sensors see nothing (as the state record has always said).
constexpr double kMinCosTilt = 0.5;

}  // namespace

double SurfaceTextures::of(ElementKind kind) const {
  switch (kind) {
    case ElementKind::floor: return floor;
    case ElementKind::wall: return wall;
    case ElementKind::post:
    case ElementKind::beam:
    case ElementKind::rail:
    case ElementKind::deck: return bar;  // a deck is drawn in the bars' colour (render/scene.cpp)
    case ElementKind::tag: return tag;
    case ElementKind::box: return box;
  }
  return 0.0;
}

TelloSenses::TelloSenses(const SensesParams& params, const VehicleParams& vehicle, const CollisionWorld* world,
                         double light_level, std::uint64_t seed)
    : params_(params),
      vehicle_(vehicle),
      world_(world),
      light_(light_level),
      vps_stream_(seed, StreamId::vps),
      height_stream_(seed, StreamId::height_sensors),
      rate_mhz_(params.sample_rate_hz > 0.0 && params.sample_rate_hz <= 1e6 ? millihertz(params.sample_rate_hz) : 0) {
  const auto positive = [](double v) { return std::isfinite(v) && v > 0.0; };
  if (rate_mhz_ <= 0 || !positive(params.vps.bias_time_constant_s) || !positive(params.height_hold.time_constant_s)) {
    throw std::invalid_argument("senses: the sample rate and the time constants must be positive");
  }
}

std::optional<TelloSenses::Surface> TelloSenses::surface_below(const RigidBodyState& s, double max_range_m) const {
  const Eigen::Vector3d z_B = s.q_WB * Eigen::Vector3d::UnitZ();
  if (!(z_B.z() > kMinCosTilt)) return std::nullopt;
  const Eigen::Vector3d belly = s.p_WB_m - vehicle_.rest_height_m() * z_B;
  if (world_) {
    const std::optional<RayHit> hit = world_->ray_cast(belly, -z_B, max_range_m);
    if (!hit) return std::nullopt;
    return Surface{hit->distance_m, hit->element.kind};
  }
  // The floor plane alone: z = floor_z_m met along -z_B.
  const double range = std::max(0.0, belly.z() - vehicle_.floor_z_m) / z_B.z();
  if (range > max_range_m) return std::nullopt;
  return Surface{range, ElementKind::floor};
}

void TelloSenses::sample(const RigidBodyState& s, double dt_s) {
  const SensesParams& P = params_;
  const double cos_tilt = (s.q_WB * Eigen::Vector3d::UnitZ()).z();
  const std::optional<Surface> below =
      surface_below(s, std::max(P.vps.max_range_m, P.height.tof_max_range_m));
  // VPS: validity from the surface below, then its bias (Gauss-Markov, exact discretisation)
  // and this sample's noise. The first sample draws the bias from its stationary law.
  vps_.valid = below && below->range_m >= P.vps.min_range_m && below->range_m <= P.vps.max_range_m &&
               P.vps.texture.of(below->kind) * light_ >= P.vps.min_contrast;
  const double a = k_sample_ == 0 ? 0.0 : std::exp(-dt_s / P.vps.bias_time_constant_s);
  const double kick = P.vps.bias_stddev_mps * std::sqrt(1.0 - a * a);
  for (int i = 0; i < 2; ++i) {
    const double z_bias = vps_stream_.normal(), z_noise = vps_stream_.normal();
    vps_.bias_H_mps[i] = a * vps_.bias_H_mps[i] + kick * z_bias;
    vps_.error_H_mps[i] = vps_.bias_H_mps[i] + P.vps.noise_mps * z_noise;
  }
  // Height: the barometer's drift, the range reading and the hold's range target, the noises.
  Height& h = height_;
  h.baro_drift_m += P.height.baro_drift_m_per_sqrt_s * std::sqrt(dt_s) * height_stream_.normal();
  h.tof_noise_m = P.height.tof_noise_m * height_stream_.normal();
  h.height_noise_m = P.height.height_noise_m * height_stream_.normal();
  h.baro_noise_m = P.height.baro_noise_m * height_stream_.normal();
  h.range_target_m = 0.0;
  if (below && below->range_m <= P.height.tof_max_range_m) {
    const double above_m = (below->range_m + h.tof_noise_m) * cos_tilt + vehicle_.rest_height_m();
    if (above_m < P.height_hold.range_below_m) {
      const double z_range = vehicle_.floor_z_m + above_m;
      h.range_target_m = P.height_hold.range_blend * (z_range - (s.p_WB_m.z() + h.baro_drift_m));
    }
  }
}

SensedState TelloSenses::sense(TimeNs t_ns, const RigidBodyState& s) {
  const double dt = last_tick_ns_ ? ns_to_seconds(t_ns - *last_tick_ns_) : 0.0;
  last_tick_ns_ = t_ns;
  const double yaw = euler_zyx_from_quaternion(s.q_WB).z();
  // The position estimate dead-reckons the velocity error held over the tick.
  if (vps_.valid && dt > 0.0) vps_.error_p_W_m += heading_to_world(yaw, vps_.error_H_mps) * dt;
  if (t_ns >= event_time(k_sample_, rate_mhz_)) {
    sample(s, 1000.0 / static_cast<double>(rate_mhz_));
    while (event_time(k_sample_, rate_mhz_) <= t_ns) ++k_sample_;
  }
  Height& h = height_;
  if (dt > 0.0) h.range_offset_m += (h.range_target_m - h.range_offset_m) * -std::expm1(-dt / params_.height_hold.time_constant_s);
  SensedState out;
  out.horizontal_hold = vps_.valid;
  out.p_W_m = s.p_WB_m + Eigen::Vector3d(vps_.error_p_W_m.x(), vps_.error_p_W_m.y(), h.baro_drift_m + h.range_offset_m);
  out.v_W_mps = velocity_W(s);
  return out;
}

Eigen::Vector3d TelloSenses::velocity_W(const RigidBodyState& s) const {
  if (!vps_.valid) return {0.0, 0.0, s.v_WB_W_mps.z()};
  const Eigen::Vector2d e_W = heading_to_world(euler_zyx_from_quaternion(s.q_WB).z(), vps_.error_H_mps);
  return s.v_WB_W_mps + Eigen::Vector3d(e_W.x(), e_W.y(), 0.0);
}

SensedReadings TelloSenses::readings(const RigidBodyState& s) const {
  SensedReadings r;
  r.v_W_mps = velocity_W(s);
  const HeightSensorParams& P = params_.height;
  if (const std::optional<Surface> below = surface_below(s, P.tof_max_range_m)) {
    r.tof_m = std::max(P.tof_ground_m, P.tof_ground_m + below->range_m + height_.tof_noise_m);
  }
  r.height_W_m = s.p_WB_m.z() + height_.baro_drift_m + height_.range_offset_m + height_.height_noise_m;
  r.baro_m = s.p_WB_m.z() + height_.baro_drift_m + height_.baro_noise_m;
  return r;
}

}  // namespace shelfcross::plant
