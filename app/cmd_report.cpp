// shelfcross report DIR: summary.json and report.md with its plots, from DIR/results.sqlite.
#include <iostream>

#include "command_registry.hpp"
#include "verification/report/report.hpp"

namespace shelfcross::app {
namespace {

const CommandRegistration kReport{
    "report", "Write a campaign's report: summary.json, report.md and PNG plots", [](CLI::App& sub) {
      auto dir = std::make_shared<std::string>();
      sub.add_option("dir", *dir, "campaign folder (holds results.sqlite)")->required();
      return [dir]() -> int {
        const verification::CampaignSummary summary = verification::write_campaign_report(*dir);
        std::cout << "wrote " << *dir << "/report.md, summary.json: " << summary.successes << " of " << summary.runs
                  << " runs succeeded\n";
        return 0;
      };
    }};

}  // namespace
}  // namespace shelfcross::app
