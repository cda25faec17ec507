#include "verification/report/compare.hpp"

#include <cmath>
#include <fstream>
#include <iomanip>
#include <map>
#include <sstream>

#include "config/strict_json.hpp"
#include "verification/campaign/campaign.hpp"
#include "verification/campaign/stored_run.hpp"
#include "verification/cosim/cosim.hpp"
#include "verification/cosim/run_metrics_json.hpp"
#include "verification/plot/plot.hpp"
#include "verification/report/report.hpp"
#include "verification/statistics/statistics.hpp"

namespace shelfcross::verification {

using config::number_or_null;
namespace {

using nlohmann::json;

struct PaperRow {
  const char* strategy;
  const char* label;
  double distance_m, time_s;
};
// docs/method.md section 6, Table 2 (simulated five-shelf warehouse, mean over runs).
const PaperRow kPaper[] = {{"through_cells", "through empty cells (this method)", 14.0, 240.0},
                           {"over_tops", "over the shelf tops", 22.0, 300.0},
                           {"around_ends", "around the shelf sides", 28.0, 360.0}};

const PaperRow& paper_row(const std::string& strategy) {
  for (const PaperRow& r : kPaper) {
    if (strategy == r.strategy) return r;
  }
  throw std::invalid_argument("unknown strategy '" + strategy + "'");
}

const cv::Scalar kColours[] = {cv::Scalar(60, 160, 60), cv::Scalar(200, 120, 30), cv::Scalar(40, 40, 220)};

}  // namespace

const std::vector<std::string>& compared_strategies() {
  static const std::vector<std::string> s{"through_cells", "over_tops", "around_ends"};
  return s;
}

StrategyRow summarize_strategy(const std::string& strategy, const std::vector<RunRecord>& runs,
                               std::int64_t runs_requested) {
  StrategyRow row;
  row.strategy = strategy;
  row.paper_distance_m = paper_row(strategy).distance_m;
  row.paper_time_s = paper_row(strategy).time_s;
  std::vector<double> distance, time, recall;
  std::vector<std::string> outcomes;
  for (const RunRecord& r : runs) {
    if (r.index >= runs_requested) continue;
    ++row.runs;
    outcomes.push_back(r.outcome);
    const StoredMetrics stored = stored_metrics(r);
    if (stored.run) recall.push_back(stored.run->inventory.recall);
    if (r.outcome != "success") continue;
    ++row.successes;
    distance.push_back(stored.run.value().truth.path_length_m);  // a success always measured its run
    time.push_back(stored.run.value().mission_time_s);
  }
  row.success_rate = row.runs ? static_cast<double>(row.successes) / static_cast<double>(row.runs) : 0.0;
  row.success_lower_95 = row.runs ? clopper_pearson_lower(row.successes, row.runs, 0.95) : 0.0;
  const SafetySummary safety = summarize_safety(outcomes);
  row.contacts = safety.contacts;
  row.contact_upper_95 = safety.contact_upper_95;
  row.safe_aborts = safety.safe_aborts;
  row.inventory_errors = safety.inventory_errors;
  if (!distance.empty()) row.mean_distance_m = summarize(distance).mean;
  if (!time.empty()) row.mean_time_s = summarize(time).mean;
  if (!recall.empty()) row.mean_recall = summarize(recall).mean;
  return row;
}

std::string comparison_table_markdown(const std::vector<StrategyRow>& rows) {
  std::ostringstream md;
  md << "| path strategy | runs | mean distance (m) | paper | mean time (s) | paper | success rate | "
        "95 % lower bound | contacts | contact 95 % upper bound | safe aborts | inventory errors | inventory recall |\n"
     << "|---|---|---|---|---|---|---|---|---|---|---|---|---|\n";
  const auto opt = [](const std::optional<double>& v, int decimals) { return v ? fixed_text(*v, decimals) : std::string("-"); };
  for (const StrategyRow& r : rows) {
    md << "| " << paper_row(r.strategy).label << " | " << r.runs << " | " << opt(r.mean_distance_m, 2) << " | "
       << fixed_text(r.paper_distance_m, 0) << " | " << opt(r.mean_time_s, 1) << " | " << fixed_text(r.paper_time_s, 0) << " | "
       << r.successes << "/" << r.runs << " = " << fixed_text(r.success_rate, 3) << " | " << fixed_text(r.success_lower_95, 3)
       << " | " << r.contacts << " | " << fixed_text(r.contact_upper_95, 4) << " | " << r.safe_aborts << " | "
       << r.inventory_errors << " | " << opt(r.mean_recall, 4) << " |\n";
  }
  md << "\nMean distance and time over the successful runs (a failed run ends early); recall over every run. "
        "Lower bound: one-sided Clopper-Pearson at 95 %. Safety apart from success: contacts (a shelf or a "
        "wall touched) with their one-sided 95 % Clopper-Pearson upper bound, safe aborts (gave up, landed "
        "without contact), inventory errors. Paper: docs/method.md section 6, Table 2.\n";
  return md.str();
}

RunByRun compare_run_by_run(const std::vector<std::string>& strategies,
                            const std::vector<std::vector<RunRecord>>& runs_per_strategy, std::int64_t runs_requested) {
  if (strategies.size() < 2 || strategies.size() != runs_per_strategy.size()) {
    throw std::invalid_argument("run by run: needs two or more strategies, each with its runs");
  }
  // (time, distance) of each strategy's successful runs, by run index.
  struct Flown {
    double time_s, distance_m;
  };
  std::vector<std::map<std::int64_t, Flown>> flown(strategies.size());
  for (std::size_t k = 0; k < strategies.size(); ++k) {
    for (const RunRecord& r : runs_per_strategy[k]) {
      if (r.index >= runs_requested || r.outcome != "success") continue;
      const RunMetrics m = stored_metrics(r).run.value();  // a success always measured its run
      flown[k][r.index] = {m.mission_time_s, m.truth.path_length_m};
    }
  }
  RunByRun out;
  out.first = strategies.front();
  std::vector<std::vector<double>> dt(strategies.size()), dd(strategies.size());
  out.against.resize(strategies.size() - 1);
  for (const auto& [index, first] : flown.front()) {
    bool all = true, shortest = true, fastest = true;
    for (std::size_t k = 1; k < strategies.size(); ++k) {
      const auto it = flown[k].find(index);
      if (it == flown[k].end()) {
        all = false;
        continue;
      }
      RunByRun::Against& a = out.against[k - 1];
      ++a.pairs;
      a.shorter += first.distance_m < it->second.distance_m;
      a.faster += first.time_s < it->second.time_s;
      dt[k].push_back(it->second.time_s - first.time_s);
      dd[k].push_back(it->second.distance_m - first.distance_m);
      shortest = shortest && first.distance_m < it->second.distance_m;
      fastest = fastest && first.time_s < it->second.time_s;
    }
    if (!all) continue;
    ++out.runs;
    out.shortest += shortest;
    out.fastest += fastest;
    if (!fastest) out.not_fastest.push_back(index);
  }
  for (std::size_t k = 1; k < strategies.size(); ++k) {
    RunByRun::Against& a = out.against[k - 1];
    a.strategy = strategies[k];
    if (a.pairs == 0) continue;
    a.time_s = wilcoxon_signed_rank(dt[k], 0.95);
    a.distance_m = wilcoxon_signed_rank(dd[k], 0.95);
  }
  if (out.runs > 0) {
    out.shortest_lower_95 = clopper_pearson_lower(out.shortest, out.runs, 0.95);
    out.fastest_lower_95 = clopper_pearson_lower(out.fastest, out.runs, 0.95);
  }
  return out;
}

std::string run_by_run_markdown(const RunByRun& r) {
  if (r.runs == 0) return "";
  const auto share = [&r](std::int64_t n, double lower) {
    return std::to_string(n) + " of " + std::to_string(r.runs) + " (" +
           fixed_text(100.0 * static_cast<double>(n) / static_cast<double>(r.runs), 1) + " %; at least " +
           fixed_text(100.0 * lower, 1) + " %, one-sided 95 %)";
  };
  std::ostringstream md;
  md << "## Run by run\n\nOver the " << r.runs << " runs every strategy flew successfully (the same seed and draws): "
     << r.first << " the shortest in " << share(r.shortest, r.shortest_lower_95) << ", the fastest in "
     << share(r.fastest, r.fastest_lower_95) << ".\n\n"
     << "| against | runs both succeeded | " << r.first << " shorter | " << r.first
     << " faster | time shift (other - " << r.first << ") | 95 % interval | Wilcoxon p | distance shift | 95 % interval |\n"
     << "|---|---|---|---|---|---|---|---|---|\n";
  for (const RunByRun::Against& a : r.against) {
    md << "| " << a.strategy << " | " << a.pairs << " | " << a.shorter << " | " << a.faster << " | ";
    if (a.pairs == 0) {
      md << "| | | | |\n";
      continue;
    }
    std::ostringstream p;
    p << std::setprecision(3) << a.time_s.p_two_sided;
    md << fixed_text(a.time_s.hodges_lehmann, 1) << " s | " << fixed_text(a.time_s.interval.lower, 1) << " to "
       << fixed_text(a.time_s.interval.upper, 1) << " s | " << p.str() << " | " << fixed_text(a.distance_m.hodges_lehmann, 2)
       << " m | " << fixed_text(a.distance_m.interval.lower, 2) << " to " << fixed_text(a.distance_m.interval.upper, 2) << " m |\n";
  }
  md << "\nShift: the Hodges-Lehmann estimate of the paired difference with its distribution-free interval. ";
  if (r.not_fastest.empty()) {
    md << r.first << " was the fastest in every such run.\n";
  } else {
    md << "Runs where " << r.first << " was not the fastest (replay them in `" << r.first << "/`):";
    for (std::int64_t i : r.not_fastest) md << " " << i;
    md << ".\n";
  }
  return md.str();
}

std::int64_t write_comparison_plots(const Scenario& nominal, const std::vector<std::vector<RunRecord>>& runs_per_strategy,
                                    const std::filesystem::path& out_dir) {
  // The run to show: the lowest index every strategy flew successfully, else 0.
  std::int64_t shown = -1;
  if (!runs_per_strategy.empty()) {
    for (const RunRecord& r : runs_per_strategy.front()) {
      bool all = true;
      for (const auto& runs : runs_per_strategy) {
        bool ok = false;
        for (const RunRecord& q : runs) ok = ok || (q.index == r.index && q.outcome == "success");
        all = all && ok;
      }
      if (all && (shown < 0 || r.index < shown)) shown = r.index;
    }
  }
  if (shown < 0) shown = 0;
  Chart top("Top view: the three strategies' paths, run " + std::to_string(shown) + " (paper Fig. 21)", "x_W (m)",
            "y_W (m)", 1280, 640);
  Chart side("Side view: the three strategies' paths, run " + std::to_string(shown), "x_W (m)", "z_W (m)", 1280, 480);
  top.set_equal_aspect(true);
  side.set_equal_aspect(true);
  const int shelves = mission_shelf_count(nominal);
  for (int i = 0; i < shelves; ++i) {
    const ShelfSpec& s = nominal.warehouse.shelves[static_cast<size_t>(i)];
    const Eigen::Isometry3d X_WS = shelf_pose_W(s);
    const int columns = static_cast<int>(s.column_pitch_m.size()), levels = static_cast<int>(s.row_pitch_m.size());
    // Footprint outline (any heading) in the top view; the shelf's end posts in the side view.
    const double y0 = post_y_S_m(s, 0), y1 = post_y_S_m(s, columns);
    std::vector<double> xs, ys;
    for (const auto& c : {Eigen::Vector3d(0, y0, 0), Eigen::Vector3d(s.depth_m, y0, 0), Eigen::Vector3d(s.depth_m, y1, 0),
                          Eigen::Vector3d(0, y1, 0), Eigen::Vector3d(0, y0, 0)}) {
      const Eigen::Vector3d p = X_WS * c;
      xs.push_back(p.x());
      ys.push_back(p.y());
    }
    top.add_line(xs, ys, kShelfBgr, 2, i == 0 ? "shelves" : "");
    const double fx = X_WS.translation().x();
    side.add_rect(fx, 0.0, fx + s.depth_m, beam_z_S_m(s, levels), kShelfBgr, false, i == 0 ? "shelves" : "");
  }
  for (size_t k = 0; k < runs_per_strategy.size() && k < compared_strategies().size(); ++k) {
    for (const RunRecord& r : runs_per_strategy[k]) {
      if (r.index != shown) continue;
      const StoredTrace t = stored_trace(r);
      const std::string label = compared_strategies()[k] + " (" + r.outcome + ")";
      top.add_line(t.x_W_m, t.y_W_m, kColours[k], 2, label);
      side.add_line(t.x_W_m, t.z_W_m, kColours[k], 2, label);
    }
  }
  top.save_png((out_dir / "compare_top_view.png").string());
  side.save_png((out_dir / "compare_side_view.png").string());
  return shown;
}

json run_comparison(const Scenario& nominal, std::int64_t runs, std::uint64_t seed, const std::filesystem::path& out_dir,
                    const CompareOptions& options) {
  std::filesystem::create_directories(out_dir);
  std::vector<StrategyRow> rows;
  std::vector<std::vector<RunRecord>> all_runs;
  bool complete = true;
  for (const std::string& strategy : compared_strategies()) {
    auto scenario = std::make_shared<Scenario>(nominal);
    scenario->cosim.strategy = strategy;
    const std::filesystem::path dir = out_dir / strategy;
    std::filesystem::create_directories(dir);
    const CampaignMeta meta{write_scenario(*scenario), seed, runs};
    ResultsStore store = ResultsStore::open_or_create(dir / "results.sqlite", meta);
    std::shared_ptr<const Scenario> shared = scenario;
    const WorkerFactory factory = options.make_workers
                                      ? options.make_workers(shared)
                                      : WorkerFactory([shared](int) { return std::make_unique<CampaignWorker>(shared); });
    PoolOptions pool;  // fields assigned one by one: the struct may grow (sharding) without touching this
    pool.jobs = options.jobs;
    pool.stop = options.stop;
    if (options.on_progress) {
      pool.on_progress = [&, strategy](const CampaignProgress& p) { options.on_progress(strategy, p); };
    }
    run_pending(store, seed, runs, factory, pool);
    write_campaign_report(dir);
    std::vector<RunRecord> stored = store.runs();
    rows.push_back(summarize_strategy(strategy, stored, runs));
    complete = complete && rows.back().runs == runs;
    all_runs.push_back(std::move(stored));
    if (options.stop && options.stop->load()) {
      complete = false;
      break;
    }
  }
  const std::int64_t shown = write_comparison_plots(nominal, all_runs, out_dir);
  json j{{"scenario", nominal.name}, {"seed", seed}, {"runs", runs}, {"plotted_run", shown}, {"complete", complete}};
  json table = json::array();
  for (const StrategyRow& r : rows) {
    table.push_back({{"strategy", r.strategy},
                     {"runs", r.runs},
                     {"successes", r.successes},
                     {"success_rate", r.success_rate},
                     {"success_lower_95", r.success_lower_95},
                     {"contacts", r.contacts},
                     {"contact_upper_95", r.contact_upper_95},
                     {"safe_aborts", r.safe_aborts},
                     {"inventory_errors", r.inventory_errors},
                     {"mean_distance_m", number_or_null(r.mean_distance_m)},
                     {"mean_time_s", number_or_null(r.mean_time_s)},
                     {"mean_inventory_recall", number_or_null(r.mean_recall)},
                     {"paper_distance_m", r.paper_distance_m},
                     {"paper_time_s", r.paper_time_s}});
  }
  j["rows"] = table;
  RunByRun by_run;  // once two strategies have flown (a stop request can come after the first)
  if (all_runs.size() >= 2) {
    const auto& all = compared_strategies();
    by_run = compare_run_by_run(std::vector<std::string>(all.begin(), all.begin() + static_cast<std::ptrdiff_t>(all_runs.size())),
                                all_runs, runs);
  }
  const auto shift_json = [](const SignedRankResult& r) {
    return json{{"hodges_lehmann", r.hodges_lehmann}, {"interval", {r.interval.lower, r.interval.upper}},
                {"p_two_sided", r.p_two_sided}};
  };
  json against = json::array();
  for (const RunByRun::Against& a : by_run.against) {
    json one{{"strategy", a.strategy}, {"pairs", a.pairs}, {"shorter", a.shorter}, {"faster", a.faster}};
    if (a.pairs > 0) {
      one["time_s"] = shift_json(a.time_s);
      one["distance_m"] = shift_json(a.distance_m);
    }
    against.push_back(one);
  }
  j["run_by_run"] = {{"strategy", by_run.first},          {"runs", by_run.runs},
                     {"shortest", by_run.shortest},        {"fastest", by_run.fastest},
                     {"shortest_lower_95", by_run.shortest_lower_95}, {"fastest_lower_95", by_run.fastest_lower_95},
                     {"against", against},                 {"not_fastest", by_run.not_fastest}};
  std::ofstream(out_dir / "compare.json") << j.dump(2) << "\n";
  std::ofstream md(out_dir / "compare.md");
  md << "# Path strategies compared: " << nominal.name << " (paper Table 2)\n\n"
     << runs << " runs per strategy, campaign seed " << seed
     << ": run k of every strategy has the same seed and the same dispersion draws.\n\n"
     << comparison_table_markdown(rows) << "\n"
     << run_by_run_markdown(by_run) << "\n"
     << "![top view](compare_top_view.png)\n\n![side view](compare_side_view.png)\n\n"
     << "Per-strategy campaign reports: ";
  for (const std::string& s : compared_strategies()) md << "[" << s << "](" << s << "/report.md) ";
  md << "\n";
  return j;
}

}  // namespace shelfcross::verification
