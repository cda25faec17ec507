#pragma once
// The air near a solid surface, per rotor: ground effect below it and ceiling effect above it,
// as factors on each rotor's thrust b Omega^2 (plant/dynamics.hpp), from the distance to the
// nearest surface along the rotor's axis (SurfaceEffectParams in plant/params.hpp).
//
// Ground (Cheeseman & Bennett, "The effect of the ground on a helicopter rotor in forward
// flight", ARC R&M 3021, 1955; the method of images on a rotor of radius R at height z over a
// plane, in hover):
//     T_IGE / T_OGE = 1 / (1 - k_g (R / 4z)^2),
// k_g = 1 the published curve (1.0667 at z = R, 1.0159 at 2R, 1.0039 at 4R). The formula is
// singular at z = R / 4 and fitted well above it, so z is taken no lower than R / 2 (1.333 at
// k_g = 1); above 5 R the excess is tapered linearly to nothing at 10 R (it is below 0.06 %
// there), so that the effect ends where the ray cast ends without a step.
//
// Ceiling: the momentum-theory model of a rotor under a plane at distance h,
//     T / T_inf = c(h) = 1/2 + 1/2 sqrt(1 + R^2 / (8 h^2))
// (2.34 at h = 0.1 R, 1.37 at 0.25 R, 1.11 at 0.5 R, 1.03 at R), the form used for the 23 mm
// propellers of small quadrotors whose ceiling effect Hsiao & Chirarattananon measured ("Ceiling
// effects for hybrid aerial-surface locomotion of small rotorcraft", IEEE/ASME Transactions on
// Mechatronics 24(5), 2019, doi:10.1109/TMECH.2019.2929589; the thrust rises steeply within
// about one radius of the ceiling). Its excess is made to act within ceiling_range_radii (1 by
// default) and to vanish there continuously:
//     factor = 1 + k_c (c(h) - c(h_max)) for h < h_max = ceiling_range_radii R, else 1,
// with h taken no lower than R / 4. k_c = 1 keeps the model's slope.
//
// Per rotor, one ray along -z_B (ground) and one along +z_B (ceiling) from the rotor's hub, in
// the body's x-y plane through the centre of mass (as the mixer has the rotors); the factor is
// the product of the two. A rotor over a box top, a deck or a bar sees that surface, one over an
// opening sees the floor far below: only some rotors over a deck give a difference of thrust
// between rotors, and so the moment of partial ground effect, through the mixer. A surface
// narrower than the disc (a 2 cm bar under a 45 mm disc) is taken as a plane: an overestimate.
// The reaction torque is left as in open air.
//
// The distances are measured once per autopilot tick (SimulatedTello) and the factors held, as
// the rotor commands are, over the tick: never inside the integrator's right-hand side.

#include <array>
#include <optional>

#include <Eigen/Core>

#include "plant/collision.hpp"
#include "plant/dynamics.hpp"
#include "plant/params.hpp"

namespace shelfcross::plant {

/// T_IGE / T_OGE at height z_m of the rotor over a surface (none: out of range, 1).
double ground_effect_factor(const SurfaceEffectParams& p, std::optional<double> z_m);
/// T / T_inf at distance h_m of the rotor under a surface (none: out of range, 1).
double ceiling_effect_factor(const SurfaceEffectParams& p, std::optional<double> h_m);

/// How far each ray looks: the ground's 10 R, the ceiling's range.
double ground_ray_range_m(const SurfaceEffectParams& p);
double ceiling_ray_range_m(const SurfaceEffectParams& p);

/// The distances along each rotor's axis, below (ground) and above (ceiling); none where the ray
/// met nothing within its range.
struct RotorSurfaceDistances {
  std::array<std::optional<double>, 4> below_m, above_m;
};

/// Ray casts in `world` from each rotor hub of the vehicle at `state` (see the file comment).
RotorSurfaceDistances rotor_surface_distances(const VehicleParams& vehicle, const CollisionWorld& world,
                                              const RigidBodyState& state);

/// Each rotor's thrust factor, ground times ceiling (all 1 with both coefficients 0).
Eigen::Vector4d rotor_thrust_factors(const SurfaceEffectParams& p, const RotorSurfaceDistances& d);

}  // namespace shelfcross::plant
