#include "verification/campaign/campaign_merge.hpp"

#include <algorithm>
#include <map>

#include "verification/campaign/results_store.hpp"

namespace shelfcross::verification {

MergeCounts merge_campaigns(const std::vector<std::filesystem::path>& sources, const std::filesystem::path& target) {
  if (sources.empty()) throw ResultsMismatch("merge: no source databases given");
  std::vector<ResultsStore> stores;
  std::vector<std::string> source_names;
  for (const auto& path : sources) {
    if (std::filesystem::exists(target) && std::filesystem::equivalent(path, target)) continue;  // merging into a source
    stores.push_back(ResultsStore::open_existing(path));
    source_names.push_back(path.string());
  }
  CampaignMeta meta = stores.empty() ? ResultsStore::open_existing(target).meta() : stores.front().meta();
  for (size_t k = 0; k < stores.size(); ++k) {
    const CampaignMeta& m = stores[k].meta();
    if (m.scenario_yaml != meta.scenario_yaml || m.campaign_seed != meta.campaign_seed) {
      throw ResultsMismatch(source_names[k] + " holds another campaign (scenario or seed) than " + source_names.front());
    }
    meta.runs_requested = std::max(meta.runs_requested, m.runs_requested);
  }
  ResultsStore out = ResultsStore::open_or_create(target, meta);

  // Where each run index is (or will be) stored, to refuse runs that disagree.
  std::map<std::int64_t, std::pair<std::string, std::string>> hash_and_origin;
  for (const RunRecord& r : out.runs()) hash_and_origin[r.index] = {r.run_hash, target.string()};
  MergeCounts counts;
  std::vector<RunRecord> to_add;
  for (size_t k = 0; k < stores.size(); ++k) {
    for (RunRecord& r : stores[k].runs()) {
      const auto [it, inserted] = hash_and_origin.try_emplace(r.index, r.run_hash, source_names[k]);
      if (!inserted) {
        if (it->second.first != r.run_hash) {
          throw ResultsMismatch("run " + std::to_string(r.index) + " has hash " + r.run_hash + " in " + source_names[k] +
                                " but " + it->second.first + " in " + it->second.second +
                                ": the shards were not made by the same build");
        }
        ++counts.duplicates;
        continue;
      }
      to_add.push_back(std::move(r));
    }
  }
  std::sort(to_add.begin(), to_add.end(), [](const RunRecord& a, const RunRecord& b) { return a.index < b.index; });
  out.insert(to_add);
  counts.added = static_cast<std::int64_t>(to_add.size());
  return counts;
}

}  // namespace shelfcross::verification
