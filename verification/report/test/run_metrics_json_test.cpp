// Typed run metrics and campaign summaries: what a run stores reads back to the same
// value, and a missing, unknown or mistyped key is refused by name instead of silently dropping
// a statistic.

#include <gtest/gtest.h>

#include <functional>

#include <nlohmann/json.hpp>

#include "verification/campaign/campaign.hpp"
#include "verification/campaign/stored_run.hpp"
#include "verification/cosim/run_metrics_json.hpp"
#include "verification/report/report.hpp"

namespace shelfcross::verification {
namespace {

using nlohmann::json;

/// Every field set, every optional present, no value equal to its default.
RunMetrics full_metrics() {
  RunMetrics m;
  m.mission_time_s = 21.375;
  m.truth.path_length_m = 6.0625;
  m.truth.floor_touches = 2;
  plant::Contact c;
  c.t_ns = 12'345'678'901;
  c.element.kind = plant::ElementKind::beam;
  c.element.name = "shelf 0 beam 2, front face";
  c.point_W_m = {1.5, -0.25, 1.125};
  c.depth_m = 0.003;
  m.truth.contact = c;
  m.strategy = "over_tops";
  m.shelves = 3;
  m.shelves_crossed = 2;
  m.shelves_crossed_target = 1;
  m.target = CellIndex{1, 2};
  m.truth.crossed = CellIndex{0, 2};
  m.crossed_target = true;
  m.truth.entry_offset_y_m = -0.0425;
  m.truth.entry_offset_z_m = 0.0175;
  m.truth.min_clearance_m = 0.0925;
  StepResponse r;
  r.initial_error = 0.5;
  r.band = 0.01;
  r.settling_time_s = 3.25;
  r.overshoot = 0.125;
  r.overshoot_abs = 0.0625;
  r.peak_abs_error = 0.5;
  m.altitude = r;
  r.initial_error = -0.75;
  m.heading = r;
  m.lateral = r;
  m.inventory = {0.75, 0.5, 3, 4, 6};
  m.flight_software_result = "completed";
  m.sticks[0] = flight_sw::AxisResponse{1.875, 0.0625, 0.5, 0.05, 120, 0.5};  // the vertical axis left unmeasured
  m.sticks[2] = flight_sw::AxisResponse{2.125, 0.125, 0.75, 0.1, 40, 0.625};
  LinkMetrics& l = m.link;
  l.model = "sdk";
  l.video_datagrams = 9000;
  l.video_datagrams_lost = 90;
  l.frames_captured = 600;
  l.frames_lost = 3;
  l.frames_decoded = 590;
  l.frames_damaged = 120;
  l.frames_handed = 580;
  l.commands_sent = 400;
  l.commands_lost = 4;
  l.replies_lost = 2;
  l.state_records_lost = 5;
  l.command_retries = 6;
  l.stale_replies = 1;
  l.injected_errors = 7;
  return m;
}

std::string error_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "(no error)";
}

TEST(RunMetricsJson, EveryFieldReadsBackToTheSameText) {
  RunMetrics m = full_metrics();
  m.lateral->settling_time_s.reset();  // never settled: null in the text
  const std::string text = run_metrics_json(m);
  const RunMetrics back = json::parse(text).get<RunMetrics>();
  EXPECT_EQ(run_metrics_json(back), text);
  ASSERT_TRUE(back.truth.contact.has_value());
  EXPECT_EQ(back.truth.contact->t_ns, 12'345'678'901);
  EXPECT_EQ(back.truth.contact->element.kind, plant::ElementKind::beam);
  EXPECT_EQ(back.lateral->settling_time_s, std::nullopt);
  EXPECT_EQ(back.link.injected_errors, 7);
  ASSERT_TRUE(back.sticks[2].has_value());
  EXPECT_EQ(back.sticks[2]->windows, 40);
  EXPECT_EQ(back.sticks[2]->delay_s, 0.1);
  EXPECT_FALSE(back.sticks[1].has_value());
  // A store written before the sticks' answer was measured reads back without it.
  json before = json::parse(text);
  before.erase("sticks");
  EXPECT_FALSE(before.get<RunMetrics>().sticks[0].has_value());
  // ... and one written before the dead time was fitted, with the lag alone.
  json no_delay = json::parse(text);
  no_delay["sticks"]["yaw"].erase("delay_s");
  EXPECT_EQ(no_delay.get<RunMetrics>().sticks[2]->delay_s, 0.0);
  // The defaults too: empty optionals are null, not missing.
  const RunMetrics empty;
  EXPECT_EQ(run_metrics_json(json::parse(run_metrics_json(empty)).get<RunMetrics>()), run_metrics_json(empty));
}

TEST(RunMetricsJson, AMisspeltMissingOrMistypedKeyIsRefusedByName) {
  const json good = full_metrics();
  json renamed = good;
  renamed["mission_time"] = renamed["mission_time_s"];
  renamed.erase("mission_time_s");
  EXPECT_EQ(error_of([&] { renamed.get<RunMetrics>(); }), "run metrics: 'mission_time_s': missing");

  json extra = good;
  extra["link"]["frames_dropped"] = 1;
  EXPECT_EQ(error_of([&] { extra.get<RunMetrics>(); }), "run metrics: 'link.frames_dropped': unknown key");

  json fractional = good;
  fractional["link"]["frames_lost"] = 2.5;  // a count is an integer
  EXPECT_EQ(error_of([&] { fractional.get<RunMetrics>(); }), "run metrics: 'link.frames_lost': expected an integer");

  json text_number = good;
  text_number["altitude"]["band"] = "0.01";
  EXPECT_EQ(error_of([&] { text_number.get<RunMetrics>(); }), "run metrics: 'altitude.band': expected a number");

  json null_required = good;
  null_required["path_length_m"] = nullptr;  // only optionals may be null
  EXPECT_EQ(error_of([&] { null_required.get<RunMetrics>(); }), "run metrics: 'path_length_m': expected a number");

  json kind = good;
  kind["contact"]["kind"] = "ceiling fan";
  EXPECT_EQ(error_of([&] { kind.get<RunMetrics>(); }), "run metrics: 'contact.kind': unknown element kind \"ceiling fan\"");
}

TEST(StoredMetrics, FinishedAndLostRunsBothReadBack) {
  const StoredMetrics finished{full_metrics(), "shelf 0 beam 2, front face", std::nullopt};
  EXPECT_EQ(parse_stored_metrics(stored_metrics_json(finished)), finished);

  const StoredMetrics crashed{std::nullopt, "worker died by signal 11 (Segmentation fault)", 11};
  const StoredMetrics back = parse_stored_metrics(stored_metrics_json(crashed));
  EXPECT_FALSE(back.run.has_value());
  EXPECT_EQ(back.detail, crashed.detail);
  EXPECT_EQ(back.signal, 11);

  // A worker_error record of a database written before its record carried "detail".
  EXPECT_EQ(parse_stored_metrics(R"({"error":"renderer: no EGL display"})").detail, "renderer: no EGL display");

  RunRecord r;
  r.index = 41;
  r.metrics_json = R"({"detail":"x","mystery":1})";
  EXPECT_EQ(error_of([&] { stored_metrics(r); }), "stored run 41: run metrics: 'mystery': unknown key");
  r.metrics_json = "{";
  EXPECT_EQ(error_of([&] { stored_metrics(r); }), "stored run 41: run metrics: not JSON");
  r.dispersion_json = R"({"gust_intensity_mps":0.25,"video_latency_mean_s":0.2})";
  EXPECT_EQ(stored_draws(r), (DrawnValues{{"gust_intensity_mps", 0.25}, {"video_latency_mean_s", 0.2}}));
  r.dispersion_json = R"({"gust_intensity_mps":"high"})";
  EXPECT_EQ(error_of([&] { stored_draws(r); }), "stored run 41: dispersion_json is not an object of numbers");
}

RunRecord record(std::int64_t index, const std::string& outcome, const StoredMetrics& metrics) {
  RunRecord r;
  r.index = index;
  r.seed = 1000 + static_cast<std::uint64_t>(index);
  r.outcome = outcome;
  r.metrics_json = stored_metrics_json(metrics);
  r.run_hash = std::string(31, '0') + std::to_string(index);
  return r;
}

TEST(CampaignSummary, EveryMetricIsSummarizedAndTheSummaryReadsBack) {
  RunMetrics slower = full_metrics();
  slower.mission_time_s = 31.375;
  const std::vector<RunRecord> runs{record(0, "success", {full_metrics(), "", std::nullopt}),
                                    record(1, "collision", {slower, "shelf 0 beam 2", std::nullopt}),
                                    record(2, "crashed", {std::nullopt, "signal 11", 11})};
  const CampaignSummary s = summarize_campaign(runs, 3, 0.02);
  EXPECT_EQ(s.runs, 3);
  EXPECT_EQ(s.successes, 1);
  EXPECT_EQ(s.outcomes, (std::map<std::string, std::int64_t>{{"collision", 1}, {"crashed", 1}, {"success", 1}}));
  EXPECT_EQ(s.safety.contacts, 1);
  EXPECT_EQ(s.safety.other_failures, 1);
  EXPECT_EQ(s.campaign_hash.size(), 32u);
  // With every optional present, every named metric has its statistics (the crashed run has none).
  for (const std::string& name : summary_metric_names()) {
    ASSERT_TRUE(s.metrics.count(name)) << name;
    EXPECT_EQ(s.metrics.at(name).count, 2) << name;
  }
  EXPECT_DOUBLE_EQ(s.metrics.at("mission_time_s").mean, 26.375);
  EXPECT_DOUBLE_EQ(s.metrics.at("link_video_datagram_loss").max, 0.01);
  EXPECT_DOUBLE_EQ(s.metrics.at("entry_offset_y_abs_m").min, 0.0425);

  const json j = s;
  const CampaignSummary back = j.get<CampaignSummary>();
  EXPECT_EQ(json(back), j);

  json misspelt = j;
  misspelt["metrics"]["mission_time"] = misspelt["metrics"]["mission_time_s"];
  EXPECT_EQ(error_of([&] { misspelt.get<CampaignSummary>(); }), "campaign summary: 'metrics.mission_time': unknown metric");
  json outcome = j;
  outcome["outcomes"]["colision"] = 1;
  EXPECT_EQ(error_of([&] { outcome.get<CampaignSummary>(); }), "campaign summary: 'outcomes.colision': unknown outcome");
  json missing = j;
  missing["safety"].erase("contact_upper_95");
  EXPECT_EQ(error_of([&] { missing.get<CampaignSummary>(); }), "campaign summary: 'safety.contact_upper_95': missing");
}

// The cost is over the runs with a CPU figure (a lost run has none), per simulated second over
// those with a mission time too; with no figure at all (a database from before cpu_s) the
// report says so instead of showing zeros.
TEST(CampaignSummary, CostOfTheRunsWithACpuFigure) {
  RunMetrics slower = full_metrics();
  slower.mission_time_s = 31.375;
  std::vector<RunRecord> runs{record(0, "success", {full_metrics(), "", std::nullopt}),
                              record(1, "collision", {slower, "shelf 0 beam 2", std::nullopt}),
                              record(2, "crashed", {std::nullopt, "signal 11", 11})};
  runs[0].cpu_s = 2.0;
  runs[1].cpu_s = 4.0;
  const CampaignSummary s = summarize_campaign(runs, 3, 0.02);
  EXPECT_EQ(s.cost.cpu_s_per_run.count, 2);
  EXPECT_DOUBLE_EQ(s.cost.cpu_s_per_run.mean, 3.0);
  EXPECT_DOUBLE_EQ(s.cost.cpu_s_per_run.max, 4.0);
  EXPECT_DOUBLE_EQ(s.cost.cpu_s_per_simulated_s.value(), 6.0 / (21.375 + 31.375));
  const json j = s;
  EXPECT_EQ(j["cost"]["cpu_s_per_run"]["count"], 2);
  EXPECT_EQ(json(j.get<CampaignSummary>()), j);
  json unknown = j;
  unknown["cost"]["runs_per_core_hour"] = 1200.0;  // derived, not stored: refused as unknown
  EXPECT_EQ(error_of([&] { unknown.get<CampaignSummary>(); }),
            "campaign summary: 'cost.runs_per_core_hour': unknown key");
  const std::string md = cost_section(s.cost, s.runs);
  EXPECT_NE(md.find("| runs with a CPU figure | 2 of 3 |"), std::string::npos) << md;
  EXPECT_NE(md.find("| CPU seconds per run: mean, p50, p95, max | 3.00, 3.00, 3.90, 4.00 |"), std::string::npos) << md;
  EXPECT_NE(md.find("| CPU seconds per simulated second | 0.114 |"), std::string::npos) << md;
  EXPECT_NE(md.find("| runs per core-hour | 1200 |"), std::string::npos) << md;

  for (RunRecord& r : runs) r.cpu_s.reset();
  const CampaignSummary none = summarize_campaign(runs, 3, 0.02);
  EXPECT_EQ(none.cost.cpu_s_per_run.count, 0);
  EXPECT_EQ(none.cost.cpu_s_per_simulated_s, std::nullopt);
  const json k = none;
  EXPECT_EQ(k["cost"], json::parse(R"({"cpu_s_per_run": null, "cpu_s_per_simulated_s": null})"));
  EXPECT_EQ(json(k.get<CampaignSummary>()), k);
  EXPECT_NE(cost_section(none.cost, none.runs).find("CPU time not recorded"), std::string::npos);
}

// A near miss is a run that touched nothing but passed closer to a shelf than the threshold,
// counted apart from contacts (a contact, however close, is not one) and from success (a
// successful run may be one); a run that never came near a shelf, or measured nothing, is not.
TEST(CampaignSummary, NearMissesAreCountedApartFromContactsAndSuccess) {
  RunMetrics close = full_metrics();
  close.truth.contact.reset();
  close.truth.min_clearance_m = 0.015;
  RunMetrics closer_abort = close;
  closer_abort.truth.min_clearance_m = 0.004;
  RunMetrics clear = close;
  clear.truth.min_clearance_m = 0.025;
  RunMetrics never_near = close;
  never_near.truth.min_clearance_m.reset();
  RunMetrics touched = full_metrics();  // a contact, its clearance 0 at the touch
  touched.truth.min_clearance_m = 0.0;
  const std::vector<RunRecord> runs{record(0, "success", {close, "", std::nullopt}),
                                    record(1, "mission_aborted", {closer_abort, "target lost", std::nullopt}),
                                    record(2, "success", {clear, "", std::nullopt}),
                                    record(3, "no_crossing", {never_near, "", std::nullopt}),
                                    record(4, "collision", {touched, "shelf 0 beam 2", std::nullopt}),
                                    record(5, "crashed", {std::nullopt, "signal 11", 11})};
  EXPECT_TRUE(is_near_miss("success", close, 0.02));
  EXPECT_FALSE(is_near_miss("success", clear, 0.02));
  EXPECT_FALSE(is_near_miss("collision", touched, 0.02));
  EXPECT_FALSE(is_near_miss("left_arena", close, 0.02));  // a contact outcome is never a near miss
  EXPECT_FALSE(is_near_miss("no_crossing", never_near, 0.02));
  EXPECT_FALSE(is_near_miss("crashed", std::nullopt, 0.02));

  const CampaignSummary s = summarize_campaign(runs, 6, 0.02);
  EXPECT_EQ(s.near_misses.near_miss_m, 0.02);
  EXPECT_EQ(s.near_misses.runs, 2);
  EXPECT_EQ(s.near_misses.successes, 1);
  EXPECT_DOUBLE_EQ(s.near_misses.rate, 2.0 / 6.0);
  EXPECT_EQ(s.safety.contacts, 1);
  EXPECT_EQ(s.successes, 2);
  // The threshold is the scenario's: at 3 cm the run that cleared by 2.5 cm is one too.
  EXPECT_EQ(summarize_campaign(runs, 6, 0.03).near_misses.runs, 3);
  EXPECT_EQ(summarize_campaign(runs, 6, 0.003).near_misses.runs, 0);

  const json j = s;
  EXPECT_EQ(j["near_misses"], json::parse(R"({"near_miss_m": 0.02, "runs": 2, "successes": 1, "rate": 0.3333333333333333})"));
  EXPECT_EQ(json(j.get<CampaignSummary>()), j);
  json missing = j;
  missing.erase("near_misses");
  EXPECT_EQ(error_of([&] { missing.get<CampaignSummary>(); }), "campaign summary: 'near_misses': missing");
  json misspelt = j;
  misspelt["near_misses"]["count"] = 2;
  EXPECT_EQ(error_of([&] { misspelt.get<CampaignSummary>(); }), "campaign summary: 'near_misses.count': unknown key");

  const std::string md = safety_section(s.safety, s.near_misses);
  EXPECT_NE(md.find("| near misses (no contact, least clearance below 2.0 cm) | 2 (1 succeeded) | 33.33 % | |"),
            std::string::npos)
      << md;
}

TEST(CampaignSummary, AStoredRunThatDoesNotReadBackStopsTheSummary) {
  std::vector<RunRecord> runs{record(0, "success", {full_metrics(), "", std::nullopt})};
  json bad = full_metrics();
  bad["detail"] = "";
  bad["inventory"]["recal"] = 1.0;
  runs[0].metrics_json = bad.dump();
  EXPECT_EQ(error_of([&] { summarize_campaign(runs, 1, 0.02); }), "stored run 0: run metrics: 'inventory.recal': unknown key");
}

}  // namespace
}  // namespace shelfcross::verification
