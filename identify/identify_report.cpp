#include "identify/identify_report.hpp"

#include <cmath>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <limits>
#include <sstream>

#include <nlohmann/json.hpp>

#include "verification/plot/plot.hpp"

namespace shelfcross::identify {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

const cv::Scalar kMeasured(200, 90, 30), kModel(30, 30, 220), kInput(120, 120, 120);

std::string num(double v, int digits = 3) {
  std::ostringstream s;
  s << std::setprecision(digits) << std::fixed << v;
  return s.str();
}

std::string interval_text(const Interval& iv, int digits = 3) {
  return num(iv.value, digits) + " [" + num(iv.lo, digits) + ", " + num(iv.hi, digits) + "]";
}

json interval_json(const Interval& iv) {
  return {{"value", iv.value}, {"lo", iv.lo}, {"hi", iv.hi}, {"stddev", iv.stddev}, {"model_allowance", iv.margin}};
}

const char* observed_as(Axis a) {
  switch (a) {
    case Axis::forward: return "vgx (heading-frame forward velocity, m/s)";
    case Axis::lateral: return "vgy (heading-frame left velocity, m/s)";
    case Axis::vertical: return "h (height above take-off, m): integral of the vertical velocity";
    case Axis::yaw: return "yaw (unwrapped heading, rad): integral of the yaw rate";
  }
  return "?";
}

// Breaks a series at its segment changes (NaN between segments).
void with_breaks(const std::vector<double>& t, const std::vector<int>& segment, const std::vector<double>& v,
                 std::vector<double>& xs, std::vector<double>& ys) {
  for (size_t k = 0; k < v.size(); ++k) {
    if (k > 0 && segment[k] != segment[k - 1]) {
      xs.push_back(std::numeric_limits<double>::quiet_NaN());
      ys.push_back(std::numeric_limits<double>::quiet_NaN());
    }
    xs.push_back(t[k]);
    ys.push_back(v[k]);
  }
}

void write_axis_plots(const AxisResult& a, const std::string& dir) {
  const AxisRecord& r = a.record;
  const std::string name = axis_name(a.axis);
  verification::Chart fit(name + ": measured state records (points) and the identified model (line)",
                          "time since the takeoff's ok (s)", observed_as(a.axis));
  fit.add_points(r.t_s, r.y, kMeasured, 3, "measured");
  std::vector<double> xs, ys;
  with_breaks(r.t_s, r.segment, a.id.fit.fitted, xs, ys);
  fit.add_line(xs, ys, kModel, 2, "model");
  if (r.observation == Observation::direct) {
    // The commanded velocity K u(t - d), stepped: the response's target.
    std::vector<double> ix, iy;
    double last = 0.0;
    for (size_t i = 0; i < r.input.t_s.size(); ++i) {
      const double t = r.input.t_s[i] + a.id.fit.delay_s;
      if (t < r.t_s.front() - 1.0 || t > r.t_s.back() + 1.0) {
        last = r.input.u[i] * a.id.fit.gain;
        continue;
      }
      ix.insert(ix.end(), {t, t});
      iy.insert(iy.end(), {last, r.input.u[i] * a.id.fit.gain});
      last = iy.back();
    }
    if (!ix.empty()) fit.add_line(ix, iy, kInput, 1, "K u(t - d)");
  }
  fit.save_png((fs::path(dir) / ("fit_" + name + ".png")).string());
  std::vector<double> res(r.y.size());
  for (size_t k = 0; k < res.size(); ++k) res[k] = r.y[k] - a.id.fit.fitted[k];
  verification::Chart residuals(name + ": residuals (measured - model)", "time since the takeoff's ok (s)", "residual");
  residuals.add_hline(0.0, kInput);
  residuals.add_points(r.t_s, res, kMeasured, 3, "residual");
  residuals.save_png((fs::path(dir) / ("residuals_" + name + ".png")).string());
}

void write_parameters_md(std::ostream& o, const ReportInputs& in) {
  const Identification& id = *in.identification;
  o << "## Parameters\n\n95 % intervals: " << id.options.bootstrap_replicates << " bootstrap refits (seed "
    << id.options.seed << "): height and heading by a moving-block residual bootstrap (blocks of " << id.options.block_s
    << " s), the velocities by a parametric one (their rounded readings drawn again with the residuals' correlation); "
    << "each widened by the model-error allowance (gains " << 100 * kAllowanceVelocityGain << " % for the velocities, "
    << 100 * kAllowanceIntegralGain << " % for height and heading, time constants " << 100 * kAllowanceTimeConstant
    << " %, the heading's at least " << kAllowanceYawTimeConstant_s << " s, root sum of squares with the bootstrap's half-width; docs/calibration.md).\n\n";
  o << "| parameter | identified [95 % interval] |" << (in.truth.empty() ? "" : " true | within |") << "\n";
  o << "|---|---|" << (in.truth.empty() ? "" : "---|---|") << "\n";
  for (const auto& [name, iv] : id.parameters) {
    o << "| " << name << " | " << interval_text(iv) << " |";
    if (!in.truth.empty()) {
      const auto t = in.truth.find(name);
      if (t == in.truth.end()) {
        o << " - | - |";
      } else {
        o << " " << num(t->second) << " | " << (t->second >= iv.lo && t->second <= iv.hi ? "yes" : "**no**") << " |";
      }
    }
    o << "\n";
  }
  o << "\n";
}

void write_axes_md(std::ostream& o, const Identification& id) {
  o << "## Axes\n\nModel per axis: tau x' = K u(t - d) - x, u = stick / 100 held from each rc datagram's send "
       "time (response_fit.hpp).\n\n";
  o << "| axis | observed | windows | records | K (at full stick) | tau (s) | d (s) | residual rms |\n";
  o << "|---|---|---|---|---|---|---|---|\n";
  for (const AxisResult& a : id.axes) {
    if (!a.identified) {
      o << "| " << axis_name(a.axis) << " | not identified: " << a.why_not << " | | | | | | |\n";
      continue;
    }
    o << "| " << axis_name(a.axis) << " | " << observed_as(a.axis) << " | " << a.windows << " | " << a.record.y.size()
      << " | " << interval_text(a.id.gain) << " " << axis_gain_unit(a.axis) << " | " << interval_text(a.id.tau_s)
      << " | " << interval_text(a.id.delay_s) << " | " << num(a.id.fit.rms, 4)
      << (a.id.fit.at_bound ? " (on a search bound)" : "") << " |\n";
  }
  o << "\n";
  for (const AxisResult& a : id.axes) {
    if (!a.identified) continue;
    o << "![" << axis_name(a.axis) << " fit](fit_" << axis_name(a.axis) << ".png)\n![" << axis_name(a.axis)
      << " residuals](residuals_" << axis_name(a.axis) << ".png)\n\n";
  }
}

void write_envelope_md(std::ostream& o, const ReportInputs& in) {
  o << "## Against the scenario " << in.scenario_path << "\n\n";
  o << "| parameter | identified [95 %] | scenario draws | verdict |\n|---|---|---|---|\n";
  for (const EnvelopeEntry& e : in.envelope) {
    o << "| " << e.parameter << " | " << interval_text(e.identified) << " | "
      << (e.dispersed ? num(e.lowest) + " to " + num(e.highest) : "fixed at " + num(e.lowest)) << " | "
      << (e.verdict == Verdict::inside ? "inside" : std::string("**") + verdict_name(e.verdict) + "**") << " |\n";
  }
  const std::vector<std::string> out = outside_parameters(in.envelope);
  o << "\n";
  if (out.empty()) {
    o << "No parameter lies outside the scenario's draws.\n\n";
  } else {
    o << "**Outside the scenario's draws:**";
    for (const std::string& p : out) o << " " << p;
    o << ". The campaign does not fly this drone there: use calibrated_scenario.yaml, or widen those ranges.\n\n";
  }
}

void write_senses_md(std::ostream& o, const SensesIdentification& s) {
  o << "## The Tello's senses\n\nFrom the senses block (tello_pilot --fly-calibration --senses-board): the still hover's "
       "readings and the height hold's answer to the board (identify/senses_fit.hpp, docs/calibration.md). ";
  if (s.still_found) {
    o << "Still hover: " << num(s.still_from_s, 1) << " to " << num(s.still_to_s, 1) << " s after the takeoff's ok, "
      << s.still_records << " state records. ";
  }
  if (s.board_height_m) o << "Board: " << num(*s.board_height_m) << " m high. ";
  o << "\n\n| parameter | identified [95 %] | from |\n|---|---|---|\n";
  for (const std::string& name : senses_parameter_names()) {
    const auto it = s.parameters.find(name);
    if (it == s.parameters.end()) continue;
    o << "| " << name << " | " << interval_text(it->second, 4) << " | " << s.how.at(name) << " |\n";
  }
  o << "\n";
  for (const auto& [name, why] : s.not_identified) o << "- " << name << ": " << why << "\n";
  if (!s.board.edges_s.empty()) {
    o << "\nThe board's edges: " << s.board.edges_s.size() << " (the range reading fell by";
    for (double d : s.board.steps_m) o << " " << num(d);
    o << " m); the fit's residual rms " << num(s.board.rms_m, 4) << " m.\n\n![board pass](board_pass.png)\n";
  }
  o << "\n";
}

void write_board_plot(const BoardPassFit& b, const std::string& dir) {
  verification::Chart c("height hold over the board: h - tof - H u and the fit",
                        "time since the takeoff's ok (s)", "m");
  c.add_points(b.t_s, b.y_m, kMeasured, 3, "measured");
  std::vector<double> xs, ys;
  with_breaks(b.t_s, b.window, b.fitted_m, xs, ys);
  c.add_line(xs, ys, kModel, 2, "model");
  c.save_png((fs::path(dir) / "board_pass.png").string());
}

json senses_json(const SensesIdentification& s) {
  json j = {{"still_found", s.still_found}, {"still_from_s", s.still_from_s}, {"still_to_s", s.still_to_s},
            {"still_records", s.still_records}, {"not_identified", s.not_identified}, {"how", s.how},
            {"board_height_m", s.board_height_m ? json(*s.board_height_m) : json(nullptr)},
            {"board_edges_s", s.board.edges_s}, {"board_steps_m", s.board.steps_m}, {"board_rms_m", s.board.rms_m}};
  return j;
}

void write_link_md(std::ostream& o, const LinkFigures& l) {
  o << "## The link, from the log's stamps\n\n";
  o << "| figure | value |\n|---|---|\n";
  o << "| state records (dropped as unparseable) | " << l.state_records << " (" << l.bad_states << ") |\n";
  o << "| state period p50 / p95 / longest gap (s) | " << num(l.state_period_p50_s) << " / " << num(l.state_period_p95_s)
    << " / " << num(l.state_gap_max_s) << " |\n";
  o << "| state records held up: fitted 10 ms or more before they were read (state_send_times) / the most | " << l.held_up_states
    << " / " << num(l.held_up_max_s) << " s |\n";
  o << "| frames (damaged) | " << l.frames << " (" << l.damaged_frames << ") |\n";
  o << "| frame period p50 / p95 (s) | " << num(l.frame_period_p50_s, 4) << " / " << num(l.frame_period_p95_s, 4) << " |\n";
  o << "| last datagram -> decoded p50 / p95 (s) | " << num(l.rx_to_handed_p50_s, 4) << " / "
    << num(l.rx_to_handed_p95_s, 4) << " |\n";
  o << "| decoded -> taken by the loop p50 / p95 (s) | " << num(l.handed_to_taken_p50_s, 4) << " / "
    << num(l.handed_to_taken_p95_s, 4) << " |\n\n";
  o << "The response delay (response_delay_s above) is the whole command-to-state dead time. The video's "
       "latency from capture to its last datagram is not in the log: a Tello stamps neither its frames nor its "
       "state records, so no stamp tells when a picture was taken.\n\n";
}

json report_json(const ReportInputs& in) {
  const Identification& id = *in.identification;
  json j = {{"source", id.source}, {"flight_s", id.flight_s}};
  json params = json::object();
  for (const auto& [name, iv] : id.parameters) {
    json p = interval_json(iv);
    if (const auto t = in.truth.find(name); t != in.truth.end()) {
      p["truth"] = t->second;
      p["within"] = t->second >= iv.lo && t->second <= iv.hi;
    }
    params[name] = p;
  }
  if (in.scenario) {
    for (const auto& [name, r] : scenario_ranges(*in.scenario)) {
      if (params.contains(name)) params[name]["scenario_range"] = {r.first, r.second};
    }
  }
  j["parameters"] = params;
  json axes = json::object();
  for (const AxisResult& a : id.axes) {
    json x = {{"identified", a.identified}, {"windows", a.windows}, {"records", a.record.y.size()}};
    if (!a.identified) x["why_not"] = a.why_not;
    if (a.identified) {
      x["gain"] = interval_json(a.id.gain);
      x["tau_s"] = interval_json(a.id.tau_s);
      x["delay_s"] = interval_json(a.id.delay_s);
      x["rms"] = a.id.fit.rms;
      x["at_bound"] = a.id.fit.at_bound;
    }
    axes[axis_name(a.axis)] = x;
  }
  j["axes"] = axes;
  j["senses"] = senses_json(id.senses);
  json env = json::array();
  for (const EnvelopeEntry& e : in.envelope) {
    env.push_back({{"parameter", e.parameter}, {"identified", interval_json(e.identified)}, {"dispersed", e.dispersed},
                   {"lowest", e.lowest}, {"highest", e.highest}, {"verdict", verdict_name(e.verdict)}});
  }
  j["envelope"] = env;
  j["outside"] = outside_parameters(in.envelope);
  const LinkFigures& l = id.link;
  j["link"] = {{"state_records", l.state_records}, {"bad_states", l.bad_states}, {"state_period_p50_s", l.state_period_p50_s},
               {"state_period_p95_s", l.state_period_p95_s}, {"state_gap_max_s", l.state_gap_max_s},
               {"held_up_states", l.held_up_states}, {"held_up_max_s", l.held_up_max_s},
               {"frames", l.frames}, {"damaged_frames", l.damaged_frames}, {"frame_period_p50_s", l.frame_period_p50_s},
               {"rx_to_handed_p50_s", l.rx_to_handed_p50_s}, {"rx_to_handed_p95_s", l.rx_to_handed_p95_s},
               {"handed_to_taken_p50_s", l.handed_to_taken_p50_s}, {"handed_to_taken_p95_s", l.handed_to_taken_p95_s}};
  j["bootstrap"] = {{"replicates", id.options.bootstrap_replicates}, {"block_s", id.options.block_s}, {"seed", id.options.seed}};
  return j;
}

void write_text(const fs::path& path, const std::string& text) {
  std::ofstream f(path, std::ios::trunc);
  f << text;
  if (!f) throw std::runtime_error("cannot write '" + path.string() + "'");
}

}  // namespace

