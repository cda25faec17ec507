#include "verification/report/compare.hpp"

#include <cmath>
#include <fstream>
#include <iomanip>
#include <sstream>

#include "config/strict_json.hpp"
#include "verification/campaign/campaign.hpp"
#include "verification/campaign/stored_run.hpp"
#include "verification/cosim/cosim.hpp"
#include "verification/cosim/run_metrics_json.hpp"
#include "verification/report/report.hpp"
#include "verification/statistics/plot.hpp"
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
const cv::Scalar kShelf(120, 80, 40);

std::string fixed(double v, int decimals) {
  std::ostringstream s;
  s << std::fixed << std::setprecision(decimals) << v;
  return s.str();
}

std::vector<double> numbers(const json& a) {
  std::vector<double> v;
  for (const json& x : a) v.push_back(x.is_number() ? x.get<double>() : NAN);
  return v;
}

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
  const auto opt = [](const std::optional<double>& v, int decimals) { return v ? fixed(*v, decimals) : std::string("-"); };
  for (const StrategyRow& r : rows) {
    md << "| " << paper_row(r.strategy).label << " | " << r.runs << " | " << opt(r.mean_distance_m, 2) << " | "
       << fixed(r.paper_distance_m, 0) << " | " << opt(r.mean_time_s, 1) << " | " << fixed(r.paper_time_s, 0) << " | "
       << r.successes << "/" << r.runs << " = " << fixed(r.success_rate, 3) << " | " << fixed(r.success_lower_95, 3)
       << " | " << r.contacts << " | " << fixed(r.contact_upper_95, 4) << " | " << r.safe_aborts << " | "
       << r.inventory_errors << " | " << opt(r.mean_recall, 4) << " |\n";
  }
  md << "\nMean distance and time over the successful runs (a failed run ends early); recall over every run. "
        "Lower bound: one-sided Clopper-Pearson at 95 %. Safety apart from success: contacts (a shelf or a "
        "wall touched) with their one-sided 95 % Clopper-Pearson upper bound, safe aborts (gave up, landed "
        "without contact), inventory errors. Paper: docs/method.md section 6, Table 2.\n";
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
    top.add_line(xs, ys, kShelf, 2, i == 0 ? "shelves" : "");
    const double fx = X_WS.translation().x();
    side.add_rect(fx, 0.0, fx + s.depth_m, beam_z_S_m(s, levels), kShelf, false, i == 0 ? "shelves" : "");
  }
  for (size_t k = 0; k < runs_per_strategy.size() && k < compared_strategies().size(); ++k) {
    for (const RunRecord& r : runs_per_strategy[k]) {
      if (r.index != shown) continue;
      const json t = json::parse(r.trace_json);
      const std::string label = compared_strategies()[k] + " (" + r.outcome + ")";
      top.add_line(numbers(t.at("x")), numbers(t.at("y")), kColours[k], 2, label);
      side.add_line(numbers(t.at("x")), numbers(t.at("z")), kColours[k], 2, label);
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
  std::ofstream(out_dir / "compare.json") << j.dump(2) << "\n";
  std::ofstream md(out_dir / "compare.md");
  md << "# Path strategies compared: " << nominal.name << " (paper Table 2)\n\n"
     << runs << " runs per strategy, campaign seed " << seed
     << ": run k of every strategy has the same seed and the same dispersion draws.\n\n"
     << comparison_table_markdown(rows) << "\n"
     << "![top view](compare_top_view.png)\n\n![side view](compare_side_view.png)\n\n"
     << "Per-strategy campaign reports: ";
  for (const std::string& s : compared_strategies()) md << "[" << s << "](" << s << "/report.md) ";
  md << "\n";
  return j;
}

}  // namespace shelfcross::verification
