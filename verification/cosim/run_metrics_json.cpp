#include "verification/cosim/run_metrics_json.hpp"

#include <stdexcept>

#include "config/strict_json.hpp"

namespace shelfcross::verification {

using config::StrictObject;
using config::number_or_null;
namespace {

using nlohmann::json;

/// The key of RunMetrics::sticks[a].
const char* stick_key(size_t a) { return flight_sw::stick_axis_name(static_cast<flight_sw::StickAxis>(a)); }

json response_json(const std::optional<StepResponse>& r) {
  if (!r) return nullptr;
  return {{"initial_error", r->initial_error},       {"band", r->band},
          {"settling_time_s", number_or_null(r->settling_time_s)}, {"overshoot", number_or_null(r->overshoot)},
          {"overshoot_abs", r->overshoot_abs},       {"peak_abs_error", r->peak_abs_error}};
}

std::optional<StepResponse> read_response(StrictObject& parent, const std::string& key) {
  auto o = parent.optional_object(key);
  if (!o) return std::nullopt;
  StepResponse r;
  r.initial_error = o->number("initial_error");
  r.band = o->number("band");
  r.settling_time_s = o->optional_number("settling_time_s");
  r.overshoot = o->optional_number("overshoot");
  r.overshoot_abs = o->number("overshoot_abs");
  r.peak_abs_error = o->number("peak_abs_error");
  o->finish();
  return r;
}

LinkMetrics read_link(StrictObject o) {
  LinkMetrics l;
  l.model = o.text("model");
  l.video_datagrams = o.integer("video_datagrams");
  l.video_datagrams_lost = o.integer("video_datagrams_lost");
  l.frames_captured = o.integer("frames_captured");
  l.frames_lost = o.integer("frames_lost");
  l.frames_decoded = o.integer("frames_decoded");
  l.frames_damaged = o.integer("frames_damaged");
  l.frames_handed = o.integer("frames_handed");
  l.commands_sent = o.integer("commands_sent");
  l.commands_lost = o.integer("commands_lost");
  l.replies_lost = o.integer("replies_lost");
  l.state_records_lost = o.integer("state_records_lost");
  l.command_retries = o.integer("command_retries");
  l.stale_replies = o.integer("stale_replies");
  l.injected_errors = o.integer("injected_errors");
  o.finish();
  return l;
}

/// Reads RunMetrics' keys from `o` (which may hold more keys: the stored record's detail);
/// the caller finishes `o`.
RunMetrics read_metrics(StrictObject& o) {
  RunMetrics m;
  m.mission_time_s = o.number("mission_time_s");
  m.truth = read_world_truth(o);
  m.truth.floor_touches = static_cast<int>(o.integer("floor_touches"));
  m.strategy = o.text("strategy");
  m.shelves = static_cast<int>(o.integer("shelves"));
  m.shelves_crossed = static_cast<int>(o.integer("shelves_crossed"));
  m.shelves_crossed_target = static_cast<int>(o.integer("shelves_crossed_target"));
  m.target = read_cell(o, "target");
  m.crossed_target = o.boolean("crossed_target");
  m.altitude = read_response(o, "altitude");
  m.heading = read_response(o, "heading");
  m.lateral = read_response(o, "lateral");
  StrictObject inv = o.object("inventory");
  m.inventory.precision = inv.number("precision");
  m.inventory.recall = inv.number("recall");
  m.inventory.correct = static_cast<int>(inv.integer("correct"));
  m.inventory.reported = static_cast<int>(inv.integer("reported"));
  m.inventory.truth = static_cast<int>(inv.integer("truth"));
  inv.finish();
  m.flight_software_result = o.text("flight_software_result");
  // Absent from stores written before the sticks' answer was measured.
  if (auto sticks = o.has("sticks") ? o.optional_object("sticks") : std::nullopt) {
    for (size_t a = 0; a < m.sticks.size(); ++a) {
      if (auto axis = sticks->optional_object(stick_key(a))) {
        flight_sw::AxisResponse s;
        s.gain = axis->number("gain");
        s.gain_se = axis->number("gain_se");
        s.tau_s = axis->number("tau_s");
        if (axis->has("delay_s")) s.delay_s = axis->number("delay_s");  // absent before the dead time was fitted
        s.windows = static_cast<int>(axis->integer("windows"));
        s.scale = axis->number("scale");
        axis->finish();
        m.sticks[a] = s;
      }
    }
    sticks->finish();
  }
  m.link = read_link(o.object("link"));
  return m;
}

}  // namespace


void to_json(json& j, const RunMetrics& m) {
  j = json{{"mission_time_s", m.mission_time_s},
           {"strategy", m.strategy},
           {"shelves", m.shelves},
           {"shelves_crossed", m.shelves_crossed},
           {"shelves_crossed_target", m.shelves_crossed_target},
           {"target", cell_json(m.target)},
           {"crossed_target", m.crossed_target},
           {"altitude", response_json(m.altitude)},
           {"heading", response_json(m.heading)},
           {"lateral", response_json(m.lateral)},
           {"inventory", {{"precision", m.inventory.precision}, {"recall", m.inventory.recall},
                          {"correct", m.inventory.correct}, {"reported", m.inventory.reported},
                          {"truth", m.inventory.truth}}},
           {"flight_software_result", m.flight_software_result},
           {"floor_touches", m.truth.floor_touches}};
  write_world_truth(j, m.truth);
  json sticks = json::object();
  for (size_t a = 0; a < m.sticks.size(); ++a) {
    if (const auto& s = m.sticks[a]) {
      sticks[stick_key(a)] = {{"gain", s->gain}, {"gain_se", s->gain_se}, {"tau_s", s->tau_s},
                               {"delay_s", s->delay_s}, {"windows", s->windows}, {"scale", s->scale}};
    } else {
      sticks[stick_key(a)] = nullptr;
    }
  }
  j["sticks"] = sticks;
  const LinkMetrics& l = m.link;
  j["link"] = {{"model", l.model},
               {"video_datagrams", l.video_datagrams},
               {"video_datagrams_lost", l.video_datagrams_lost},
               {"frames_captured", l.frames_captured},
               {"frames_lost", l.frames_lost},
               {"frames_decoded", l.frames_decoded},
               {"frames_damaged", l.frames_damaged},
               {"frames_handed", l.frames_handed},
               {"commands_sent", l.commands_sent},
               {"commands_lost", l.commands_lost},
               {"replies_lost", l.replies_lost},
               {"state_records_lost", l.state_records_lost},
               {"command_retries", l.command_retries},
               {"stale_replies", l.stale_replies},
               {"injected_errors", l.injected_errors}};
}

void from_json(const json& j, RunMetrics& m) {
  StrictObject o(j, "run metrics");
  m = read_metrics(o);
  o.finish();
}

std::string run_metrics_json(const RunMetrics& m) { return json(m).dump(); }

bool StoredMetrics::operator==(const StoredMetrics& other) const {
  return stored_metrics_json(*this) == stored_metrics_json(other);
}

// Stored form: the metrics' keys (when the run finished) and "detail" side by side in one
// object, plus "signal" for a crashed worker. Databases written before the worker-error record
// carried "detail" hold {"error": message} for a worker_error run; it reads as the detail.
std::string stored_metrics_json(const StoredMetrics& s) {
  json j = s.run ? json(*s.run) : json::object();
  j["detail"] = s.detail;
  if (s.signal) j["signal"] = *s.signal;
  return j.dump();
}

StoredMetrics parse_stored_metrics(const std::string& text) {
  const json j = json::parse(text, nullptr, /*allow_exceptions=*/false);
  if (j.is_discarded()) throw std::invalid_argument("run metrics: not JSON");
  StrictObject o(j, "run metrics");
  StoredMetrics s;
  if (o.has("mission_time_s")) s.run = read_metrics(o);
  if (o.has("error") && !o.has("detail")) {
    s.detail = o.text("error");
  } else {
    s.detail = o.text("detail");
  }
  if (o.has("signal")) s.signal = static_cast<int>(o.integer("signal"));
  o.finish();
  return s;
}


}  // namespace shelfcross::verification
