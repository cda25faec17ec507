// shelfcross campaign --scenario FILE --runs N --seed S --jobs J --out DIR: a Monte Carlo
// crossing campaign; resumable (the same command again runs only what is missing).
#include <unistd.h>

#include <csignal>
#include <cstdio>
#include <iostream>
#include <thread>

#include "command_registry.hpp"
#include "verification/campaign.hpp"
#include "verification/report.hpp"

namespace shelfcross::app {
namespace {

std::atomic<bool> g_stop{false};
extern "C" void request_stop(int) { g_stop = true; }

struct CampaignOptions {
  std::string scenario = verification::kDefaultScenarioFile;
  std::int64_t runs = 100;
  std::uint64_t seed = 1;
  int jobs = static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  std::string out = "out/campaign";
};

std::string duration(double s) {
  char text[32];
  std::snprintf(text, sizeof text, "%d:%02d:%02d", static_cast<int>(s) / 3600, static_cast<int>(s) / 60 % 60,
                static_cast<int>(s) % 60);
  return text;
}

const CommandRegistration kCampaign{
    "campaign", "Run a Monte Carlo crossing campaign over the scenario's dispersions (resumable)",
    [](CLI::App& sub) {
      auto o = std::make_shared<CampaignOptions>();
      sub.add_option("--scenario", o->scenario, "scenario file")->capture_default_str();
      sub.add_option("--runs", o->runs, "number of runs")->capture_default_str()->check(CLI::Range(1, 10000000));
      sub.add_option("--seed", o->seed, "campaign seed; run k's seed is a fixed hash of (seed, k)")->capture_default_str();
      sub.add_option("--jobs", o->jobs, "worker threads (default: all cores)")->capture_default_str()->check(CLI::Range(1, 1024));
      sub.add_option("--out", o->out, "output folder: results.sqlite, summary.json, report.md")->capture_default_str();
      return [o]() -> int {
        auto nominal = std::make_shared<const verification::Scenario>(verification::load_scenario(o->scenario));
        std::filesystem::create_directories(o->out);
        const verification::CampaignMeta meta{verification::write_scenario(*nominal), o->seed, o->runs};
        verification::ResultsStore store =
            verification::ResultsStore::open_or_create(std::filesystem::path(o->out) / "results.sqlite", meta);
        std::signal(SIGINT, request_stop);
        std::signal(SIGTERM, request_stop);
        const bool tty = isatty(STDERR_FILENO);
        std::int64_t last_line = -1;
        const auto progress = [&](const verification::CampaignProgress& p) {
          const int width = 30;
          const int filled = static_cast<int>(width * p.done / std::max<std::int64_t>(1, p.total));
          char line[160];
          std::snprintf(line, sizeof line, "[%s%s] %lld/%lld runs, %lld successes, %s left", std::string(filled, '#').c_str(),
                        std::string(width - filled, '.').c_str(), static_cast<long long>(p.done),
                        static_cast<long long>(p.total), static_cast<long long>(p.successes), duration(p.remaining_s).c_str());
          if (tty) {
            std::cerr << '\r' << line << std::flush;
          } else if (p.done * 10 / p.total != last_line || p.done == p.total) {
            last_line = p.done * 10 / p.total;
            std::cerr << line << '\n';
          }
        };
        const auto factory = [nominal](int) { return std::make_unique<verification::CampaignWorker>(nominal); };
        const std::int64_t added =
            verification::run_pending(store, o->seed, o->runs, factory, {.jobs = o->jobs, .on_progress = progress, .stop = &g_stop});
        if (tty) std::cerr << '\n';
        const nlohmann::json summary = verification::write_campaign_report(o->out);
        std::cout << "campaign " << nominal->name << ": " << added << " runs this time, " << summary["runs"] << " of "
                  << o->runs << " stored; " << summary["successes"] << " successes, success rate "
                  << summary["success_rate"] << ", 95 % lower bound " << summary["success_lower_95"] << "\n"
                  << "wrote " << o->out << "/results.sqlite, summary.json, report.md\n";
        if (summary["runs"].get<std::int64_t>() < o->runs) {
          std::cout << "interrupted: run the same command again to resume\n";
          return 130;
        }
        return 0;
      };
    }};

}  // namespace
}  // namespace shelfcross::app
