#include "verification/report/report.hpp"

#include <cmath>
#include <fstream>
#include <iomanip>
#include <map>
#include <optional>
#include <sstream>

#include "shelfcross/rotation.hpp"
#include "verification/campaign/campaign.hpp"
#include "verification/campaign/results_store.hpp"
#include "verification/campaign/stored_run.hpp"
#include "verification/cosim/run_metrics_json.hpp"
#include "verification/plot/plot.hpp"
#include "verification/report/crossing_push.hpp"
#include "verification/report/link_report.hpp"
#include "verification/scenario/dispersion.hpp"
#include "verification/scenario/scenario.hpp"
#include "verification/statistics/statistics.hpp"
#include "verification/statistics/success_bins.hpp"

namespace shelfcross::verification {
namespace {

using nlohmann::json;

const cv::Scalar kGood(60, 160, 60), kBad(40, 40, 220), kCell(230, 200, 150);

/// Latency in the loop: when the campaign disperses the video latency, the success rate
/// against each run's total latency from capture to command (its link's mean video latency
/// plus the flight software's compute latency, both as drawn for that run: its stored draws applied
/// to the scenario), in 50 ms bins: a markdown section and latency_sweep.png.
/// Empty when the video latency is not dispersed.
std::string latency_sweep_section(const Scenario& scenario, const std::vector<RunRecord>& runs,
                                  const std::filesystem::path& dir) {
  if (!scenario.dispersions.count("video_latency_mean_s") || runs.empty()) return "";
  constexpr double kBin_s = 0.05;
  SuccessBins bins(kBin_s);
  for (const RunRecord& r : runs) {
    const DrawnValues drawn = stored_draws(r);
    if (drawn.empty()) continue;  // a worker_error record: its draws were never stored
    const RunSetup setup = disperse(scenario, r.seed, drawn);
    const LinkSettings& l = setup.scenario->cosim.link;
    bins.add(l.video_latency_mean_s + l.compute_latency_s, r.outcome == "success");
  }
  std::ostringstream md;
  md << "## Success rate against latency\n\nTotal latency = the run's mean video latency + the flight software's "
        "compute latency (as drawn), in "
     << kBin_s * 1e3 << " ms bins.\n\n| total latency (ms) | runs | successes | success rate | 95 % lower bound |\n"
        "|---|---|---|---|---|\n"
     << bins.table_rows(1e3, 0);
  std::vector<double> centre_ms, rate;
  std::optional<double> last_90_ms, first_below_50_ms;
  bool all_90 = true;  // every bin so far at 90 % or more
  for (const SuccessBins::Bin& b : bins.bins()) {
    const double lo = b.lo * 1e3, hi = b.hi * 1e3, p = b.rate();
    centre_ms.push_back(0.5 * (lo + hi));
    rate.push_back(p);
    all_90 = all_90 && p >= 0.9;
    if (all_90) last_90_ms = hi;
    if (p < 0.5 && !first_below_50_ms) first_below_50_ms = lo;
  }
  md << "\n";
  if (last_90_ms) md << "Success rate at least 90 % in every bin up to " << fixed_text(*last_90_ms, 0) << " ms. ";
  if (first_below_50_ms) {
    md << "It falls below 50 % from " << fixed_text(*first_below_50_ms, 0) << " ms on.\n\n";
  } else {
    md << "It never falls below 50 % in the swept range.\n\n";
  }
  Chart chart("Success rate against total latency (video link + compute)", "total latency (ms)", "success rate");
  chart.set_y_limits(0.0, 1.05);
  chart.add_line(centre_ms, rate, kGood, 2);
  chart.add_points(centre_ms, rate, kGood, 4);
  chart.add_hline(0.9, cv::Scalar(120, 120, 120), "90 %");
  chart.add_hline(0.5, kBad, "50 %");
  chart.save_png((dir / "latency_sweep.png").string());
  md << "![success rate against latency](latency_sweep.png)\n\n";
  return md.str();
}

}  // namespace

std::string safety_section(const SafetySummary& s, const NearMissSummary& n) {
  const auto percent = [](double v, int decimals) { return fixed_text(100.0 * v, decimals) + " %"; };
  std::ostringstream md;
  md << "## Safety apart from mission success\n\n"
     << "| | runs | rate | one-sided 95 % bound (Clopper-Pearson) |\n|---|---|---|---|\n"
     << "| contacts (shelf or wall) | " << s.contacts << " of " << s.runs << " | "
     << percent(s.contact_rate, 2) << " | below " << percent(s.contact_upper_95, 2) << " |\n"
     << "| of which with a shelf | " << s.shelf_contacts << " | | |\n"
     << "| safe aborts (gave up, landed without contact) | " << s.safe_aborts << " | "
     << percent(s.runs ? static_cast<double>(s.safe_aborts) / static_cast<double>(s.runs) : 0.0, 2) << " | |\n"
     << "| inventory errors (flown safely, wrong inventory) | " << s.inventory_errors << " | | |\n"
     << "| other failures (timeout, software fault) | " << s.other_failures << " | | |\n"
     << "| near misses (no contact, least clearance below " << fixed_text(100.0 * n.near_miss_m, 1) << " cm) | " << n.runs
     << " (" << n.successes << " succeeded) | " << percent(n.rate, 2) << " | |\n\n"
     << "A contact is the safety failure; an abort is only a lost mission. The contact bound is the "
        "largest contact probability consistent with these runs at 95 % confidence. A near miss is "
        "counted apart from both: a run that touched nothing but passed closer to a shelf than "
        "cosim.near_miss_m, whether or not its mission succeeded.\n\n";
  return md.str();
}

std::string cost_section(const CostSummary& c, std::int64_t runs) {
  std::ostringstream md;
  md << "## Cost\n\n";
  if (c.cpu_s_per_run.count == 0) {
    md << "CPU time not recorded: no run has a figure (runs stored by a version before it was, or lost runs "
          "only).\n\n";
    return md.str();
  }
  const Summary& s = c.cpu_s_per_run;
  const auto or_none = [](const std::optional<double>& v, int decimals) { return v ? fixed_text(*v, decimals) : "-"; };
  md << "| | |\n|---|---|\n"
     << "| runs with a CPU figure | " << s.count << " of " << runs << " |\n"
     << "| CPU seconds per run: mean, p50, p95, max | " << fixed_text(s.mean, 2) << ", " << fixed_text(s.p50, 2) << ", "
     << fixed_text(s.p95, 2) << ", " << fixed_text(s.max, 2) << " |\n"
     << "| CPU seconds per simulated second | " << or_none(c.cpu_s_per_simulated_s, 3) << " |\n"
     << "| runs per core-hour | " << (s.mean > 0.0 ? fixed_text(3600.0 / s.mean, 0) : std::string("-")) << " |\n\n"
     << "CPU time (user + system) each run took in its worker process (with in-process worker threads: its "
        "thread's); it depends on the machine and its load. Runs lost with their worker (crashed, hung) or "
        "failed in it have no figure.\n\n";
  return md.str();
}

namespace {

/// What the report says of the runs besides its charts: the failed runs' table rows.
struct RunsDrawn {
  int failures = 0;
  std::ostringstream failed_rows;
  int near_misses = 0;
  std::ostringstream near_miss_rows;
};

/// Every run's trajectory over the shelves (top and side views), its approach responses, and
/// the distributions of settling times and entry offsets, saved as PNGs in `dir`.
RunsDrawn draw_runs(const std::filesystem::path& dir, const Scenario& scenario, const std::vector<RunRecord>& runs) {
  // The approach responses are measured on the first shelf (the metrics' target is its cell).
  const ShelfSpec& shelf = scenario.warehouse.shelves.at(0);
  const Eigen::Isometry3d X_WS = shelf_pose_W(shelf);

  Chart top("Top view of every run (green: success, red: failure)", "x_W (m)", "y_W (m)");
  Chart side("Side view of every run", "x_W (m)", "z_W (m)");
  Chart altitude("Altitude error during the approach (paper Fig. 26)", "time from approach start (s)", "z - z_cell (m)");
  Chart heading("Heading error during the approach (paper Fig. 27)", "time from approach start (s)", "yaw - yaw_shelf (deg)");
  Chart lateral("Lateral error during the approach (paper Fig. 28)", "time from approach start (s)", "y_S - y_cell (m)");
  top.set_equal_aspect(true);
  side.set_equal_aspect(true);
  // Every shelf: posts from above, beams and faces from the side (each axis-aligned with W
  // when its yaw is 0, as in the shipped scenarios).
  for (const ShelfSpec& sh : scenario.warehouse.shelves) {
    const Eigen::Isometry3d X = shelf_pose_W(sh);
    const double x_face = X.translation().x();
    const int columns = static_cast<int>(sh.column_pitch_m.size());
    const int levels = static_cast<int>(sh.row_pitch_m.size());
    for (int i = 0; i <= columns; ++i) {
      const Eigen::Vector3d a = X * Eigen::Vector3d(0, post_y_S_m(sh, i), 0);
      top.add_rect(a.x() - 0.01, a.y() - 0.01, a.x() + sh.depth_m + 0.01, a.y() + 0.01, kShelfBgr, true);
    }
    for (int j = 0; j <= levels; ++j) {
      const double z = beam_z_S_m(sh, j);
      side.add_rect(x_face - 0.01, z - 0.01, x_face + sh.depth_m + 0.01, z + 0.01, kShelfBgr, true);
    }
    side.add_rect(x_face - 0.01, 0.0, x_face + 0.01, beam_z_S_m(sh, levels), kShelfBgr, true);
    side.add_rect(x_face + sh.depth_m - 0.01, 0.0, x_face + sh.depth_m + 0.01, beam_z_S_m(sh, levels), kShelfBgr, true);
  }

  std::vector<double> settle_z, settle_yaw, offset_y, offset_z;
  RunsDrawn drawn;
  for (const RunRecord& r : runs) {
    const StoredTrace trace = stored_trace(r);
    const StoredMetrics stored = stored_metrics(r);
    const bool ok = r.outcome == "success";
    const cv::Scalar colour = ok ? kGood : kBad;
    if (!trace.t_s.empty()) {
      const std::vector<double>&t = trace.t_s, &x = trace.x_W_m, &y = trace.y_W_m, &z = trace.z_W_m, &yaw = trace.yaw_rad;
      top.add_line(x, y, colour);
      side.add_line(x, z, colour);
      std::optional<CellIndex> target;
      if (stored.run) target = stored.run->target;
      if (trace.approach_start_s && target) {
        const double t0 = *trace.approach_start_s;
        const double t1 = trace.cross_start_s.value_or(t.back());
        const Eigen::Vector3d c = cell_centre_S_m(shelf, target->level, target->column);
        std::vector<double> tt, ez, eyaw, ey;
        for (size_t i = 0; i < t.size(); ++i) {
          if (t[i] < t0 || t[i] > t1) continue;
          const Eigen::Vector3d p_S = X_WS.inverse() * Eigen::Vector3d(x[i], y[i], z[i]);
          tt.push_back(t[i] - t0);
          ez.push_back(p_S.z() - c.z());
          ey.push_back(p_S.y() - c.y());
          eyaw.push_back(rad_to_deg(wrap_pi(yaw[i] - shelf.yaw_rad)));
        }
        altitude.add_line(tt, ez, colour);
        heading.add_line(tt, eyaw, colour);
        lateral.add_line(tt, ey, colour);
      }
    }
    if (stored.run) {
      const RunMetrics& m = *stored.run;
      settle_z.push_back(m.altitude && m.altitude->settling_time_s ? *m.altitude->settling_time_s : NAN);
      settle_yaw.push_back(m.heading && m.heading->settling_time_s ? *m.heading->settling_time_s : NAN);
      if (m.truth.entry_offset_y_m) offset_y.push_back(*m.truth.entry_offset_y_m);
      if (m.truth.entry_offset_z_m) offset_z.push_back(*m.truth.entry_offset_z_m);
    }
    if (is_near_miss(r.outcome, stored.run, scenario.cosim.near_miss_m)) {
      ++drawn.near_misses;
      drawn.near_miss_rows << "| " << r.index << " | " << r.outcome << " | "
                           << fixed_text(100.0 * *stored.run->truth.min_clearance_m, 1) << " | `shelfcross replay "
                           << dir.string() << " --run " << r.index << "` |\n";
    }
    if (!ok) {
      ++drawn.failures;
      drawn.failed_rows << "| " << r.index << " | " << r.outcome << " | " << stored.detail << " | `shelfcross replay "
             << dir.string() << " --run " << r.index << "` |\n";
    }
  }
  top.save_png((dir / "top_view.png").string());
  side.save_png((dir / "side_view.png").string());
  altitude.add_hline(0.0, cv::Scalar(0, 0, 0));
  heading.add_hline(0.0, cv::Scalar(0, 0, 0));
  lateral.add_hline(0.0, cv::Scalar(0, 0, 0));
  altitude.save_png((dir / "altitude_response.png").string());
  heading.save_png((dir / "heading_response.png").string());
  lateral.save_png((dir / "lateral_response.png").string());
  histogram_chart(settle_z, 20, "Altitude settling time", "s").save_png((dir / "settling_altitude.png").string());
  histogram_chart(settle_yaw, 20, "Heading settling time", "s").save_png((dir / "settling_heading.png").string());
  histogram_chart(offset_y, 20, "Entry offset from the cell centre, lateral", "m").save_png((dir / "entry_offset_y.png").string());
  histogram_chart(offset_z, 20, "Entry offset from the cell centre, vertical", "m").save_png((dir / "entry_offset_z.png").string());
  return drawn;
}

/// The crossings' pushes against their room (crossing_push.hpp), by column width: a markdown
/// section and crossing_push.png. Empty when no run crossed a cell of shelf 0.
std::string crossing_push_section(const Scenario& scenario, const std::vector<RunRecord>& runs,
                                  const std::filesystem::path& dir) {
  struct Column {
    double room_m = 0.0;
    std::vector<double> push_m;
    double largest_m = -1.0;
    std::int64_t largest_run = -1;
  };
  std::map<long, Column> by_width;  // column pitch in mm
  std::vector<double> all_m;
  for (const RunRecord& r : runs) {
    const StoredMetrics stored = stored_metrics(r);
    const std::optional<double> push = crossing_push_m(scenario, stored, stored_trace(r));
    if (!push) continue;
    const int column = stored.run->truth.crossed->column;
    const double pitch_m = scenario.warehouse.shelves.front().column_pitch_m[static_cast<std::size_t>(column - 1)];
    Column& c = by_width[std::lround(1000.0 * pitch_m)];
    c.room_m = crossing_room_m(scenario, column);
    c.push_m.push_back(*push);
    if (*push > c.largest_m) {
      c.largest_m = *push;
      c.largest_run = r.index;
    }
    all_m.push_back(*push);
  }
  if (all_m.empty()) return "";
  std::ostringstream md;
  md << "## Crossing push\n\nThe largest distance across the cell of the vehicle from the crossed cell's centre line "
        "while any part of it is within the shelf's depth (shelf 0, from the stored 10 Hz trace), against the room "
        "before its side touches a post (half the column's pitch - half a post - half the vehicle's width).\n\n"
        "| column pitch | room | crossings | mean push | p95 | p99 | largest | its run | least room left |\n"
        "|---|---|---|---|---|---|---|---|---|\n";
  for (const auto& [width_mm, c] : by_width) {
    const Summary p = summarize(c.push_m);
    md << "| " << width_mm / 10.0 << " cm | " << fixed_text(100.0 * c.room_m, 1) << " cm | " << p.count << " | "
       << fixed_text(100.0 * p.mean, 1) << " cm | " << fixed_text(100.0 * p.p95, 1) << " cm | " << fixed_text(100.0 * p.p99, 1)
       << " cm | " << fixed_text(100.0 * c.largest_m, 1) << " cm | " << c.largest_run << " | "
       << fixed_text(100.0 * (c.room_m - c.largest_m), 1) << " cm |\n";
  }
  histogram_chart(all_m, 20, "Crossing push from the cell's centre line", "m").save_png((dir / "crossing_push.png").string());
  md << "\n![crossing push](crossing_push.png)\n\n";
  return md.str();
}

}  // namespace

CampaignSummary write_campaign_report(const std::filesystem::path& dir) {
  ResultsStore store = ResultsStore::open_existing(dir / "results.sqlite");
  const Scenario scenario = parse_scenario(store.meta().scenario_yaml, (dir / "results.sqlite").string() + " (scenario)");
  const std::vector<RunRecord> runs = store.runs();
  const CampaignSummary summary = summarize_campaign(runs, store.meta().runs_requested, scenario.cosim.near_miss_m);
  std::ofstream(dir / "summary.json") << json(summary).dump(2) << "\n";

  const RunsDrawn drawn = draw_runs(dir, scenario, runs);

  std::ofstream md(dir / "report.md");
  md << "# Crossing campaign: " << scenario.name << "\n\n";
  md << "Campaign seed " << store.meta().campaign_seed << ", " << summary.runs << " of " << store.meta().runs_requested
     << " runs stored. "
     << (summary.campaign_hash.empty() ? std::string("Campaign hash: once every run is stored.")
                                       : "Campaign hash `" + summary.campaign_hash + "`.")
     << "\n\n";
  md << "| | |\n|---|---|\n";
  md << "| successes | " << summary.successes << " |\n";
  md << "| success rate | " << fixed_text(summary.success_rate, 4) << " |\n";
  md << "| one-sided 95 % lower bound (Clopper-Pearson) | " << fixed_text(summary.success_lower_95, 4) << " |\n\n";
  md << safety_section(summary.safety, summary.near_misses);
  md << "## Outcomes\n\n| outcome | runs |\n|---|---|\n";
  for (const auto& [name, n] : summary.outcomes) md << "| " << name << " | " << n << " |\n";
  md << "\n## Metrics\n\n| metric | runs | mean | p50 | p95 | p99 | max |\n|---|---|---|---|---|---|---|\n";
  for (const auto& [name, s] : summary.metrics) {
    md << "| " << name << " | " << s.count << " | " << fixed_text(s.mean, 3) << " | " << fixed_text(s.p50, 3) << " | "
       << fixed_text(s.p95, 3) << " | " << fixed_text(s.p99, 3) << " | " << fixed_text(s.max, 3) << " |\n";
  }
  md << "\nSettling: from the start of the approach until the error stays inside max(" << scenario.cosim.settling_fraction * 100
     << " % of its initial value, " << scenario.cosim.settling_floor_z_m * 100 << " cm / "
     << fixed_text(rad_to_deg(scenario.cosim.settling_floor_yaw_rad), 2) << " deg) for good.\n\n";
  md << cost_section(summary.cost, summary.runs);
  md << "## Trajectories\n\n![top view](top_view.png)\n\n![side view](side_view.png)\n\n";
  md << "## Approach responses" << (scenario.warehouse.shelves.size() > 1 ? " (first shelf)" : "")
     << "\n\n![altitude](altitude_response.png)\n\n![heading](heading_response.png)\n\n"
        "![lateral](lateral_response.png)\n\n";
  md << "## Distributions\n\n![altitude settling](settling_altitude.png)\n\n![heading settling](settling_heading.png)\n\n"
        "![lateral entry offset](entry_offset_y.png)\n\n![vertical entry offset](entry_offset_z.png)\n\n";
  md << crossing_push_section(scenario, runs, dir);
  md << latency_sweep_section(scenario, runs, dir);
  md << link_section(runs, dir);
  md << "## Failed runs (" << drawn.failures << ")\n\n";
  if (drawn.failures) {
    md << "| run | outcome | detail | replay |\n|---|---|---|---|\n" << drawn.failed_rows.str();
  } else {
    md << "None.\n";
  }
  md << "\n## Near misses (" << drawn.near_misses << ")\n\n";
  if (drawn.near_misses) {
    md << "| run | outcome | least clearance (cm) | replay |\n|---|---|---|---|\n" << drawn.near_miss_rows.str();
  } else {
    md << "None closer than " << fixed_text(100.0 * scenario.cosim.near_miss_m, 1) << " cm.\n";
  }
  return summary;
}

}  // namespace shelfcross::verification
