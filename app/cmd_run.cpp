// shelfcross run --scenario FILE --seed N --out DIR [--video]: one co-simulated run.
#include <iostream>

#include "command_registry.hpp"
#include "run_output.hpp"
#include "verification/scenario/scenario.hpp"

namespace shelfcross::app {
namespace {

struct RunOptions {
  std::string scenario = verification::kDefaultScenarioFile;
  std::uint64_t seed = 1;
  std::string out = "out/run";
  bool video = false;
};

const CommandRegistration kRun{
    "run", "Fly one co-simulated run: the flight software against the simulated Tello, world and camera",
    [](CLI::App& sub) {
      auto o = std::make_shared<RunOptions>();
      sub.add_option("--scenario", o->scenario, "scenario file")->capture_default_str();
      sub.add_option("--seed", o->seed, "the run's seed: its dispersion draws, noise, latencies")->capture_default_str();
      sub.add_option("--out", o->out, "output folder: run.json, trajectory.csv, events.log")->capture_default_str();
      sub.add_flag("--video", o->video, "also write video.mp4 (H.264, the camera's rate and size) with what the flight "
                "software computed from each picture drawn on it (docs/replay.md)");
      return [o]() -> int {
        const verification::Scenario nominal = verification::load_scenario(o->scenario);
        const verification::RunSetup setup = verification::disperse(nominal, o->seed);
        const verification::RunResult r = run_and_write(setup, o->out, o->video);
        std::cout << "run " << nominal.name << " seed " << o->seed << ": " << verification::outcome_name(r.outcome)
                  << (r.detail.empty() ? "" : " (" + r.detail + ")") << ", " << r.metrics.mission_time_s
                  << " s simulated, hash " << r.run_hash << "\n"
                  << "wrote " << o->out << "/run.json, trajectory.csv, events.log" << (o->video ? ", video.mp4" : "")
                  << "\n";
        return 0;
      };
    }};

}  // namespace
}  // namespace shelfcross::app
