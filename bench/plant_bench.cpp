// Plant + autopilot speed: simulated seconds per wall-clock second, autopilot (and plant input
// changes, each a CVODE re-initialisation) at 500 Hz.
//   build/release/bench/shelfcross_bench --benchmark_filter=Plant
// Each iteration flies 10 s from a hover at 1 m: 3 s hover, 4 s forward at half stick, 3 s
// yawing and climbing, with the default parameters (all model terms on, calm air).

#include <benchmark/benchmark.h>

#include "plant/simulated_tello.hpp"

namespace {

using namespace shelfcross;
using namespace shelfcross::plant;

// A Tello hovering at 1 m, as after `takeoff` (the climb itself is not part of the measure).
SimulatedTello hovering_tello(const WindParams& wind) {
  SimulatedTello tello(VehicleParams{}, AutopilotParams{}, wind, 7);
  tello.submit(0, "command");
  tello.submit(seconds_to_ns(0.1), "takeoff");
  tello.step_to(seconds_to_ns(6.0));
  return tello;
}

void fly_ten_seconds(benchmark::State& state, const WindParams& wind) {
  double simulated_s = 0.0;
  for (auto _ : state) {
    state.PauseTiming();
    SimulatedTello tello = hovering_tello(wind);
    const TimeNs t0 = tello.time_ns();
    state.ResumeTiming();
    tello.step_to(t0 + seconds_to_ns(3.0));
    tello.submit(t0 + seconds_to_ns(3.0), "rc 0 50 0 0");
    tello.step_to(t0 + seconds_to_ns(7.0));
    tello.submit(t0 + seconds_to_ns(7.0), "rc 0 0 20 50");
    tello.step_to(t0 + seconds_to_ns(10.0));
    benchmark::DoNotOptimize(tello.state().p_WB_m.data());
    simulated_s += 10.0;
  }
  state.counters["sim_s_per_wall_s"] = benchmark::Counter(simulated_s, benchmark::Counter::kIsRate);
}

void BM_PlantAutopilot500Hz_Calm(benchmark::State& state) { fly_ten_seconds(state, WindParams{}); }
BENCHMARK(BM_PlantAutopilot500Hz_Calm)->Unit(benchmark::kMillisecond);

void BM_PlantAutopilot500Hz_Gusty(benchmark::State& state) {
  WindParams wind;
  wind.steady_W_mps = Eigen::Vector3d(0.3, -0.2, 0.0);
  wind.gust_stddev_mps = 0.3;
  fly_ten_seconds(state, wind);
}
BENCHMARK(BM_PlantAutopilot500Hz_Gusty)->Unit(benchmark::kMillisecond);

}  // namespace
