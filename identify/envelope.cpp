#include "identify/envelope.hpp"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <sstream>
#include <stdexcept>

#include <nlohmann/json.hpp>

#include "verification/scenario/dispersion.hpp"
#include "verification/scenario/senses_dispersion.hpp"

namespace shelfcross::identify {
namespace {

// The identified parameters that are scenario parameters, and the dispersion of each.
struct Mapped {
  const char* parameter;      // Identification::parameters name
  const char* dispersion;     // dispersion.hpp name
};
constexpr Mapped kMapped[] = {
    {"rc_gain_scale", "rc_gain_scale"},
    {"velocity_time_constant_s", "velocity_time_constant_s"},
    {"vertical_time_constant_s", "vertical_time_constant_s"},
    {"yaw_time_constant_s", "yaw_time_constant_s"},
    {"vps_noise_mps", "vps_noise_mps"},
    {"height_noise_m", "height_noise_m"},
    {"baro_noise_m", "baro_noise_m"},
    {"tof_noise_m", "tof_noise_m"},
    {"height_hold_range_blend", "height_hold_range_blend"},
    {"height_hold_time_constant_s", "height_hold_time_constant_s"},
};

double nominal_of(const verification::Scenario& s, const std::string& dispersion) {
  const plant::AutopilotParams& ap = s.autopilot;
  if (dispersion == "rc_gain_scale") return 1.0;
  if (dispersion == "velocity_time_constant_s") return ap.velocity_time_constant_s;
  if (dispersion == "vertical_time_constant_s") return ap.vertical_time_constant_s;
  if (dispersion == "yaw_time_constant_s") return ap.yaw_time_constant_s;
  plant::SensesParams senses = s.senses;
  if (const double* field = verification::senses_dispersed_field(senses, dispersion)) return *field;
  throw std::logic_error("no nominal for " + dispersion);
}

Verdict judge(const Interval& iv, double lo, double hi) {
  if (iv.lo >= lo && iv.hi <= hi) return Verdict::inside;
  if (iv.hi < lo || iv.lo > hi) return Verdict::outside;
  return Verdict::straddles;
}

EnvelopeEntry entry(const std::string& name, const Interval& iv, const verification::Scenario& s,
                    const std::string& dispersion) {
  EnvelopeEntry e;
  e.parameter = name;
  e.identified = iv;
  e.identified.replicates.clear();
  const auto it = s.dispersions.find(dispersion);
  e.dispersed = it != s.dispersions.end();
  if (e.dispersed) {
    e.lowest = it->second.lowest();
    e.highest = it->second.highest();
    e.verdict = judge(iv, e.lowest, e.highest);
  } else {
    e.lowest = e.highest = nominal_of(s, dispersion);
    // Not dispersed: the campaign flies the nominal alone; the drone matches it when its
    // interval holds it.
    e.verdict = iv.lo <= e.lowest && e.lowest <= iv.hi ? Verdict::inside : Verdict::outside;
  }
  return e;
}

// A truncated normal centred on the estimate: +-3 standard deviations, inside the parameter's
// allowed range (dispersion.hpp); a zero spread (a noise-free record) gets 1 % of the value.
// The standard deviation holds the bootstrap's and the model-error allowance's, the latter as
// a bias anywhere within +-margin (uniform: margin / sqrt(3)).
verification::Distribution centred(const Interval& iv, double centre, double rel_scale, const std::string& dispersion) {
  verification::Distribution d;
  d.kind = verification::Distribution::Kind::truncated_normal;
  d.mean = centre;
  const double sd = std::hypot(iv.stddev, iv.margin / std::sqrt(3.0));
  d.stddev = std::max(sd * rel_scale, 0.01 * std::abs(centre));
  double lowest = 0.0, highest = 0.0;
  for (const auto& p : verification::dispersion_parameters()) {
    if (dispersion == p.name) {
      lowest = p.lowest;
      highest = p.highest;
    }
  }
  d.min = std::max(lowest, centre - 3.0 * d.stddev);
  d.max = std::min(highest, centre + 3.0 * d.stddev);
  return d;
}

const Interval* find(const Identification& id, const std::string& name) {
  const auto it = id.parameters.find(name);
  return it == id.parameters.end() ? nullptr : &it->second;
}

// The overlay's senses: section, the keys identified (scenarios/README.md, section `senses`).
void write_senses_overlay(std::ostream& o, const Identification& id, const plant::SensesParams& senses) {
  const bool vps = find(id, "vps_noise_mps") != nullptr;
  const bool height = find(id, "height_noise_m") || find(id, "baro_noise_m") || find(id, "tof_noise_m");
  const bool hold = find(id, "height_hold_range_blend") || find(id, "height_hold_time_constant_s");
  if (!vps && !height && !hold) return;
  o << "senses:\n";
  if (vps) o << "  vps:\n    noise_mps: " << senses.vps.noise_mps << "\n";
  if (height) {
    o << "  height:\n";
    if (find(id, "tof_noise_m")) o << "    tof_noise_m: " << senses.height.tof_noise_m << "\n";
    if (find(id, "height_noise_m")) o << "    height_noise_m: " << senses.height.height_noise_m << "\n";
    if (find(id, "baro_noise_m")) o << "    baro_noise_m: " << senses.height.baro_noise_m << "\n";
  }
  if (hold) {
    o << "  height_hold:\n";
    if (find(id, "height_hold_range_blend")) o << "    range_blend: " << senses.height_hold.range_blend << "\n";
    if (find(id, "height_hold_time_constant_s")) o << "    time_constant_s: " << senses.height_hold.time_constant_s << "\n";
  }
}

}  // namespace

const char* verdict_name(Verdict v) {
  switch (v) {
    case Verdict::inside: return "inside";
    case Verdict::straddles: return "straddles";
    case Verdict::outside: return "outside";
  }
  return "?";
}

IdentifyOptions with_scenario(IdentifyOptions o, const verification::Scenario& s) {
  o.autopilot = s.autopilot;
  o.vehicle = s.vehicle;
  return o;
}

std::vector<EnvelopeEntry> check_envelope(const Identification& id, const verification::Scenario& s) {
  std::vector<EnvelopeEntry> out;
  for (const Mapped& m : kMapped) {
    if (std::string(m.parameter) == "rc_gain_scale") {
      // Against this scenario's nominal gains (the identification may have used others).
      if (const auto scale = gain_scale(id, s.autopilot)) out.push_back(entry(m.parameter, *scale, s, m.dispersion));
    } else if (const Interval* iv = find(id, m.parameter)) {
      out.push_back(entry(m.parameter, *iv, s, m.dispersion));
    }
  }
  // Each axis's gain as a scale of the scenario's nominal for that axis.
  const plant::AutopilotParams& ap = s.autopilot;
  for (const AxisResult& a : id.axes) {
    if (!a.identified) continue;
    const double nominal = a.axis == Axis::yaw        ? ap.rc_yaw_radps_at_100
                           : a.axis == Axis::vertical ? ap.rc_vertical_mps_at_100
                                                      : ap.rc_horizontal_mps_at_100;
    Interval scaled = a.id.gain;
    scaled.value /= nominal;
    scaled.lo /= nominal;
    scaled.hi /= nominal;
    scaled.stddev /= nominal;
    scaled.margin /= nominal;
    out.push_back(entry(std::string("rc_gain_scale (") + axis_name(a.axis) + ")", scaled, s, "rc_gain_scale"));
  }
  return out;
}

std::map<std::string, std::pair<double, double>> scenario_ranges(const verification::Scenario& s) {
  std::map<std::string, std::pair<double, double>> out;
  auto range = [&](const std::string& dispersion) {
    const auto it = s.dispersions.find(dispersion);
    if (it == s.dispersions.end()) return std::pair(nominal_of(s, dispersion), nominal_of(s, dispersion));
    return std::pair(it->second.lowest(), it->second.highest());
  };
  for (const Mapped& m : kMapped) out[m.parameter] = range(m.dispersion);
  const auto [lo, hi] = out["rc_gain_scale"];
  const plant::AutopilotParams& ap = s.autopilot;
  out["rc_horizontal_mps_at_100"] = {ap.rc_horizontal_mps_at_100 * lo, ap.rc_horizontal_mps_at_100 * hi};
  out["rc_vertical_mps_at_100"] = {ap.rc_vertical_mps_at_100 * lo, ap.rc_vertical_mps_at_100 * hi};
  out["rc_yaw_radps_at_100"] = {ap.rc_yaw_radps_at_100 * lo, ap.rc_yaw_radps_at_100 * hi};
  return out;
}

verification::Scenario calibrated_scenario(const verification::Scenario& base, const Identification& id) {
  verification::Scenario s = base;
  plant::AutopilotParams& ap = s.autopilot;
  if (const Interval* g = find(id, "rc_horizontal_mps_at_100")) ap.rc_horizontal_mps_at_100 = g->value;
  if (const Interval* g = find(id, "rc_vertical_mps_at_100")) ap.rc_vertical_mps_at_100 = g->value;
  if (const Interval* g = find(id, "rc_yaw_radps_at_100")) ap.rc_yaw_radps_at_100 = g->value;
  if (const Interval* g = find(id, "rc_gain_scale")) {
    // The gains are now the nominals: the scale is 1 with the combined gain's relative spread.
    s.dispersions["rc_gain_scale"] = centred(*g, 1.0, 1.0 / std::max(g->value, 1e-9), "rc_gain_scale");
  }
  const std::pair<const char*, double plant::AutopilotParams::*> taus[] = {
      {"velocity_time_constant_s", &plant::AutopilotParams::velocity_time_constant_s},
      {"vertical_time_constant_s", &plant::AutopilotParams::vertical_time_constant_s},
      {"yaw_time_constant_s", &plant::AutopilotParams::yaw_time_constant_s}};
  for (const auto& [name, member] : taus) {
    if (const Interval* t = find(id, name)) {
      ap.*member = t->value;
      s.dispersions[name] = centred(*t, t->value, 1.0, name);
    }
  }
  // The senses: a noise's interval centred as the autopilot's; the VPS's noise is an upper bound
  // only (senses_fit.hpp), so the campaign draws it anywhere below the bound.
  for (const std::string& name : senses_parameter_names()) {
    const Interval* iv = find(id, name);
    double* field = verification::senses_dispersed_field(s.senses, name);
    if (!iv || !field) continue;
    if (name == "vps_noise_mps") {
      verification::Distribution d;
      d.kind = verification::Distribution::Kind::uniform;
      d.min = 0.0;
      d.max = std::max(iv->hi, 1e-4);
      *field = 0.5 * d.max;
      s.dispersions[name] = d;
      continue;
    }
    *field = std::max(iv->value, 0.0);
    s.dispersions[name] = centred(*iv, *field, 1.0, name);
  }
  s.name = base.name + "_calibrated";
  return s;
}

std::string overlay_yaml(const Identification& id) {
  verification::Scenario blank;
  const verification::Scenario s = calibrated_scenario(blank, id);
  std::ostringstream o;
  o.precision(6);
  o << "# The identified drone (shelfcross identify, " << id.source << "): merge into a scenario's\n"
    << "# autopilot: and dispersions: sections (or use calibrated_scenario.yaml, merged already).\n";
  o << "autopilot:\n";
  if (find(id, "rc_horizontal_mps_at_100")) o << "  rc_horizontal_mps_at_100: " << s.autopilot.rc_horizontal_mps_at_100 << "\n";
  if (find(id, "rc_vertical_mps_at_100")) o << "  rc_vertical_mps_at_100: " << s.autopilot.rc_vertical_mps_at_100 << "\n";
  if (find(id, "rc_yaw_radps_at_100")) o << "  rc_yaw_radps_at_100: " << s.autopilot.rc_yaw_radps_at_100 << "\n";
  if (find(id, "velocity_time_constant_s")) o << "  velocity_time_constant_s: " << s.autopilot.velocity_time_constant_s << "\n";
  if (find(id, "vertical_time_constant_s")) o << "  vertical_time_constant_s: " << s.autopilot.vertical_time_constant_s << "\n";
  if (find(id, "yaw_time_constant_s")) o << "  yaw_time_constant_s: " << s.autopilot.yaw_time_constant_s << "\n";
  write_senses_overlay(o, id, s.senses);
  o << "dispersions:\n";
  for (const auto& [name, d] : s.dispersions) {
    if (d.kind == verification::Distribution::Kind::uniform) {
      o << "  " << name << ": {uniform: {min: " << d.min << ", max: " << d.max << "}}\n";
      continue;
    }
    o << "  " << name << ": {truncated_normal: {mean: " << d.mean << ", stddev: " << d.stddev << ", min: " << d.min
      << ", max: " << d.max << "}}\n";
  }
  return o.str();
}

std::map<std::string, double> emulator_truth(const std::string& path, const verification::Scenario& s) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error("cannot read the emulator report '" + path + "'");
  const nlohmann::json j = nlohmann::json::parse(in, nullptr, false);
  if (j.is_discarded() || !j.is_object() || !j.contains("dispersions") || !j["dispersions"].is_object()) {
    throw std::runtime_error(path + ": not a tello-sim report (no \"dispersions\" object)");
  }
  auto drawn = [&](const char* name, double nominal) {
    const auto& d = j["dispersions"];
    if (!d.contains(name)) return nominal;
    const auto& v = d[name];
    if (!v.is_object() || !v.contains("value") || !v["value"].is_number()) {
      throw std::runtime_error(path + ": dispersion '" + std::string(name) + "' has no numeric value");
    }
    return v["value"].get<double>();
  };
  const plant::AutopilotParams& ap = s.autopilot;
  const double scale = drawn("rc_gain_scale", 1.0);
  std::map<std::string, double> truth = {
      {"rc_gain_scale", scale},
      {"rc_horizontal_mps_at_100", ap.rc_horizontal_mps_at_100 * scale},
      {"rc_vertical_mps_at_100", ap.rc_vertical_mps_at_100 * scale},
      {"rc_yaw_radps_at_100", ap.rc_yaw_radps_at_100 * scale},
      {"velocity_time_constant_s", drawn("velocity_time_constant_s", ap.velocity_time_constant_s)},
      {"vertical_time_constant_s", drawn("vertical_time_constant_s", ap.vertical_time_constant_s)},
      {"yaw_time_constant_s", drawn("yaw_time_constant_s", ap.yaw_time_constant_s)}};
  for (const std::string& name : senses_parameter_names()) truth[name] = drawn(name.c_str(), nominal_of(s, name));
  return truth;
}

}  // namespace shelfcross::identify
