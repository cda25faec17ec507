// shelfcross merge --out DIR SRC...: combines the databases of a campaign's shards
// (`campaign --shard I/N`) into DIR/results.sqlite and writes its report; with every shard
// present, the campaign hash is the one a single process would have computed.
#include <iostream>

#include "command_registry.hpp"
#include "verification/campaign/campaign_merge.hpp"
#include "verification/report/report.hpp"

namespace shelfcross::app {
namespace {

struct MergeOptions {
  std::vector<std::string> sources;
  std::string out;
};

const CommandRegistration kMerge{
    "merge", "Combine campaign shards (campaign --shard I/N) into one results database and report",
    [](CLI::App& sub) {
      auto o = std::make_shared<MergeOptions>();
      sub.add_option("sources", o->sources, "shard output folders (holding results.sqlite) or .sqlite files")->required();
      sub.add_option("--out", o->out, "output folder: results.sqlite, summary.json, report.md")->required();
      return [o]() -> int {
        namespace fs = std::filesystem;
        std::vector<fs::path> dbs;
        for (const std::string& s : o->sources) {
          const fs::path p = fs::is_directory(s) ? fs::path(s) / "results.sqlite" : fs::path(s);
          if (!fs::is_regular_file(p)) throw UsageError(s + ": no results database (expected a campaign folder or a .sqlite file)");
          dbs.push_back(p);
        }
        fs::create_directories(o->out);
        const verification::MergeCounts counts = verification::merge_campaigns(dbs, fs::path(o->out) / "results.sqlite");
        const verification::CampaignSummary summary = verification::write_campaign_report(o->out);
        const std::int64_t stored = summary.runs, requested = summary.runs_requested;
        std::cout << "merged " << dbs.size() << " databases: " << counts.added << " runs added, " << counts.duplicates
                  << " already present; " << stored << " of " << requested << " runs stored\n";
        if (stored == requested) {
          std::cout << "campaign hash " << summary.campaign_hash << "\n";
        } else {
          std::cout << requested - stored << " runs missing: merge again when the remaining shards are done\n";
        }
        std::cout << "wrote " << o->out << "/results.sqlite, summary.json, report.md\n";
        return 0;
      };
    }};

}  // namespace
}  // namespace shelfcross::app
