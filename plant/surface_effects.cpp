#include "plant/surface_effects.hpp"

#include <algorithm>
#include <cmath>

namespace shelfcross::plant {
namespace {

constexpr double kGroundFloorRadii = 0.5;     // z no lower than R / 2 (singular at R / 4)
constexpr double kGroundFullRadii = 5.0;      // the published curve up to 5 R ...
constexpr double kGroundRangeRadii = 10.0;    // ... tapered to nothing at 10 R
constexpr double kCeilingFloorRadii = 0.25;   // h no lower than R / 4

/// The ceiling model's T / T_inf at h (file comment).
double ceiling_model(double R, double h) { return 0.5 + 0.5 * std::sqrt(1.0 + R * R / (8.0 * h * h)); }

}  // namespace

double ground_ray_range_m(const SurfaceEffectParams& p) { return kGroundRangeRadii * p.rotor_radius_m; }
double ceiling_ray_range_m(const SurfaceEffectParams& p) { return p.ceiling_range_radii * p.rotor_radius_m; }

double ground_effect_factor(const SurfaceEffectParams& p, std::optional<double> z_m) {
  const double R = p.rotor_radius_m;
  if (p.ground_coeff <= 0.0 || !z_m || *z_m >= kGroundRangeRadii * R) return 1.0;
  const double z = std::max(*z_m, kGroundFloorRadii * R);
  const double r = R / (4.0 * z);
  const double excess = 1.0 / (1.0 - p.ground_coeff * r * r) - 1.0;
  const double taper = std::clamp((kGroundRangeRadii * R - z) / ((kGroundRangeRadii - kGroundFullRadii) * R), 0.0, 1.0);
  return 1.0 + excess * taper;
}

double ceiling_effect_factor(const SurfaceEffectParams& p, std::optional<double> h_m) {
  const double R = p.rotor_radius_m, h_max = ceiling_ray_range_m(p);
  if (p.ceiling_coeff <= 0.0 || !h_m || *h_m >= h_max) return 1.0;
  const double h = std::max(*h_m, kCeilingFloorRadii * R);
  return 1.0 + p.ceiling_coeff * (ceiling_model(R, std::min(h, h_max)) - ceiling_model(R, h_max));
}

RotorSurfaceDistances rotor_surface_distances(const VehicleParams& vehicle, const CollisionWorld& world,
                                              const RigidBodyState& state) {
  const SurfaceEffectParams& p = vehicle.surface_effects;
  const Eigen::Matrix3d R_WB = state.q_WB.normalized().toRotationMatrix();
  const Eigen::Vector3d up_W = R_WB.col(2);
  RotorSurfaceDistances d;
  for (int i = 0; i < 4; ++i) {
    const Eigen::Vector3d hub_W =
        state.p_WB_m + R_WB * Eigen::Vector3d(kRotorSx[i] * vehicle.arm_x_m, kRotorSy[i] * vehicle.arm_y_m, 0.0);
    if (p.ground_coeff > 0.0) {
      if (const auto hit = world.ray_cast(hub_W, -up_W, ground_ray_range_m(p))) d.below_m[i] = hit->distance_m;
    }
    if (p.ceiling_coeff > 0.0) {
      if (const auto hit = world.ray_cast(hub_W, up_W, ceiling_ray_range_m(p))) d.above_m[i] = hit->distance_m;
    }
  }
  return d;
}

Eigen::Vector4d rotor_thrust_factors(const SurfaceEffectParams& p, const RotorSurfaceDistances& d) {
  Eigen::Vector4d k;
  for (int i = 0; i < 4; ++i) k[i] = ground_effect_factor(p, d.below_m[i]) * ceiling_effect_factor(p, d.above_m[i]);
  return k;
}

}  // namespace shelfcross::plant
