// Collision world: the cost of one plant step's swept check, and of a clearance query, on the
// default scenario (the paper's test shelf). Run:
//   build/release/bench/shelfcross_bench --benchmark_filter=Collision
#include <benchmark/benchmark.h>

#include "plant/collision.hpp"
#include "verification/scenario/scenario.hpp"

namespace {

using shelfcross::TimeNs;
using shelfcross::plant::CollisionWorld;

const shelfcross::verification::Scenario& scenario() {
  static const auto s = shelfcross::verification::load_scenario(
      std::string(SHELFCROSS_SOURCE_DIR) + "/" + shelfcross::verification::kDefaultScenarioFile);
  return s;
}

Eigen::Isometry3d pose(double x, double y, double z, double yaw_rad) {
  Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
  X.linear() = Eigen::AngleAxisd(yaw_rad, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  X.translation() = Eigen::Vector3d(x, y, z);
  return X;
}

// One 2 ms step at 1 m/s with a little yaw, at x0 (a crossing of the empty wide cell at level 2,
// column 2, centred y = 0.24, z = 0.81); the path repeats over 2.5 m so the mix of steps far
// from and inside the shelf is that of a real crossing.
void sweep_crossing(benchmark::State& state, double speed_mps) {
  const CollisionWorld world(scenario().warehouse, scenario().vehicle.size_m, 0.01);
  constexpr TimeNs kStepNs = 2'000'000;
  const double step_m = speed_mps * 0.002;
  double x = 2.0;
  TimeNs t = 0;
  for (auto _ : state) {
    const auto c = world.sweep(pose(x, 0.24, 0.81, 0.01 * x), t, pose(x + step_m, 0.24, 0.81,
                               0.01 * (x + step_m)), t + kStepNs);
    benchmark::DoNotOptimize(c);
    x += step_m;
    t += kStepNs;
    if (x > 4.5) x = 2.0;
  }
}
void BM_CollisionSweepCrossing1mps(benchmark::State& state) { sweep_crossing(state, 1.0); }
void BM_CollisionSweepCrossing8mps(benchmark::State& state) { sweep_crossing(state, 8.0); }
BENCHMARK(BM_CollisionSweepCrossing1mps);
BENCHMARK(BM_CollisionSweepCrossing8mps);

// A step hovering inside the front plane of the cell (the most candidates at once).
void BM_CollisionSweepInsideCell(benchmark::State& state) {
  const CollisionWorld world(scenario().warehouse, scenario().vehicle.size_m, 0.01);
  const Eigen::Isometry3d a = pose(3.0, 0.24, 0.81, 0.0), b = pose(3.002, 0.24, 0.81, 0.004);
  for (auto _ : state) benchmark::DoNotOptimize(world.sweep(a, 0, b, 2'000'000));
}
BENCHMARK(BM_CollisionSweepInsideCell);

// A landed step: the floor is touched; the harness asks for the first non-floor contact.
void BM_CollisionSweepLandedIgnoringFloor(benchmark::State& state) {
  const CollisionWorld world(scenario().warehouse, scenario().vehicle.size_m, 0.01);
  const Eigen::Isometry3d a = pose(0.0, 0.0, 0.0205, 0.0);
  for (auto _ : state) {
    benchmark::DoNotOptimize(
        world.sweep(a, 0, a, 2'000'000, shelfcross::plant::FloorContacts::ignore));
  }
}
BENCHMARK(BM_CollisionSweepLandedIgnoringFloor);

void BM_CollisionClearanceNearShelf(benchmark::State& state) {
  const CollisionWorld world(scenario().warehouse, scenario().vehicle.size_m, 0.01);
  const Eigen::Isometry3d X = pose(2.8, 0.24, 0.81, 0.1);
  for (auto _ : state) benchmark::DoNotOptimize(world.clearance_to_shelves(X));
}
BENCHMARK(BM_CollisionClearanceNearShelf);

void BM_CollisionClearanceAtStart(benchmark::State& state) {
  const CollisionWorld world(scenario().warehouse, scenario().vehicle.size_m, 0.01);
  const Eigen::Isometry3d X = pose(0.0, 0.0, 1.0, 0.0);
  for (auto _ : state) benchmark::DoNotOptimize(world.clearance_to_shelves(X));
}
BENCHMARK(BM_CollisionClearanceAtStart);

void BM_CollisionWorldBuild(benchmark::State& state) {
  for (auto _ : state) {
    CollisionWorld world(scenario().warehouse, scenario().vehicle.size_m, 0.01);
    benchmark::DoNotOptimize(world.elements().data());
  }
}
BENCHMARK(BM_CollisionWorldBuild);

}  // namespace
