#include "verification/campaign/campaign.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <ctime>
#include <map>
#include <stdexcept>
#include <utility>

#include "config/strict_json.hpp"
#include "verification/campaign/stored_run.hpp"
#include "verification/cosim/run_hash.hpp"
#include "verification/cosim/run_metrics_json.hpp"
#include "verification/statistics/statistics.hpp"

namespace shelfcross::verification {

using config::StrictObject;
using config::number_or_null;

CampaignWorker::CampaignWorker(std::shared_ptr<const Scenario> nominal, DrawFunction draw, CpuClock cpu_clock)
    : nominal_(std::move(nominal)),
      draw_(std::move(draw)),
      cpu_clock_(cpu_clock),
      renderer_(std::make_unique<render::Renderer>(nominal_->warehouse, nominal_->camera,
                                                   render_options_for(*nominal_))) {}

RunRecord CampaignWorker::run(std::int64_t index, std::uint64_t seed) {
  return run_setup(index, draw_ ? disperse(*nominal_, seed, draw_(seed)) : disperse(*nominal_, seed));
}

RunRecord CampaignWorker::run_drawn(std::int64_t index, std::uint64_t seed, const DrawnValues& drawn) {
  return run_setup(index, disperse(*nominal_, seed, drawn));
}

namespace {
// CPU seconds (user + system) of the calling thread or of the whole process since some fixed
// point: their difference across a run is its RunRecord::cpu_s.
double cpu_clock_s(CpuClock which) {
  timespec t{};
  const clockid_t clock = which == CpuClock::thread ? CLOCK_THREAD_CPUTIME_ID : CLOCK_PROCESS_CPUTIME_ID;
  if (::clock_gettime(clock, &t) != 0) throw std::runtime_error("clock_gettime: no CPU-time clock");
  return static_cast<double>(t.tv_sec) + 1e-9 * static_cast<double>(t.tv_nsec);
}
}  // namespace

RunRecord CampaignWorker::run_setup(std::int64_t index, const RunSetup& setup) {
  const auto t0 = std::chrono::steady_clock::now();  // informative wall time only
  // The thread's CPU time runs the whole co-simulation (the renderer inline, the video coded
  // and decoded inline), so it is this run's alone even beside other workers' threads; but
  // llvmpipe's own rasteriser threads, if it has any, are not counted (it starts one per CPU
  // unless LP_NUM_THREADS=0). A worker process sets that and counts its whole process.
  const double cpu0_s = cpu_clock_s(cpu_clock_);
  renderer_->set_warehouse(setup.scenario->warehouse);
  const RunResult result = run_cosimulation(setup, *renderer_);
  const double wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  RunRecord record = make_run_record(index, setup, result, wall_s);
  record.cpu_s = cpu_clock_s(cpu_clock_) - cpu0_s;
  return record;
}

RunRecord make_run_record(std::int64_t index, const RunSetup& setup, const RunResult& result, double wall_s) {
  RunRecord r;
  r.index = index;
  r.seed = setup.seed;
  r.dispersion_json = nlohmann::json(setup.drawn).dump();
  r.outcome = outcome_name(result.outcome);
  r.metrics_json = stored_metrics_json({result.metrics, result.detail, std::nullopt});
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
  j["approach_start_s"] = number_or_null(result.approach_start_s);
  j["cross_start_s"] = number_or_null(result.cross_start_s);
  return j.dump();
}

namespace {

/// The one list of summarized metrics: (name, value) for a run, in summary order.
std::vector<std::pair<std::string, std::optional<double>>> named_summary_values(const RunMetrics& m) {
  using Value = std::optional<double>;
  const auto abs_of = [](const Value& v) { return v ? Value(std::abs(*v)) : Value(); };
  std::vector<std::pair<std::string, Value>> v{{"mission_time_s", m.mission_time_s},
                                               {"path_length_m", m.truth.path_length_m},
                                               {"min_clearance_m", m.truth.min_clearance_m},
                                               {"entry_offset_y_abs_m", abs_of(m.truth.entry_offset_y_m)},
                                               {"entry_offset_z_abs_m", abs_of(m.truth.entry_offset_z_m)}};
  const std::pair<const char*, const std::optional<StepResponse>*> axes[] = {
      {"altitude", &m.altitude}, {"heading", &m.heading}, {"lateral", &m.lateral}};
  for (const auto& [axis, r] : axes) {
    v.push_back({std::string(axis) + "_settling_time_s", *r ? (*r)->settling_time_s : Value()});
    v.push_back({std::string(axis) + "_overshoot", *r ? (*r)->overshoot : Value()});
    v.push_back({std::string(axis) + "_overshoot_abs", *r ? Value((*r)->overshoot_abs) : Value()});
  }
  v.push_back({"inventory_precision", m.inventory.precision});
  v.push_back({"inventory_recall", m.inventory.recall});
  // What the link did (sdk: datagrams; ideal: whole messages).
  const LinkMetrics& l = m.link;
  const auto count = [](std::int64_t n) { return Value(static_cast<double>(n)); };
  v.push_back({"link_video_datagrams", count(l.video_datagrams)});
  v.push_back({"link_video_datagrams_lost", count(l.video_datagrams_lost)});
  v.push_back({"link_frames_decoded", count(l.frames_decoded)});
  v.push_back({"link_frames_damaged", count(l.frames_damaged)});
  v.push_back({"link_commands_sent", count(l.commands_sent)});
  v.push_back({"link_commands_lost", count(l.commands_lost)});
  v.push_back({"link_replies_lost", count(l.replies_lost)});
  v.push_back({"link_state_records_lost", count(l.state_records_lost)});
  v.push_back({"link_command_retries", count(l.command_retries)});
  v.push_back({"link_video_datagram_loss", l.video_datagrams > 0 ? Value(l.video_datagram_loss()) : Value()});
  v.push_back({"link_damaged_frame_fraction",
               l.frames_handed > 0 ? Value(static_cast<double>(l.frames_damaged) / static_cast<double>(l.frames_handed))
                                   : Value()});
  return v;
}

}  // namespace

const std::vector<std::string>& summary_metric_names() {
  static const std::vector<std::string> names = [] {
    std::vector<std::string> n;
    for (const auto& [name, value] : named_summary_values(RunMetrics{})) n.push_back(name);
    return n;
  }();
  return names;
}

std::vector<std::optional<double>> summary_metric_values(const RunMetrics& m) {
  std::vector<std::optional<double>> values;
  for (const auto& [name, value] : named_summary_values(m)) values.push_back(value);
  return values;
}

CampaignSummary summarize_campaign(const std::vector<RunRecord>& runs, std::int64_t runs_requested, double near_miss_m) {
  CampaignSummary summary;
  summary.runs_requested = runs_requested;
  summary.near_misses.near_miss_m = near_miss_m;
  const std::vector<std::string>& names = summary_metric_names();
  std::vector<std::vector<double>> values(names.size());
  std::vector<std::string> hashes, outcomes;
  std::vector<double> cpu_s;
  double cpu_s_simulated = 0.0, simulated_s = 0.0;  // over the runs with both figures
  for (const RunRecord& r : runs) {
    if (r.index >= runs_requested) continue;
    ++summary.runs;
    summary.successes += r.outcome == "success";
    ++summary.outcomes[r.outcome];
    outcomes.push_back(r.outcome);
    hashes.push_back(r.run_hash);
    if (r.cpu_s) cpu_s.push_back(*r.cpu_s);
    const StoredMetrics stored = stored_metrics(r);
    if (!stored.run) continue;  // a crashed, hung or failed worker measured nothing
    if (is_near_miss(r.outcome, stored.run, near_miss_m)) {
      ++summary.near_misses.runs;
      summary.near_misses.successes += r.outcome == "success";
    }
    if (r.cpu_s) {
      cpu_s_simulated += *r.cpu_s;
      simulated_s += stored.run->mission_time_s;
    }
    const std::vector<std::optional<double>> v = summary_metric_values(*stored.run);
    for (size_t i = 0; i < v.size(); ++i) {
      if (v[i]) values[i].push_back(*v[i]);
    }
  }
  if (summary.runs > 0) {
    summary.success_rate = static_cast<double>(summary.successes) / static_cast<double>(summary.runs);
    summary.success_lower_95 = clopper_pearson_lower(summary.successes, summary.runs, 0.95);
    summary.near_misses.rate = static_cast<double>(summary.near_misses.runs) / static_cast<double>(summary.runs);
  }
  summary.safety = summarize_safety(outcomes);
  for (size_t i = 0; i < names.size(); ++i) {
    if (!values[i].empty()) summary.metrics[names[i]] = summarize(values[i]);
  }
  CostSummary& cost = summary.cost;
  cost.cpu_s_per_run = summarize(cpu_s);
  if (simulated_s > 0.0) cost.cpu_s_per_simulated_s = cpu_s_simulated / simulated_s;
  summary.campaign_hash = summary.runs == runs_requested ? combine_run_hashes(hashes) : std::string();
  return summary;
}

namespace {

nlohmann::json summary_json(const Summary& m) {
  return {{"count", m.count}, {"mean", m.mean}, {"min", m.min}, {"p50", m.p50},
          {"p95", m.p95},     {"p99", m.p99},   {"max", m.max}};
}

Summary read_summary(StrictObject m) {
  Summary out;
  out.count = m.integer("count");
  out.mean = m.number("mean");
  out.min = m.number("min");
  out.p50 = m.number("p50");
  out.p95 = m.number("p95");
  out.p99 = m.number("p99");
  out.max = m.number("max");
  m.finish();
  return out;
}

}  // namespace

void to_json(nlohmann::json& j, const CampaignSummary& s) {
  using nlohmann::json;
  json metrics = json::object();
  for (const auto& [name, m] : s.metrics) metrics[name] = summary_json(m);
  const CostSummary& c = s.cost;
  // null where no run has a figure (runs per core-hour: 3600 / cpu_s_per_run.mean)
  const json cost{{"cpu_s_per_run", c.cpu_s_per_run.count > 0 ? summary_json(c.cpu_s_per_run) : json(nullptr)},
                  {"cpu_s_per_simulated_s", number_or_null(c.cpu_s_per_simulated_s)}};
  const SafetySummary& f = s.safety;
  j = json{{"runs", s.runs},
           {"runs_requested", s.runs_requested},
           {"successes", s.successes},
           {"success_rate", s.success_rate},
           {"success_lower_95", s.success_lower_95},
           {"outcomes", s.outcomes},
           {"safety",
            {{"runs", f.runs}, {"contacts", f.contacts}, {"shelf_contacts", f.shelf_contacts},
             {"contact_rate", f.contact_rate}, {"contact_upper_95", f.contact_upper_95},
             {"safe_aborts", f.safe_aborts}, {"inventory_errors", f.inventory_errors},
             {"other_failures", f.other_failures}}},
           {"near_misses",
            {{"near_miss_m", s.near_misses.near_miss_m}, {"runs", s.near_misses.runs},
             {"successes", s.near_misses.successes}, {"rate", s.near_misses.rate}}},
           {"metrics", metrics},
           {"cost", cost},
           {"campaign_hash", s.campaign_hash}};
}

void from_json(const nlohmann::json& j, CampaignSummary& s) {
  StrictObject o(j, "campaign summary");
  s = CampaignSummary{};
  s.runs = o.integer("runs");
  s.runs_requested = o.integer("runs_requested");
  s.successes = o.integer("successes");
  s.success_rate = o.number("success_rate");
  s.success_lower_95 = o.number("success_lower_95");
  s.campaign_hash = o.text("campaign_hash");
  StrictObject outcomes = o.object("outcomes");
  const std::vector<std::string>& known = known_run_outcomes();
  for (const std::string& name : outcomes.keys()) {
    if (std::find(known.begin(), known.end(), name) == known.end()) outcomes.fail_at(outcomes.path_of(name), "unknown outcome");
    s.outcomes[name] = outcomes.integer(name);
  }
  StrictObject f = o.object("safety");
  s.safety.runs = f.integer("runs");
  s.safety.contacts = f.integer("contacts");
  s.safety.shelf_contacts = f.integer("shelf_contacts");
  s.safety.contact_rate = f.number("contact_rate");
  s.safety.contact_upper_95 = f.number("contact_upper_95");
  s.safety.safe_aborts = f.integer("safe_aborts");
  s.safety.inventory_errors = f.integer("inventory_errors");
  s.safety.other_failures = f.integer("other_failures");
  f.finish();
  StrictObject n = o.object("near_misses");
  s.near_misses.near_miss_m = n.number("near_miss_m");
  s.near_misses.runs = n.integer("runs");
  s.near_misses.successes = n.integer("successes");
  s.near_misses.rate = n.number("rate");
  n.finish();
  StrictObject metrics = o.object("metrics");
  const std::vector<std::string>& names = summary_metric_names();
  for (const std::string& name : metrics.keys()) {
    if (std::find(names.begin(), names.end(), name) == names.end()) metrics.fail_at(metrics.path_of(name), "unknown metric");
    s.metrics[name] = read_summary(metrics.object(name));
  }
  StrictObject cost = o.object("cost");
  if (auto per_run = cost.optional_object("cpu_s_per_run")) s.cost.cpu_s_per_run = read_summary(std::move(*per_run));
  s.cost.cpu_s_per_simulated_s = cost.optional_number("cpu_s_per_simulated_s");
  cost.finish();
  o.finish();
}

}  // namespace shelfcross::verification
