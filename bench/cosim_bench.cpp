// Speed of a whole co-simulated run: plant and autopilot at 500 Hz, swept collision checks,
// 960 x 720 rendering at 30 fps (llvmpipe on a CPU-only machine), the flight software on every
// frame, the link: one run of scenarios/paper_test_shelf.yaml without the Tello's own senses (the
// truth sensed) per iteration, with the `ideal` link (whole frames) and the `sdk` link (the
// Tello's H.264 stream encoded, cut into datagrams, decoded by tello_pilot's receiver; the pilot
// loop's driver), same seeds. BM_WholeRunSenses is the same on the scenario as shipped, with
// every effect on: the Tello's own senses (VPS, range, barometer: a downward ray cast per sensor
// sample), ground and ceiling effect per rotor (8 ray casts per autopilot tick) and the camera's
// rolling shutter.
//
// Run (one core's worth of work; see also bench/README.md):
//   taskset -c 1 build/release/bench/shelfcross_bench --benchmark_filter=WholeRun
// Time is process CPU time (llvmpipe's rasteriser thread included; LP_NUM_THREADS=1 and
// single-threaded OpenCV, as in render_bench.cpp). Counters:
//   sim_x        simulated seconds per CPU second (the "times real time" figure; target 30)
//   runs_per_h   runs per CPU hour of one core (a 2-core campaign does about twice that)
//   frames       frames rendered and handed to the flight software per run
#include <benchmark/benchmark.h>

#include <cstdlib>
#include <memory>

#include <opencv2/core/utility.hpp>

#include "shelfcross/random.hpp"
#include "verification/campaign/campaign.hpp"
#include "verification/cosim/cosim.hpp"
#include "verification/scenario/dispersion.hpp"
#include "verification/scenario/scenario.hpp"
#include "verification/scenario/senses_dispersion.hpp"

namespace {

using namespace shelfcross;
using namespace shelfcross::verification;

void whole_run(benchmark::State& state, const Scenario& shipped) {
  ::setenv("LP_NUM_THREADS", "1", 1);
  cv::setNumThreads(1);
  Scenario nominal = shipped;
  nominal.cosim.link.model = state.range(1) ? "sdk" : "ideal";
  // A fixed run of the default campaign (campaign seed 1, run index from the argument).
  const RunSetup setup = disperse(nominal, run_seed(1, static_cast<std::uint64_t>(state.range(0))));
  render::Renderer renderer(setup.scenario->warehouse, setup.scenario->camera, render_options_for(*setup.scenario));
  double simulated_s = 0.0, runs = 0.0, frames = 0.0;
  for (auto _ : state) {
    std::int64_t frames_this_run = 0;
    const RunResult r =
        run_cosimulation(setup, renderer, [&](const CameraFrame&, const flight_sw::FlightSoftware&) { ++frames_this_run; });
    simulated_s += r.metrics.mission_time_s;
    frames += static_cast<double>(frames_this_run);
    runs += 1.0;
    state.SetLabel(nominal.cosim.link.model + " " + outcome_name(r.outcome));
  }
  state.counters["sim_x"] = benchmark::Counter(simulated_s, benchmark::Counter::kIsRate);
  state.counters["runs_per_h"] = benchmark::Counter(3600.0 * runs, benchmark::Counter::kIsRate);
  state.counters["frames"] = benchmark::Counter(frames / runs);
  state.counters["sim_s"] = benchmark::Counter(simulated_s / runs);
}

void BM_WholeRun(benchmark::State& state) {
  static const Scenario truth = without_senses(load_scenario(SHELFCROSS_SOURCE_DIR "/scenarios/paper_test_shelf.yaml"));
  whole_run(state, truth);
}
BENCHMARK(BM_WholeRun)->ArgsProduct({{0, 1, 2}, {0, 1}})->ArgNames({"run", "sdk"})->Iterations(1)->MeasureProcessCPUTime()
    ->Unit(benchmark::kSecond);

void BM_WholeRunSenses(benchmark::State& state) {
  static const Scenario shipped = load_scenario(SHELFCROSS_SOURCE_DIR "/scenarios/paper_test_shelf.yaml");
  whole_run(state, shipped);
}
BENCHMARK(BM_WholeRunSenses)->ArgsProduct({{0, 1, 2}, {0, 1}})->ArgNames({"run", "sdk"})->Iterations(1)
    ->MeasureProcessCPUTime()->Unit(benchmark::kSecond);

}  // namespace
