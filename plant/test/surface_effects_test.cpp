// Ground and ceiling effect per rotor (plant/surface_effects.hpp): the published curves, their
// ranges, the moment of a partial ground effect through the dynamics, and the distances from
// ray casts in the collision world.
#include "plant/surface_effects.hpp"

#include "plant/simulated_tello.hpp"

#include <gtest/gtest.h>

namespace shelfcross::plant {
namespace {

SurfaceEffectParams both_on() {
  SurfaceEffectParams p;
  p.ground_coeff = 1.0;
  p.ceiling_coeff = 1.0;
  return p;
}

// Cheeseman & Bennett: T_IGE / T_OGE = 1 / (1 - (R / 4z)^2) at z / R = 1, 2 and 4.
TEST(SurfaceEffects, GroundEffectIsThePublishedCurve) {
  const SurfaceEffectParams p = both_on();
  const double R = p.rotor_radius_m;
  for (const double z_over_R : {1.0, 2.0, 4.0}) {
    const double published = 1.0 / (1.0 - std::pow(1.0 / (4.0 * z_over_R), 2));
    EXPECT_NEAR(ground_effect_factor(p, z_over_R * R), published, 1e-12) << z_over_R;
  }
  EXPECT_NEAR(ground_effect_factor(p, R), 16.0 / 15.0, 1e-12);
  // Below R / 2 it holds the value there (the formula is singular at R / 4).
  EXPECT_NEAR(ground_effect_factor(p, 0.1 * R), 4.0 / 3.0, 1e-12);
  // Tapered from 5 R to nothing at 10 R; nothing beyond, nor without a surface, nor when off.
  const double at5 = 1.0 / (1.0 - std::pow(1.0 / 20.0, 2));
  EXPECT_NEAR(ground_effect_factor(p, 7.5 * R), 1.0 + 0.5 * (1.0 / (1.0 - std::pow(1.0 / 30.0, 2)) - 1.0), 1e-12);
  EXPECT_GT(ground_effect_factor(p, 5.0 * R), 1.0);
  EXPECT_NEAR(ground_effect_factor(p, 5.0 * R), at5, 1e-12);
  EXPECT_EQ(ground_effect_factor(p, 10.0 * R), 1.0);
  EXPECT_EQ(ground_effect_factor(p, std::nullopt), 1.0);
  SurfaceEffectParams off = p;
  off.ground_coeff = 0.0;
  EXPECT_EQ(ground_effect_factor(off, R), 1.0);
  // The coefficient scales the image term: k = 0.5 at z = R gives 1 / (1 - 1/32).
  SurfaceEffectParams half = p;
  half.ground_coeff = 0.5;
  EXPECT_NEAR(ground_effect_factor(half, R), 32.0 / 31.0, 1e-12);
}

// The ceiling model c(h) = 1/2 + 1/2 sqrt(1 + R^2 / (8 h^2)), less its value at the range: it
// acts within one radius by default and vanishes at and beyond it.
TEST(SurfaceEffects, CeilingEffectVanishesBeyondItsRange) {
  const SurfaceEffectParams p = both_on();
  const double R = p.rotor_radius_m;
  const auto c = [](double h_over_R) { return 0.5 + 0.5 * std::sqrt(1.0 + 1.0 / (8.0 * h_over_R * h_over_R)); };
  EXPECT_NEAR(ceiling_effect_factor(p, 0.5 * R), 1.0 + c(0.5) - c(1.0), 1e-12);
  EXPECT_NEAR(c(0.5), 1.1124, 1e-4);  // the model's own figure at half a radius
  EXPECT_GT(ceiling_effect_factor(p, 0.99 * R), 1.0);
  EXPECT_EQ(ceiling_effect_factor(p, R), 1.0);
  EXPECT_EQ(ceiling_effect_factor(p, 1.5 * R), 1.0);
  EXPECT_EQ(ceiling_effect_factor(p, 40.0 * R), 1.0);
  EXPECT_EQ(ceiling_effect_factor(p, std::nullopt), 1.0);
  // Held below R / 4.
  EXPECT_NEAR(ceiling_effect_factor(p, 0.01 * R), 1.0 + c(0.25) - c(1.0), 1e-12);
  // A wider range moves where it vanishes: 2 radii.
  SurfaceEffectParams wide = p;
  wide.ceiling_range_radii = 2.0;
  EXPECT_GT(ceiling_effect_factor(wide, 1.5 * R), 1.0);
  EXPECT_EQ(ceiling_effect_factor(wide, 2.0 * R), 1.0);
  EXPECT_EQ(ceiling_ray_range_m(wide), 2.0 * R);
}

// Two rotors over a surface at one radius, two over nothing: the front pair lifts 16/15 of
// its open-air thrust, and the dynamics turn the difference into a nose-up moment.
TEST(SurfaceEffects, PartialGroundEffectGivesItsMoment) {
  VehicleParams v;
  v.surface_effects = both_on();
  const double R = v.surface_effects.rotor_radius_m;
  RotorSurfaceDistances d;
  d.below_m = {R, R, std::nullopt, std::nullopt};  // rotors 1, 2: the front pair
  const Eigen::Vector4d k = rotor_thrust_factors(v.surface_effects, d);
  EXPECT_NEAR(k[0], 16.0 / 15.0, 1e-12);
  EXPECT_NEAR(k[1], 16.0 / 15.0, 1e-12);
  EXPECT_EQ(k[2], 1.0);
  EXPECT_EQ(k[3], 1.0);

  RigidBodyState x;
  x.p_WB_m = {0.0, 0.0, 1.0};
  x.rotor_speed_radps = Eigen::Vector4d::Constant(v.hover_rotor_speed_radps());
  const auto open = rigid_body_rhs(v, x, x.rotor_speed_radps, Eigen::Vector3d::Zero());
  const auto near = rigid_body_rhs(v, x, x.rotor_speed_radps, Eigen::Vector3d::Zero(), k);
  // Open air at hover speed: no vertical acceleration, no moment.
  EXPECT_NEAR(open[kIdxV + 2], 0.0, 1e-9);
  EXPECT_EQ(open[kIdxW + 1], 0.0);
  // Two rotors at 16/15: the weight times (2/4)(1/15) upward, and about y the pitch moment
  // -b a_x (k_1 + k_2 - 2) Omega^2 (front lifts: nose up, negative).
  const double g = v.gravity_mps2, w2 = v.hover_rotor_speed_radps() * v.hover_rotor_speed_radps();
  EXPECT_NEAR(near[kIdxV + 2], g * 0.5 / 15.0, 1e-9);
  const double tau_y = -v.thrust_coeff_N_per_radps2 * v.arm_x_m * (2.0 / 15.0) * w2;
  EXPECT_NEAR(near[kIdxW + 1], tau_y / v.inertia_kgm2.y(), 1e-9);
  EXPECT_LT(near[kIdxW + 1], 0.0);
  EXPECT_NEAR(near[kIdxW + 0], 0.0, 1e-12);  // left and right alike: no roll
  // Factors of 1 leave the right-hand side bit for bit as in open air.
  const auto ones = rigid_body_rhs(v, x, x.rotor_speed_radps, Eigen::Vector3d::Zero(), Eigen::Vector4d::Ones());
  EXPECT_EQ(ones, open);
}

// The distances come from ray casts along each rotor's axis in the collision world: over the
// paper's test shelf with 18 mm decks (beams 0.30, 0.64, 0.98 m; deck tops 0.01 + 0.018 above
// them), in the wide cell of level 2 (y = 0.24).
TEST(SurfaceEffects, RayCastsFindTheDeckUnderSomeRotorsAndTheDeckAbove) {
  Warehouse w;
  ShelfSpec s;
  s.origin_W_m = {3.0, 0.0, 0.0};
  s.column_pitch_m = {0.34, 0.48, 0.34, 0.48};
  s.row_pitch_m = {0.34, 0.34, 0.34, 0.34};
  s.deck_thickness_m = 0.018;
  w.shelves.push_back(s);
  VehicleParams v;
  v.surface_effects = both_on();
  const double R = v.surface_effects.rotor_radius_m;
  const CollisionWorld world(w, v.size_m, 0.0);
  // Straddling the front edge: the front rotors (x + 26.4 mm) over the deck under level 2, its
  // top at 0.668 m, one radius below them; the rear rotors (x - 26.4 mm) in front of the shelf,
  // over the floor far below. Partial ground effect: the front pair alone.
  RigidBodyState x;
  x.p_WB_m = {3.015, 0.24, 0.668 + R};
  RotorSurfaceDistances d = rotor_surface_distances(v, world, x);
  ASSERT_TRUE(d.below_m[0] && d.below_m[1]);
  EXPECT_NEAR(*d.below_m[0], R, 1e-12);
  EXPECT_NEAR(*d.below_m[1], R, 1e-12);
  EXPECT_FALSE(d.below_m[2] || d.below_m[3]);  // the floor is 30 radii down: beyond the ray
  Eigen::Vector4d k = rotor_thrust_factors(v.surface_effects, d);
  EXPECT_NEAR(k[0], 16.0 / 15.0, 1e-12);
  EXPECT_EQ(k[2], 1.0);
  // Inside the cell, half a radius under the deck of level 3 (its underside at 0.99 m): the
  // ceiling effect on every rotor, and no ground effect (the deck below is 14 radii down).
  x.p_WB_m = {3.17, 0.24, 0.99 - 0.5 * R};
  d = rotor_surface_distances(v, world, x);
  k = rotor_thrust_factors(v.surface_effects, d);
  const double expected = ceiling_effect_factor(v.surface_effects, 0.5 * R);
  EXPECT_GT(expected, 1.05);
  for (int i = 0; i < 4; ++i) {
    ASSERT_TRUE(d.above_m[i]) << i;
    EXPECT_NEAR(*d.above_m[i], 0.5 * R, 1e-12);
    EXPECT_NEAR(k[i], expected, 1e-12) << i;
  }
  // Both effects off: no ray is cast, every factor 1.
  VehicleParams off;
  const RotorSurfaceDistances none = rotor_surface_distances(off, world, x);
  EXPECT_FALSE(none.above_m[0] || none.below_m[0]);
  EXPECT_EQ(rotor_thrust_factors(off.surface_effects, none), Eigen::Vector4d::Ones());
}

// The simulated Tello measures the distances at each autopilot tick, in its senses' world, and
// holds the factors over the tick: landed, every rotor hub is half the airframe's height over
// the floor; off, or with no world, every rotor stays in open air.
TEST(SurfaceEffects, TheSimulatedTelloHoldsTheFactorsOfEachTick) {
  const CollisionWorld floor_only(Warehouse{}, VehicleParams{}.size_m, 0.0);
  VehicleParams v;
  v.surface_effects = both_on();
  SensesSetup senses;
  senses.world = &floor_only;
  SimulatedTello tello(v, AutopilotParams{}, WindParams{}, 1, {}, 0.0, 0.0, 0.0, senses);
  tello.step_to(kNsPerSecond / 100);
  const double landed = ground_effect_factor(v.surface_effects, v.rest_height_m());
  EXPECT_NEAR(landed, 1.0 / (1.0 - std::pow(v.surface_effects.rotor_radius_m / (4.0 * 0.0205), 2)), 1e-12);
  EXPECT_EQ(tello.plant().rotor_thrust_factors(), Eigen::Vector4d::Constant(landed));
  SimulatedTello open_air(VehicleParams{}, AutopilotParams{}, WindParams{}, 1, {}, 0.0, 0.0, 0.0, senses);
  open_air.step_to(kNsPerSecond / 100);
  EXPECT_EQ(open_air.plant().rotor_thrust_factors(), Eigen::Vector4d::Ones());
  SimulatedTello no_world(v, AutopilotParams{}, WindParams{}, 1);
  no_world.step_to(kNsPerSecond / 100);
  EXPECT_EQ(no_world.plant().rotor_thrust_factors(), Eigen::Vector4d::Ones());
}

}  // namespace
}  // namespace shelfcross::plant
