#include "verification/report/diff_report.hpp"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <iomanip>
#include <optional>
#include <sstream>
#include <utility>

#include "config/strict_json.hpp"
#include "verification/plot/plot.hpp"
#include "verification/statistics/statistics.hpp"

namespace shelfcross::verification {

using config::number_or_null;
namespace {

using nlohmann::json;

const cv::Scalar kPoint(180, 110, 40), kDiagonal(120, 120, 120);

/// The metrics drawn as histograms of their paired differences.
const char* const kHistogramMetrics[] = {"min_clearance_m",      "crossing_push_m",          "mission_time_s",
                                         "entry_offset_y_abs_m", "entry_offset_z_abs_m", "altitude_settling_time_s",
                                         "cpu_s"};

constexpr const char* kIntervalMethod = "Newcombe's hybrid score interval for paired proportions (method 10)";

/// A p-value as read: 4 significant digits, "< 1e-12" in the far tail.
std::string p_text(double p) {
  if (p < 1e-12) return "< 1e-12";
  std::ostringstream s;
  s << std::setprecision(4) << p;
  return s.str();
}

std::string percent(double v, int decimals) { return fixed_text(100.0 * v, decimals) + " %"; }

std::string signed_percent(double v, int decimals) {
  std::string text(v > 0.0 ? "+" : "");
  text += percent(v, decimals);
  return text;
}

const MetricComparison* find_metric(const PairedDiff& diff, const std::string& name) {
  for (const MetricComparison& m : diff.metrics) {
    if (m.name == name) return &m;
  }
  return nullptr;
}

json side_json(const DiffSide& s) {
  return {{"path", s.db_path.string()},
          {"scenario", s.scenario.name},
          {"campaign_seed", s.meta.campaign_seed},
          {"runs_stored", s.runs.size()},
          {"runs_requested", s.meta.runs_requested}};
}

json interval_json(const Interval& i) { return json::array({i.lower, i.upper}); }

/// Mission success in success terms: the failure table read the other way round.
json success_json(const EventComparison& f) {
  const PairedTable& t = f.table;
  return {{"both_succeed", t.neither},
          {"base_only_succeeds", t.new_only},
          {"new_only_succeeds", t.base_only},
          {"both_fail", t.both},
          {"base_rate", 1.0 - f.base_rate},
          {"new_rate", 1.0 - f.new_rate},
          {"difference", f.base_rate - f.new_rate},
          {"difference_interval", json::array({-f.difference.upper, -f.difference.lower})},
          {"interval_method", kIntervalMethod},
          {"discordant", f.mcnemar.discordant},
          {"p_new_worse", f.mcnemar.p_new_worse},
          {"p_two_sided", f.mcnemar.p_two_sided}};
}

json contact_json(const EventComparison& c) {
  const PairedTable& t = c.table;
  return {{"both", t.both},
          {"base_only", t.base_only},
          {"new_only", t.new_only},
          {"neither", t.neither},
          {"base_rate", c.base_rate},
          {"new_rate", c.new_rate},
          {"difference", c.new_rate - c.base_rate},
          {"difference_interval", interval_json(c.difference)},
          {"interval_method", kIntervalMethod},
          {"discordant", c.mcnemar.discordant},
          {"p_new_worse", c.mcnemar.p_new_worse},
          {"p_two_sided", c.mcnemar.p_two_sided}};
}

/// One side's least or largest value of a metric (MetricComparison::base_each or new_each) and
/// its run; nothing when that side has the metric in no pair.
std::optional<std::pair<std::int64_t, double>> extreme(const std::vector<std::pair<std::int64_t, double>>& each,
                                                       bool least) {
  if (each.empty()) return std::nullopt;
  const auto by_value = [](const auto& a, const auto& b) { return a.second < b.second; };
  return least ? *std::min_element(each.begin(), each.end(), by_value)
               : *std::max_element(each.begin(), each.end(), by_value);
}

json extreme_json(const std::vector<std::pair<std::int64_t, double>>& each, bool least) {
  const auto e = extreme(each, least);
  return e ? json{{"run", e->first}, {"value", e->second}} : json(nullptr);
}

json metric_json(const MetricComparison& m) {
  json j{{"pairs", m.pairs}, {"tolerance", m.tolerance}, {"moved_up", m.moved_up}, {"moved_down", m.moved_down},
         {"base_runs_with_it", m.base_each.size()}, {"new_runs_with_it", m.new_each.size()},
         {"base_min", extreme_json(m.base_each, true)}, {"base_max", extreme_json(m.base_each, false)},
         {"new_min", extreme_json(m.new_each, true)}, {"new_max", extreme_json(m.new_each, false)}};
  if (m.pairs > 0) {
    j["median_difference"] = m.paired.median;
    j["hodges_lehmann"] = m.paired.hodges_lehmann;
    j["interval"] = interval_json(m.paired.interval);
    j["nonzero_differences"] = m.paired.nonzero;
    j["p_two_sided"] = m.paired.p_two_sided;
  }
  return j;
}

json draws_json(const DrawnValues& d) {
  json j = json::object();
  for (const auto& [name, value] : d) j[name] = value;
  return j;
}

}  // namespace

std::string replay_command(const DiffSide& side, std::int64_t run) {
  return "shelfcross replay " + side.dir.string() + " --run " + std::to_string(run) + " --video";
}

json diff_json(const PairedDiff& diff, const DiffReportOptions& options) {
  json flips = json::array();
  for (const Flip& f : diff.flips) {
    flips.push_back({{"base_run", f.base_run},
                     {"new_run", f.new_run},
                     {"seed", f.seed},
                     {"base_outcome", f.base_outcome},
                     {"new_outcome", f.new_outcome},
                     {"base_detail", f.base_detail},
                     {"new_detail", f.new_detail},
                     {"success_changed", f.success_changed},
                     {"contact_changed", f.contact_changed},
                     {"near_miss_changed", f.near_miss_changed},
                     {"new_near_miss", f.new_near_miss},
                     {"base_draws", draws_json(f.base_draws)},
                     {"new_draws", draws_json(f.new_draws)},
                     {"replay", {replay_command(diff.base, f.base_run), replay_command(diff.next, f.new_run)}}});
  }
  json metrics = json::object();
  for (const MetricComparison& m : diff.metrics) metrics[m.name] = metric_json(m);
  json scenario = json::array();
  for (const ScenarioDifference& s : diff.scenario_differences) {
    scenario.push_back({{"key", s.key}, {"base", s.base}, {"new", s.next}});
  }
  json draws = json::array();
  for (const DrawDifference& d : diff.draw_differences) {
    draws.push_back({{"name", d.name},
                     {"pairs", d.pairs},
                     {"first_base_run", d.first_base_run},
                     {"first_new_run", d.first_new_run},
                     {"first_base", number_or_null(d.first_base)},
                     {"first_new", number_or_null(d.first_new)}});
  }
  json gate = nullptr;
  if (options.fail_if_worse_alpha) {
    gate = {{"alpha", *options.fail_if_worse_alpha}, {"new_worse", new_is_worse(diff, *options.fail_if_worse_alpha)}};
  }
  return {{"base", side_json(diff.base)},
          {"new", side_json(diff.next)},
          {"paired_by", diff.paired_by_seed ? "run_seed" : "run_index"},
          {"confidence", diff.confidence},
          {"pairs", diff.pairs},
          {"identical_runs", diff.identical},
          {"mission_success", success_json(diff.failures)},
          {"contacts", contact_json(diff.contacts)},
          {"near_misses", contact_json(diff.near_misses)},
          {"near_miss_m", {{"base", diff.base.scenario.cosim.near_miss_m}, {"new", diff.next.scenario.cosim.near_miss_m}}},
          {"metrics", metrics},
          {"flips", flips},
          {"scenario_differences", scenario},
          {"draw_differences", draws},
          {"pairs_with_other_draws", diff.pairs_with_other_draws},
          {"gate", gate}};
}

namespace {

std::string side_line(const char* label, const DiffSide& s) {
  std::ostringstream md;
  md << "| " << label << " | `" << s.db_path.string() << "` | " << s.scenario.name << " | " << s.meta.campaign_seed
     << " | " << s.runs.size() << " of " << s.meta.runs_requested << " |\n";
  return md.str();
}

std::string header_section(const PairedDiff& d) {
  std::ostringstream md;
  md << "# Paired comparison: " << d.base.scenario.name
     << (d.next.scenario.name != d.base.scenario.name ? " against " + d.next.scenario.name : std::string()) << "\n\n"
     << "| | results | scenario | campaign seed | runs stored |\n|---|---|---|---|---|\n"
     << side_line("BASE", d.base) << side_line("NEW", d.next) << "\n"
     << "**" << d.pairs << " runs paired** "
     << (d.paired_by_seed ? "by run seed (`--allow-different-scenarios`)"
                          : "by run index: the same campaign seed, scenario and draws")
     << ". ";
  const auto n_base = static_cast<std::int64_t>(d.base.runs.size()), n_new = static_cast<std::int64_t>(d.next.runs.size());
  if (n_base != d.pairs || n_new != d.pairs || d.base.meta.runs_requested != d.next.meta.runs_requested) {
    md << "Only the runs stored on both sides are compared: " << n_base - d.pairs << " of BASE's and "
       << n_new - d.pairs << " of NEW's stored runs have no partner (a campaign still running, stopped, or of "
       << "another size). ";
  }
  md << "\n\n";
  return md.str();
}

std::string verdict_section(const PairedDiff& d, const DiffReportOptions& o) {
  const EventComparison &f = d.failures, &c = d.contacts;
  std::ostringstream md;
  md << "## Verdict\n\n";
  md << "- **" << d.identical << " of " << d.pairs << " runs identical** (the same run hash on both sides)"
     << (d.identical == d.pairs ? ": NEW changes nothing on these runs." : ".") << "\n";
  md << "- **Mission success**: BASE " << d.pairs - f.table.both - f.table.base_only << " of " << d.pairs << ", NEW "
     << d.pairs - f.table.both - f.table.new_only << " of " << d.pairs << "; " << f.table.new_only
     << " runs lost in NEW, " << f.table.base_only << " gained; difference NEW - BASE "
     << signed_percent(f.base_rate - f.new_rate, 2) << " (" << fixed_text(100.0 * d.confidence, 0) << " % interval "
     << signed_percent(-f.difference.upper, 2) << " to " << signed_percent(-f.difference.lower, 2)
     << "); exact McNemar: one-sided p (NEW worse) = " << p_text(f.mcnemar.p_new_worse)
     << ", two-sided p = " << p_text(f.mcnemar.p_two_sided) << ".\n";
  md << "- **Contacts** (shelf or wall): BASE " << c.table.both + c.table.base_only << ", NEW "
     << c.table.both + c.table.new_only << "; " << c.table.new_only << " new in NEW, " << c.table.base_only
     << " gone; difference " << signed_percent(c.new_rate - c.base_rate, 2) << " (interval "
     << signed_percent(c.difference.lower, 2) << " to " << signed_percent(c.difference.upper, 2)
     << "); one-sided p (NEW worse) = " << p_text(c.mcnemar.p_new_worse) << ", two-sided p = "
     << p_text(c.mcnemar.p_two_sided) << ".\n";
  const EventComparison& n = d.near_misses;
  md << "- **Near misses** (no contact, least clearance below " << fixed_text(100.0 * d.base.scenario.cosim.near_miss_m, 1)
     << " cm in BASE, " << fixed_text(100.0 * d.next.scenario.cosim.near_miss_m, 1) << " cm in NEW): BASE "
     << n.table.both + n.table.base_only << ", NEW " << n.table.both + n.table.new_only << "; " << n.table.new_only
     << " new in NEW, " << n.table.base_only << " gone; one-sided p (NEW worse) = " << p_text(n.mcnemar.p_new_worse)
     << ", two-sided p = " << p_text(n.mcnemar.p_two_sided) << " (reported, not gated).\n";
  if (o.fail_if_worse_alpha) {
    const double a = *o.fail_if_worse_alpha;
    md << "- **Gate** (`--fail-if-worse " << a << "`): "
       << (new_is_worse(d, a) ? "FAILED: NEW is worse than BASE at this level"
                              : "passed: NEW is not shown worse at this level")
       << ".\n";
  }
  md << "\n";
  return md.str();
}

std::string table_section(const PairedDiff& d) {
  const PairedTable &f = d.failures.table, &c = d.contacts.table, &n = d.near_misses.table;
  std::ostringstream md;
  md << "## Outcomes, paired\n\n"
     << "| mission success | NEW succeeds | NEW fails |\n|---|---|---|\n"
     << "| BASE succeeds | " << f.neither << " | " << f.new_only << " |\n"
     << "| BASE fails | " << f.base_only << " | " << f.both << " |\n\n"
     << "| contacts | NEW: contact | NEW: none |\n|---|---|---|\n"
     << "| BASE: contact | " << c.both << " | " << c.base_only << " |\n"
     << "| BASE: none | " << c.new_only << " | " << c.neither << " |\n\n"
     << "| near misses | NEW: near miss | NEW: none |\n|---|---|---|\n"
     << "| BASE: near miss | " << n.both << " | " << n.base_only << " |\n"
     << "| BASE: none | " << n.new_only << " | " << n.neither << " |\n\n"
     << "Only the discordant pairs (one side one way, the other the other) carry information about a "
        "difference. The exact McNemar test takes them as " << d.failures.mcnemar.discordant << " (mission) and "
     << d.contacts.mcnemar.discordant
     << " (contacts) fair coin tosses under \"no difference\": the one-sided p-value is the chance of at least "
        "as many going NEW's way as did, the two-sided one twice the smaller tail. The interval for the "
        "difference in rates is "
     << kIntervalMethod << ", at " << fixed_text(100.0 * d.confidence, 0) << " %.\n\n";
  return md.str();
}

std::string value_text(double v) {
  std::ostringstream s;
  s << std::setprecision(4) << v;
  return s.str();
}

/// The margins' tails: each side's least clearance and largest push, with its run. A campaign is
/// only as safe as its closest call, which a shift of the median does not show.
std::string closest_calls_section(const PairedDiff& d) {
  std::ostringstream md;
  md << "## Closest calls\n\nEach side over every pair where it has the metric (a run that crossed on one side "
        "only counts on that side).\n\n| | BASE | its run | NEW | its run |\n|---|---|---|---|---|\n";
  const auto side = [&md](const std::vector<std::pair<std::int64_t, double>>& each, bool least) {
    const auto e = extreme(each, least);
    if (e) {
      md << " | " << fixed_text(100.0 * e->second, 1) << " cm | " << e->first;
    } else {
      md << " | none | ";
    }
  };
  const auto row = [&](const char* label, const char* name, bool least) {
    const MetricComparison* m = find_metric(d, name);
    if (!m) return;
    md << "| " << label;
    side(m->base_each, least);
    side(m->new_each, least);
    md << " |\n";
  };
  row("least clearance to the shelf", "min_clearance_m", true);
  row("largest crossing push", "crossing_push_m", false);
  md << "\n";
  return md.str();
}

std::string metrics_section(const PairedDiff& d) {
  std::ostringstream md;
  md << "## Metrics, paired (NEW - BASE)\n\n"
     << "| metric | pairs | differences not 0 | median difference | Hodges-Lehmann shift | "
     << fixed_text(100.0 * d.confidence, 0)
     << " % interval | Wilcoxon p (two-sided) | tolerance | NEW higher | NEW lower |\n"
        "|---|---|---|---|---|---|---|---|---|---|\n";
  for (const MetricComparison& m : d.metrics) {
    if (m.pairs == 0) {
      md << "| " << m.name << " | 0 | | | | | | | | |\n";
      continue;
    }
    const SignedRankResult& r = m.paired;
    md << "| " << m.name << " | " << m.pairs << " | " << r.nonzero << " | " << value_text(r.median) << " | "
       << value_text(r.hodges_lehmann) << " | " << value_text(r.interval.lower) << " to "
       << value_text(r.interval.upper) << " | " << p_text(r.p_two_sided) << " | " << value_text(m.tolerance)
       << " | " << m.moved_up << " | " << m.moved_down << " |\n";
  }
  md << "\nOver the pairs where both runs have the metric (a run that did not cross has no clearance). "
        "The shift is the Hodges-Lehmann estimate (the median of the Walsh "
        "averages of the differences, zeros included) with its distribution-free interval; the Wilcoxon "
        "signed-rank test drops the zeros (exact for up to 50 untied differences, else normal with the tie "
        "correction). NEW higher / lower: runs that moved by more than the tolerance (from the unit: 5 mm, 0.1 s, "
        "0.5 CPU s, 0.01 for fractions, any change of a count). crossing_push_m: the largest distance across the "
        "cell of the vehicle from the crossed cell's centre line while it is within the shelf's depth, from the "
        "stored 10 Hz trace (crossing_push.hpp). CPU seconds depend on the machine and its load when each campaign "
        "ran.\n\n";
  md << closest_calls_section(d);
  return md.str();
}

std::string draws_text(const DrawnValues& draws) {
  std::ostringstream s;
  bool first = true;
  for (const auto& [name, value] : draws) {
    s << (first ? "" : ", ") << name << " " << value_text(value);
    first = false;
  }
  return first ? std::string("(none stored)") : s.str();
}

std::string flips_section(const PairedDiff& d) {
  std::ostringstream md;
  md << "## Flipped runs (" << d.flips.size() << ")\n\n";
  if (d.flips.empty()) {
    md << "None: every paired run has the same outcome and near-miss class on both sides.\n\n";
    return md.str();
  }
  md << "| BASE run | NEW run | BASE outcome | NEW outcome | mission | contact | near miss |\n"
        "|---|---|---|---|---|---|---|\n";
  for (const Flip& f : d.flips) {
    const bool new_ok = f.new_outcome == "success";
    md << "| " << f.base_run << " | " << f.new_run << " | " << f.base_outcome
       << (f.base_detail.empty() ? "" : " (" + f.base_detail + ")") << " | " << f.new_outcome
       << (f.new_detail.empty() ? "" : " (" + f.new_detail + ")") << " | "
       << (f.success_changed ? (new_ok ? "gained" : "**lost**") : "") << " | "
       << (f.contact_changed ? (classify_outcome(f.new_outcome) == RunSafetyClass::contact ? "**new contact**" : "contact gone")
                             : "")
       << " | " << (f.near_miss_changed ? (f.new_near_miss ? "**new near miss**" : "near miss gone") : "") << " |\n";
  }
  md << "\n";
  for (const Flip& f : d.flips) {
    md << "### Run " << f.base_run << (f.new_run != f.base_run ? " / " + std::to_string(f.new_run) : std::string())
       << ": " << f.base_outcome << " -> " << f.new_outcome << "\n\nSeed " << f.seed << ". Draws: "
       << draws_text(f.base_draws) << ".";
    if (f.new_draws != f.base_draws) md << " NEW's draws: " << draws_text(f.new_draws) << ".";
    md << "\n\n    " << replay_command(d.base, f.base_run) << "    # BASE\n    " << replay_command(d.next, f.new_run)
       << "    # NEW\n\n";
  }
  return md.str();
}

std::string differences_section(const PairedDiff& d) {
  std::ostringstream md;
  if (!d.scenario_differences.empty()) {
    md << "## Scenario keys that differ (" << d.scenario_differences.size() << ")\n\n| key | BASE | NEW |\n|---|---|---|\n";
    for (const ScenarioDifference& s : d.scenario_differences) {
      md << "| " << s.key << " | " << s.base << " | " << s.next << " |\n";
    }
    md << "\n";
  }
  if (d.paired_by_seed) {
    md << "## Draws that differ\n\n";
    if (d.draw_differences.empty()) {
      md << "None: every pair has the same draws.\n\n";
    } else {
      md << d.pairs_with_other_draws << " of " << d.pairs << " pairs have other draws.\n\n"
         << "| draw | pairs | first pair (BASE run / NEW run) | BASE | NEW |\n|---|---|---|---|---|\n";
      const auto show = [](const std::optional<double>& v) { return v ? value_text(*v) : std::string("not drawn"); };
      for (const DrawDifference& x : d.draw_differences) {
        md << "| " << x.name << " | " << x.pairs << " | " << x.first_base_run << " / " << x.first_new_run << " | "
           << show(x.first_base) << " | " << show(x.first_new) << " |\n";
      }
      md << "\n";
    }
  }
  return md.str();
}

/// The plots; returns the markdown that shows them.
std::string write_plots(const PairedDiff& d, const std::filesystem::path& dir) {
  std::ostringstream md;
  md << "## Plots\n\n";
  if (const MetricComparison* m = find_metric(d, "min_clearance_m"); m && m->pairs > 0) {
    Chart chart("Least clearance to the shelf per run: BASE against NEW", "BASE (cm)", "NEW (cm)");
    std::vector<double> x, y;
    for (std::size_t i = 0; i < m->base.size(); ++i) {
      x.push_back(100.0 * m->base[i]);
      y.push_back(100.0 * m->next[i]);
    }
    const double lo = std::min(*std::min_element(x.begin(), x.end()), *std::min_element(y.begin(), y.end()));
    const double hi = std::max(*std::max_element(x.begin(), x.end()), *std::max_element(y.begin(), y.end()));
    const double pad = std::max(0.5, 0.05 * (hi - lo));
    chart.set_x_limits(lo - pad, hi + pad);
    chart.set_y_limits(lo - pad, hi + pad);
    chart.set_equal_aspect(true);
    chart.add_line({lo - pad, hi + pad}, {lo - pad, hi + pad}, kDiagonal, 1, "NEW = BASE");
    chart.add_points(x, y, kPoint, 3, "one run (both crossed)");
    chart.save_png((dir / "clearance_base_vs_new.png").string());
    md << "Least clearance in each run that crossed on both sides; below the diagonal NEW passed closer.\n\n"
          "![clearance BASE against NEW](clearance_base_vs_new.png)\n\n";
  }
  for (const char* name : kHistogramMetrics) {
    const MetricComparison* m = find_metric(d, name);
    if (!m || m->pairs == 0) continue;
    std::vector<double> diff(m->base.size());
    for (std::size_t i = 0; i < diff.size(); ++i) diff[i] = m->next[i] - m->base[i];
    const std::string file = std::string("difference_") + name + ".png";
    histogram_chart(diff, 30, std::string("Paired difference NEW - BASE: ") + name, name)
        .save_png((dir / file).string());
    md << "![" << name << " NEW - BASE](" << file << ")\n\n";
  }
  return md.str();
}

}  // namespace

json write_diff_report(const PairedDiff& diff, const std::filesystem::path& out_dir, const DiffReportOptions& options) {
  std::filesystem::create_directories(out_dir);
  const json j = diff_json(diff, options);
  std::ofstream(out_dir / "diff.json") << j.dump(2) << "\n";
  std::ofstream md(out_dir / "diff.md");
  md << header_section(diff) << verdict_section(diff, options) << table_section(diff) << flips_section(diff)
     << metrics_section(diff) << differences_section(diff) << write_plots(diff, out_dir);
  if (!md) throw std::runtime_error("cannot write " + (out_dir / "diff.md").string());
  return j;
}

}  // namespace shelfcross::verification
