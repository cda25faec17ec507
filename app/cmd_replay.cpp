// shelfcross replay DIR --run K [--video]: re-runs run K of a campaign alone and checks its hash.
#include <iostream>

#include "command_registry.hpp"
#include "run_output.hpp"
#include "verification/campaign/results_store.hpp"
#include "verification/campaign/stored_run.hpp"
#include "verification/cosim/run_metrics_json.hpp"
#include "verification/scenario/scenario.hpp"
#include "verification/search/search.hpp"

namespace shelfcross::app {
namespace {

struct ReplayOptions {
  std::string dir;
  std::int64_t run = 0;
  bool video = false;
};

const CommandRegistration kReplay{
    "replay", "Re-run one run of a campaign alone and check that its hash matches the stored one",
    [](CLI::App& sub) {
      auto o = std::make_shared<ReplayOptions>();
      sub.add_option("dir", o->dir, "campaign folder (holds results.sqlite)")->required();
      sub.add_option("--run", o->run, "run index")->required()->check(CLI::NonNegativeNumber);
      sub.add_flag("--video", o->video, "also write video.mp4 (H.264, the camera's rate and size) with what the flight "
                "software computed from each picture drawn on it (docs/replay.md)");
      return [o]() -> int {
        const auto db = std::filesystem::path(o->dir) / "results.sqlite";
        verification::ResultsStore store = verification::ResultsStore::open_existing(db);
        if (o->run >= store.meta().runs_requested) {
          throw UsageError("run " + std::to_string(o->run) + " is not in this campaign of " +
                           std::to_string(store.meta().runs_requested) + " runs");
        }
        const verification::Scenario nominal = verification::parse_scenario(store.meta().scenario_yaml, db.string());
        const std::uint64_t seed = run_seed(store.meta().campaign_seed, static_cast<std::uint64_t>(o->run));
        const auto out = std::filesystem::path(o->dir) / ("replay_" + std::to_string(o->run));
        std::optional<verification::RunRecord> stored;
        for (const auto& rec : store.runs()) {
          if (rec.index == o->run) stored = rec;
        }
        // A search's runs draw from its proposals (verification/search/search.hpp): replayed with the
        // stored draws. A campaign's stored draws are its seed's own.
        const bool search = verification::is_search_database(db);
        if (search && !stored) throw UsageError("run " + std::to_string(o->run) + " of this search is not stored yet");
        const verification::RunSetup setup =
            search ? verification::disperse(nominal, seed, verification::stored_draws(*stored))
                   : verification::disperse(nominal, seed);
        const verification::RunResult r = run_and_write(setup, out, o->video);
        std::cout << "replay of run " << o->run << ": " << verification::outcome_name(r.outcome) << ", hash " << r.run_hash
                  << "\nwrote " << out.string() << ": run.json, trajectory.csv, events.log"
                  << (o->video ? ", video.mp4" : "") << "\n";
        if (!stored) {
          std::cout << "run " << o->run << " is not stored yet: nothing to compare\n";
          return 0;
        }
        if (stored->run_hash != r.run_hash) {
          std::cout << "MISMATCH: stored hash " << stored->run_hash << "\n";
          return 1;
        }
        std::cout << "hash matches the stored run\n";
        return 0;
      };
    }};

}  // namespace
}  // namespace shelfcross::app
