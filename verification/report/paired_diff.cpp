#include "verification/report/paired_diff.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <sstream>
#include <utility>

#include <yaml-cpp/yaml.h>

#include "verification/campaign/campaign.hpp"
#include "verification/cosim/run_metrics_json.hpp"
#include "verification/report/crossing_push.hpp"

namespace shelfcross::verification {

DiffSide load_diff_side(const std::filesystem::path& folder_or_database) {
  DiffSide side;
  side.db_path = std::filesystem::is_directory(folder_or_database) ? folder_or_database / "results.sqlite"
                                                                   : folder_or_database;
  side.dir = side.db_path.parent_path().empty() ? std::filesystem::path(".") : side.db_path.parent_path();
  // A reader takes no lock: a campaign may go on storing runs meanwhile (WAL: this reads the
  // runs committed when it starts).
  const ResultsStore store = ResultsStore::open_existing(side.db_path);
  side.meta = store.meta();
  side.scenario = parse_scenario(side.meta.scenario_yaml, side.db_path.string() + " (scenario)");
  side.runs = store.runs();
  return side;
}

namespace {

/// key path -> scalar text of a YAML tree ("a.b[2].c").
void flatten(const YAML::Node& node, const std::string& path, std::map<std::string, std::string>& out) {
  if (node.IsMap()) {
    for (const auto& entry : node) {
      const std::string key = entry.first.as<std::string>();
      flatten(entry.second, path.empty() ? key : path + "." + key, out);
    }
  } else if (node.IsSequence()) {
    // A sequence of scalars is one value ("[1, 2, 3]"); of maps, one path per element.
    bool scalars = true;
    for (const auto& element : node) scalars = scalars && element.IsScalar();
    if (scalars) {
      std::string text = "[";
      for (std::size_t i = 0; i < node.size(); ++i) text += (i ? ", " : "") + node[i].as<std::string>();
      out[path] = text + "]";
    } else {
      for (std::size_t i = 0; i < node.size(); ++i) flatten(node[i], path + "[" + std::to_string(i) + "]", out);
    }
  } else if (node.IsScalar()) {
    out[path] = node.as<std::string>();
  } else {
    out[path] = "null";
  }
}

}  // namespace

std::vector<ScenarioDifference> scenario_differences(const Scenario& base, const Scenario& next) {
  std::vector<ScenarioDifference> out;
  if (base == next) return out;
  std::map<std::string, std::string> b, n;
  flatten(YAML::Load(write_scenario(base)), "", b);
  flatten(YAML::Load(write_scenario(next)), "", n);
  const std::string absent = "(absent)";
  for (const auto& [key, value] : b) {
    const auto it = n.find(key);
    if (it == n.end()) {
      out.push_back({key, value, absent});
    } else if (it->second != value) {
      out.push_back({key, value, it->second});
    }
  }
  for (const auto& [key, value] : n) {
    if (!b.count(key)) out.push_back({key, absent, value});
  }
  std::sort(out.begin(), out.end(), [](const auto& x, const auto& y) { return x.key < y.key; });
  // Equal in YAML but not as values (a double written alike): say so rather than nothing.
  if (out.empty()) out.push_back({"(scenario)", "differs", "differs"});
  return out;
}

double metric_tolerance(const std::string& name) {
  const auto ends_with = [&name](const std::string& suffix) {
    return name.size() >= suffix.size() && name.compare(name.size() - suffix.size(), suffix.size(), suffix) == 0;
  };
  if (name == "cpu_s") return 0.5;
  if (ends_with("_m")) return 0.005;
  if (ends_with("_s")) return 0.1;
  if (name.rfind("link_", 0) == 0 && !ends_with("_loss") && !ends_with("_fraction")) return 0.0;  // counts
  return 0.01;  // fractions, ratios, overshoots
}

namespace {

std::string text_of(double v) {
  std::ostringstream s;
  s << v;
  return s.str();
}

/// The pairs (index into base.runs, index into next.runs), by run index or by run seed.
std::vector<std::pair<std::size_t, std::size_t>> match_runs(const DiffSide& base, const DiffSide& next, bool by_seed) {
  std::map<std::uint64_t, std::size_t> next_by_key;
  for (std::size_t j = 0; j < next.runs.size(); ++j) {
    const RunRecord& r = next.runs[j];
    next_by_key[by_seed ? r.seed : static_cast<std::uint64_t>(r.index)] = j;
  }
  std::vector<std::pair<std::size_t, std::size_t>> pairs;
  for (std::size_t i = 0; i < base.runs.size(); ++i) {
    const RunRecord& r = base.runs[i];
    const auto it = next_by_key.find(by_seed ? r.seed : static_cast<std::uint64_t>(r.index));
    if (it != next_by_key.end()) pairs.emplace_back(i, it->second);
  }
  return pairs;
}

/// Refuses what cannot be paired by index (the file comment's rules).
void check_same_experiment(const DiffSide& base, const DiffSide& next) {
  const std::string flag = "; pass --allow-different-scenarios to compare them paired by run seed";
  if (base.meta.campaign_seed != next.meta.campaign_seed) {
    throw PairingRefused("BASE (" + base.db_path.string() + ") is campaign seed " +
                         std::to_string(base.meta.campaign_seed) + ", NEW (" + next.db_path.string() +
                         ") campaign seed " + std::to_string(next.meta.campaign_seed) +
                         ": their runs are other draws and cannot be paired; run NEW with --seed " +
                         std::to_string(base.meta.campaign_seed));
  }
  const std::vector<ScenarioDifference> d = scenario_differences(base.scenario, next.scenario);
  if (!d.empty()) {
    throw PairingRefused("the campaigns' scenarios differ (" + std::to_string(d.size()) + " key" +
                         (d.size() == 1 ? "" : "s") + "), first " + d.front().key + ": " + d.front().base +
                         " in BASE, " + d.front().next + " in NEW" + flag);
  }
}

/// Names drawn differently in a pair (or on one side only); empty when the pair's draws agree.
/// A record without draws (a worker_error) is not compared.
std::vector<std::string> differing_draws(const DrawnValues& b, const DrawnValues& n) {
  std::vector<std::string> names;
  if (b.empty() || n.empty()) return names;
  for (const auto& [name, value] : b) {
    const auto it = n.find(name);
    if (it == n.end() || it->second != value) names.push_back(name);
  }
  for (const auto& [name, value] : n) {
    if (!b.count(name)) names.push_back(name);
  }
  return names;
}

std::optional<double> value_of(const DrawnValues& d, const std::string& name) {
  const auto it = d.find(name);
  return it == d.end() ? std::nullopt : std::optional<double>(it->second);
}

void add_to_table(PairedTable& t, bool base_event, bool new_event) {
  if (base_event && new_event) ++t.both;
  else if (base_event) ++t.base_only;
  else if (new_event) ++t.new_only;
  else ++t.neither;
}

EventComparison compare_event(const PairedTable& t, double confidence) {
  EventComparison e;
  e.table = t;
  e.mcnemar = mcnemar_exact(t);
  const auto n = static_cast<double>(t.pairs());
  e.base_rate = static_cast<double>(t.both + t.base_only) / n;
  e.new_rate = static_cast<double>(t.both + t.new_only) / n;
  e.difference = newcombe_paired_difference(t, confidence);
  return e;
}

/// A run's metrics as compared: summary_metric_values(), the crossing's push from its trace,
/// then cpu_s.
std::vector<std::optional<double>> metric_row(const Scenario& scenario, const StoredMetrics& stored, const RunRecord& r) {
  std::vector<std::optional<double>> v = stored.run ? summary_metric_values(*stored.run)
                                                    : std::vector<std::optional<double>>(summary_metric_names().size());
  v.push_back(crossing_push_m(scenario, stored, stored_trace(r)));
  v.push_back(r.cpu_s);
  return v;
}

/// Draws that differ, name by name, over the pairs (allow_different_scenarios).
struct DrawTally {
  std::map<std::string, DrawDifference> by_name;
  std::int64_t pairs_with_any = 0;
  void add(const RunRecord& b, const RunRecord& n, const DrawnValues& bd, const DrawnValues& nd) {
    const std::vector<std::string> names = differing_draws(bd, nd);
    pairs_with_any += !names.empty();
    for (const std::string& name : names) {
      DrawDifference& d = by_name[name];
      if (d.pairs++ == 0) {
        d.name = name;
        d.first_base_run = b.index;
        d.first_new_run = n.index;
        d.first_base = value_of(bd, name);
        d.first_new = value_of(nd, name);
      }
    }
  }
};

}  // namespace

PairedDiff pair_campaigns(DiffSide base, DiffSide next, const DiffOptions& options) {
  PairedDiff diff;
  diff.paired_by_seed = options.allow_different_scenarios;
  diff.confidence = options.confidence;
  if (!diff.paired_by_seed) check_same_experiment(base, next);
  diff.scenario_differences = scenario_differences(base.scenario, next.scenario);
  const auto pairs = match_runs(base, next, diff.paired_by_seed);
  if (pairs.empty()) {
    throw PairingRefused("no run is stored on both sides (BASE " + std::to_string(base.runs.size()) + " runs, NEW " +
                         std::to_string(next.runs.size()) + (diff.paired_by_seed ? ", paired by run seed" : "") + ")");
  }
  diff.pairs = static_cast<std::int64_t>(pairs.size());
  PairedTable failures, contacts, near_misses;
  DrawTally draws;
  std::vector<std::string> names = summary_metric_names();
  names.emplace_back("crossing_push_m");
  names.emplace_back("cpu_s");
  diff.metrics.resize(names.size());
  for (std::size_t k = 0; k < names.size(); ++k) {
    diff.metrics[k].name = names[k];
    diff.metrics[k].tolerance = metric_tolerance(names[k]);
  }
  for (const auto& [i, j] : pairs) {
    const RunRecord& b = base.runs[i];
    const RunRecord& n = next.runs[j];
    const DrawnValues bd = stored_draws(b), nd = stored_draws(n);
    if (!diff.paired_by_seed) {
      if (const auto names_differing = differing_draws(bd, nd); !names_differing.empty()) {
        const std::string& name = names_differing.front();
        const auto show = [](const std::optional<double>& v) { return v ? text_of(*v) : std::string("not drawn"); };
        throw PairingRefused("run " + std::to_string(b.index) + " was drawn differently: " + name + " is " +
                             show(value_of(bd, name)) + " in BASE, " + show(value_of(nd, name)) + " in NEW (" +
                             std::to_string(names_differing.size()) +
                             " draws differ in this run); the builds draw the scenario differently, so the runs are "
                             "not the same flights; pass --allow-different-scenarios to compare them anyway");
      }
    }
    draws.add(b, n, bd, nd);
    diff.identical += b.run_hash == n.run_hash;
    const bool base_ok = b.outcome == "success", new_ok = n.outcome == "success";
    const bool base_contact = classify_outcome(b.outcome) == RunSafetyClass::contact;
    const bool new_contact = classify_outcome(n.outcome) == RunSafetyClass::contact;
    add_to_table(failures, !base_ok, !new_ok);
    add_to_table(contacts, base_contact, new_contact);
    const StoredMetrics bs = stored_metrics(b), ns = stored_metrics(n);
    const bool base_near = is_near_miss(b.outcome, bs.run, base.scenario.cosim.near_miss_m);
    const bool new_near = is_near_miss(n.outcome, ns.run, next.scenario.cosim.near_miss_m);
    add_to_table(near_misses, base_near, new_near);
    if (b.outcome != n.outcome || base_near != new_near) {
      diff.flips.push_back({b.index, n.index, b.seed, b.outcome, n.outcome, bs.detail, ns.detail, base_ok != new_ok,
                            base_contact != new_contact, base_near != new_near, new_near, bd, nd});
    }
    const auto bv = metric_row(base.scenario, bs, b), nv = metric_row(next.scenario, ns, n);
    for (std::size_t k = 0; k < names.size(); ++k) {
      if (bv[k]) diff.metrics[k].base_each.emplace_back(b.index, *bv[k]);
      if (nv[k]) diff.metrics[k].new_each.emplace_back(n.index, *nv[k]);
      if (!bv[k] || !nv[k]) continue;
      diff.metrics[k].base.push_back(*bv[k]);
      diff.metrics[k].next.push_back(*nv[k]);
    }
  }
  diff.failures = compare_event(failures, options.confidence);
  diff.contacts = compare_event(contacts, options.confidence);
  diff.near_misses = compare_event(near_misses, options.confidence);
  for (MetricComparison& m : diff.metrics) {
    m.pairs = static_cast<std::int64_t>(m.base.size());
    if (m.pairs == 0) continue;
    std::vector<double> d(m.base.size());
    for (std::size_t k = 0; k < d.size(); ++k) {
      d[k] = m.next[k] - m.base[k];
      m.moved_up += d[k] > m.tolerance;
      m.moved_down += d[k] < -m.tolerance;
    }
    m.paired = wilcoxon_signed_rank(d, options.confidence);
  }
  for (auto& [name, d] : draws.by_name) diff.draw_differences.push_back(std::move(d));
  diff.pairs_with_other_draws = draws.pairs_with_any;
  diff.base = std::move(base);
  diff.next = std::move(next);
  return diff;
}

bool new_is_worse(const PairedDiff& diff, double alpha) {
  return diff.failures.mcnemar.p_new_worse <= alpha || diff.contacts.mcnemar.p_new_worse <= alpha;
}

}  // namespace shelfcross::verification