std::vector<std::string> outside_parameters(const std::vector<EnvelopeEntry>& envelope) {
  std::vector<std::string> out;
  for (const EnvelopeEntry& e : envelope) {
    if (e.verdict == Verdict::outside) out.push_back(e.parameter);
  }
  return out;
}

void write_identify_report(const ReportInputs& in, const std::string& dir) {
  const Identification& id = *in.identification;
  fs::create_directories(dir);
  for (const AxisResult& a : id.axes) {
    if (a.identified) write_axis_plots(a, dir);
  }
  if (!id.senses.board.t_s.empty()) write_board_plot(id.senses.board, dir);
  std::ostringstream md;
  md << "# Identification of " << id.source << "\n\n";
  md << "The simulated Tello's autopilot parameters (plant/autopilot.hpp) from " << num(id.flight_s, 1)
     << " s of flight (takeoff's ok to the first land).";
  if (!in.truth_source.empty()) md << " True values: " << in.truth_source << ".";
  md << "\n\n";
  write_parameters_md(md, in);
  write_axes_md(md, id);
  write_senses_md(md, id.senses);
  if (in.scenario) write_envelope_md(md, in);
  write_link_md(md, id.link);
  md << "## Files\n\noverlay.yaml: the autopilot and dispersion entries of this drone; calibrated_scenario.yaml: "
     << (in.scenario ? in.scenario_path : std::string("the default scenario"))
     << " with them applied (`shelfcross campaign --scenario calibrated_scenario.yaml`).\n";
  write_text(fs::path(dir) / "identify.md", md.str());
  write_text(fs::path(dir) / "identify.json", report_json(in).dump(2) + "\n");
  write_text(fs::path(dir) / "overlay.yaml", overlay_yaml(id));
  if (in.scenario) {
    write_text(fs::path(dir) / "calibrated_scenario.yaml", verification::write_scenario(calibrated_scenario(*in.scenario, id)));
  }
}

}  // namespace shelfcross::identify
