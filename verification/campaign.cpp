#include "verification/campaign.hpp"

#include <chrono>
#include <cmath>
#include <map>

#include "verification/run_hash.hpp"
#include "verification/statistics.hpp"

namespace shelfcross::verification {

render::RenderOptions render_options_for(const Scenario& s) {
  render::RenderOptions o;
  o.noise_stddev = s.cosim.render_noise_stddev;
  o.motion_blur_samples = s.cosim.motion_blur_samples;
  return o;
}

CampaignWorker::CampaignWorker(std::shared_ptr<const Scenario> nominal)
    : nominal_(std::move(nominal)),
      renderer_(std::make_unique<render::Renderer>(nominal_->warehouse, nominal_->camera,
                                                   render_options_for(*nominal_))) {}

RunRecord CampaignWorker::run(std::int64_t index, std::uint64_t seed) {
  const auto t0 = std::chrono::steady_clock::now();  // informative wall time only
  const RunSetup setup = disperse(*nominal_, seed);
  renderer_->set_warehouse(setup.scenario->warehouse);
  const RunResult result = run_cosimulation(setup, *renderer_);
  const double wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return make_run_record(index, setup, result, wall_s);
}

RunRecord make_run_record(std::int64_t index, const RunSetup& setup, const RunResult& result, double wall_s) {
  RunRecord r;
  r.index = index;
  r.seed = setup.seed;
  r.dispersion_json = nlohmann::json(setup.drawn).dump();
  r.outcome = outcome_name(result.outcome);
  nlohmann::json metrics = nlohmann::json::parse(run_metrics_json(result.metrics));
  metrics["detail"] = result.detail;
  r.metrics_json = metrics.dump();
  r.run_hash = result.run_hash;
  r.wall_s = wall_s;
  r.trace_json = trace_json(result);
  return r;
}

std::string trace_json(const RunResult& result) {
  const auto rounded = [](double v, double unit) { return std::round(v / unit) * unit; };
  nlohmann::json t = nlohmann::json::array(), x = t, y = t, z = t, yaw = t;
  // The trajectory is sampled at cosim.trajectory_rate_hz; keep about 10 Hz.
  double next_s = 0.0;
  for (const TrajectorySample& s : result.trajectory) {
    if (s.t_s + 1e-9 < next_s) continue;
    next_s = s.t_s + 0.1;
    t.push_back(rounded(s.t_s, 1e-3));
    x.push_back(rounded(s.p_WB_m.x(), 1e-3));
    y.push_back(rounded(s.p_WB_m.y(), 1e-3));
    z.push_back(rounded(s.p_WB_m.z(), 1e-3));
    yaw.push_back(rounded(s.yaw_rad, 1e-4));
  }
  nlohmann::json j{{"t", t}, {"x", x}, {"y", y}, {"z", z}, {"yaw", yaw}};
  j["approach_start_s"] = result.approach_start_s ? nlohmann::json(*result.approach_start_s) : nlohmann::json(nullptr);
  j["cross_start_s"] = result.cross_start_s ? nlohmann::json(*result.cross_start_s) : nlohmann::json(nullptr);
  return j.dump();
}

nlohmann::json summarize_campaign(const std::vector<RunRecord>& runs, std::int64_t runs_requested) {
  using nlohmann::json;
  std::int64_t count = 0, successes = 0;
  std::map<std::string, std::int64_t> outcomes;
  std::map<std::string, std::vector<double>> values;
  std::vector<std::string> hashes;
  const auto collect = [&](const std::string& name, const json& v) {
    if (v.is_number()) values[name].push_back(v.get<double>());
  };
  for (const RunRecord& r : runs) {
    if (r.index >= runs_requested) continue;
    ++count;
    successes += r.outcome == "success";
    ++outcomes[r.outcome];
    hashes.push_back(r.run_hash);
    const json m = json::parse(r.metrics_json);
    collect("mission_time_s", m.value("mission_time_s", json()));
    collect("path_length_m", m.value("path_length_m", json()));
    collect("min_clearance_m", m.value("min_clearance_m", json()));
    const auto abs_of = [](const json& v) { return v.is_number() ? json(std::abs(v.get<double>())) : json(); };
    collect("entry_offset_y_abs_m", abs_of(m.value("entry_offset_y_m", json())));
    collect("entry_offset_z_abs_m", abs_of(m.value("entry_offset_z_m", json())));
    for (const char* axis : {"altitude", "heading", "lateral"}) {
      const json a = m.value(axis, json());
      if (!a.is_object()) continue;
      collect(std::string(axis) + "_settling_time_s", a.value("settling_time_s", json()));
      collect(std::string(axis) + "_overshoot", a.value("overshoot", json()));
      collect(std::string(axis) + "_overshoot_abs", a.value("overshoot_abs", json()));
    }
    if (m.contains("inventory")) {
      collect("inventory_precision", m["inventory"].value("precision", json()));
      collect("inventory_recall", m["inventory"].value("recall", json()));
    }
    // What the link did (sdk: datagrams; ideal: whole frames and commands).
    if (const json l = m.value("link", json()); l.is_object()) {
      for (const char* key : {"video_datagrams", "video_datagrams_lost", "frames_decoded", "frames_damaged",
                              "commands_sent", "commands_lost", "replies_lost", "state_records_lost",
                              "command_retries"}) {
        collect(std::string("link_") + key, l.value(key, json()));
      }
      const double datagrams = l.value("video_datagrams", 0.0);
      if (datagrams > 0) collect("link_video_datagram_loss", l.value("video_datagrams_lost", 0.0) / datagrams);
      const double handed = l.value("frames_handed", 0.0);
      if (handed > 0) collect("link_damaged_frame_fraction", l.value("frames_damaged", 0.0) / handed);
    }
  }
  json summary;
  summary["runs"] = count;
  summary["runs_requested"] = runs_requested;
  summary["successes"] = successes;
  summary["success_rate"] = count ? static_cast<double>(successes) / static_cast<double>(count) : 0.0;
  summary["success_lower_95"] = count ? clopper_pearson_lower(successes, count, 0.95) : 0.0;
  summary["outcomes"] = outcomes;
  json stats = json::object();
  for (const auto& [name, v] : values) {
    const Summary s = summarize(v);
    stats[name] = {{"count", s.count}, {"mean", s.mean}, {"min", s.min}, {"p50", s.p50},
                   {"p95", s.p95},     {"p99", s.p99},   {"max", s.max}};
  }
  summary["metrics"] = stats;
  summary["campaign_hash"] = count == runs_requested ? combine_run_hashes(hashes) : std::string();
  return summary;
}

}  // namespace shelfcross::verification
