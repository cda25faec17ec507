// shelfcross compare --scenario FILE --runs N --seed S --jobs J --out DIR: the paper's Table 2
// for a scenario: one campaign per path strategy (through the cells, over the tops, around the
// ends) with the same dispersion draws, the table beside the paper's numbers, and the three
// paths in top and side views (Fig. 21). Resumable: the same command again runs what is missing.
#include <unistd.h>

#include <cstdio>
#include <iostream>
#include <thread>

#include "command_registry.hpp"
#include "verification/campaign/run_process.hpp"
#include "verification/report/compare.hpp"
#include "stop_signal.hpp"
#include "worker_options.hpp"

namespace shelfcross::app {
namespace {

struct CompareCliOptions {
  std::string scenario = "scenarios/warehouse_5_shelves.yaml";
  std::int64_t runs = 100;
  std::uint64_t seed = 1;
  int jobs = static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  std::string out = "out/compare";
  verification::WorkerLimits limits;
};

const CommandRegistration kCompare{
    "compare", "Compare the path strategies (through cells, over tops, around ends) as in the paper's Table 2",
    [](CLI::App& sub) {
      auto o = std::make_shared<CompareCliOptions>();
      sub.add_option("--scenario", o->scenario, "scenario file")->capture_default_str();
      sub.add_option("--runs", o->runs, "runs per strategy")->capture_default_str()->check(CLI::Range(1, 10000000));
      sub.add_option("--seed", o->seed, "campaign seed, shared by the three campaigns")->capture_default_str();
      sub.add_option("--jobs", o->jobs, "worker processes, one run each at a time (default: all cores)")->capture_default_str()->check(CLI::Range(1, 1024));
      sub.add_option("--out", o->out, "output folder: compare.md, compare.json, plots, one folder per strategy")
          ->capture_default_str();
      add_worker_limit_options(sub, o->limits);
      return [o]() -> int {
        const verification::Scenario nominal = verification::load_scenario(o->scenario);
        stop_on_signals();
        const bool tty = isatty(STDERR_FILENO);
        verification::CompareOptions options;
        options.jobs = o->jobs;
        options.stop = &stop_requested();
        options.make_workers = [o](std::shared_ptr<const verification::Scenario> scenario) {
          return verification::process_worker_factory(std::move(scenario), o->limits);
        };
        options.on_progress = [tty](const std::string& strategy, const verification::CampaignProgress& p) {
          char line[160];
          std::snprintf(line, sizeof line, "%s: %lld/%lld runs, %lld successes", strategy.c_str(),
                        static_cast<long long>(p.done), static_cast<long long>(p.total),
                        static_cast<long long>(p.successes));
          if (tty) {
            std::cerr << '\r' << line << std::flush;
            if (p.done == p.total) std::cerr << '\n';
          } else {
            std::cerr << line << '\n';
          }
        };
        const nlohmann::json j = verification::run_comparison(nominal, o->runs, o->seed, o->out, options);
        for (const auto& row : j["rows"]) {
          std::cout << row["strategy"].get<std::string>() << ": " << row["successes"] << "/" << row["runs"]
                    << " successes, mean distance " << row["mean_distance_m"] << " m, mean time " << row["mean_time_s"]
                    << " s, success lower bound " << row["success_lower_95"] << "\n";
        }
        std::cout << "wrote " << o->out << "/compare.md, compare.json, compare_top_view.png, compare_side_view.png\n";
        if (!j["complete"].get<bool>()) {
          std::cout << "interrupted: run the same command again to resume\n";
          return 130;
        }
        return 0;
      };
    }};

}  // namespace
}  // namespace shelfcross::app
