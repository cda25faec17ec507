// shelfcross frames --scenario FILE --out DIR [--condition NAME] [--check]: renders the
// perception benchmark's frame set (verification/frames/frame_set.hpp) into DIR, and with --check
// flies the flight software over each sequence of the set and prints what it decided.
#include <iostream>

#include "command_registry.hpp"
#include "verification/cosim/cosim.hpp"
#include "verification/frames/frame_set.hpp"
#include "verification/frames/pipeline_check.hpp"

namespace shelfcross::app {
namespace {

struct FramesOptions {
  std::string scenario = verification::kDefaultScenarioFile;
  std::string out = "build/bench_frames";
  std::string condition;
  bool check = false;
};

const CommandRegistration kFrames{
    "frames", "Render the perception benchmark's frame set (and check the flight software on it)",
    [](CLI::App& sub) {
      auto o = std::make_shared<FramesOptions>();
      sub.add_option("--scenario", o->scenario, "scenario file")->capture_default_str();
      sub.add_option("--out", o->out, "directory to write (manifest.csv and PNGs)")->capture_default_str();
      sub.add_option("--condition", o->condition, "only this condition: nominal, dim, bright or behind");
      sub.add_flag("--check", o->check,
                   "fly the flight software over each sequence with the fast and the reference pipeline and "
                   "compare their decisions; exit 1 if they differ");
      return [o]() -> int {
        if (!o->condition.empty()) {
          bool known = false;
          for (const frames::Condition& c : frames::frame_conditions()) known = known || o->condition == c.name;
          if (!known) throw UsageError("--condition: unknown condition '" + o->condition + "'");
        }
        const verification::Scenario sc = verification::load_scenario(o->scenario);
        if (sc.warehouse.shelves.empty()) throw UsageError(o->scenario + ": the frame set needs a shelf");
        const int n = frames::generate_frame_set(sc, o->out, o->condition);
        std::cout << "wrote " << n << " frames and manifest.csv to " << o->out << " (frame set version "
                  << frames::kFrameSetVersion << ")\n";
        if (!o->check) return 0;
        const frames::FrameSet set = frames::load_frame_set(o->out, sc);
        const flight_sw::FlightConfig config = verification::flight_config_for(sc, sc.camera);
        const frames::TagComparison tags = frames::compare_tag_detection(set, config);
        std::cout << tags.summary;
        bool all_same = tags.same;
        for (const frames::Condition& c : frames::frame_conditions()) {
          if (set.sequence(c.name).empty()) continue;
          const frames::PipelineComparison cmp = frames::compare_pipelines(set, c.name, config);
          std::cout << cmp.summary;
          all_same = all_same && cmp.same;
        }
        std::cout << (all_same ? "decisions: fast == reference\n" : "decisions DIFFER\n");
        return all_same ? 0 : 1;
      };
    }};

}  // namespace
}  // namespace shelfcross::app
