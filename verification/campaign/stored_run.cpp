#include "verification/campaign/stored_run.hpp"

#include <limits>
#include <stdexcept>
#include <string>

#include <nlohmann/json.hpp>

#include "verification/statistics/statistics.hpp"

namespace shelfcross::verification {

bool is_near_miss(const std::string& outcome, const std::optional<RunMetrics>& run, double near_miss_m) {
  if (!run || classify_outcome(outcome) == RunSafetyClass::contact || run->truth.contact) return false;
  return run->truth.min_clearance_m && *run->truth.min_clearance_m < near_miss_m;
}

StoredMetrics stored_metrics(const RunRecord& record) {
  try {
    return parse_stored_metrics(record.metrics_json);
  } catch (const std::exception& e) {
    throw std::invalid_argument("stored run " + std::to_string(record.index) + ": " + e.what());
  }
}

DrawnValues stored_draws(const RunRecord& record) {
  const nlohmann::json j = nlohmann::json::parse(record.dispersion_json, nullptr, /*allow_exceptions=*/false);
  DrawnValues drawn;
  if (j.is_object()) {
    for (const auto& [name, value] : j.items()) {
      if (!value.is_number()) break;
      drawn[name] = value.get<double>();
    }
    if (drawn.size() == j.size()) return drawn;
  }
  throw std::invalid_argument("stored run " + std::to_string(record.index) +
                              ": dispersion_json is not an object of numbers");
}

StoredTrace stored_trace(const RunRecord& record) {
  StoredTrace trace;
  const nlohmann::json j = nlohmann::json::parse(record.trace_json.empty() ? "{}" : record.trace_json, nullptr,
                                                 /*allow_exceptions=*/false);
  const auto fail = [&record](const std::string& why) {
    return std::invalid_argument("stored run " + std::to_string(record.index) + ": trace_json " + why);
  };
  if (!j.is_object()) throw fail("is not an object");
  if (!j.contains("t")) return trace;  // nothing measured
  const auto numbers = [&](const char* key, std::vector<double>& out) {
    if (!j.contains(key) || !j[key].is_array()) throw fail(std::string("has no array \"") + key + "\"");
    for (const nlohmann::json& v : j[key]) {  // JSON has no NaN: a diverged run's is null
      if (!v.is_number() && !v.is_null()) throw fail(std::string("\"") + key + "\" holds a value that is not a number");
      out.push_back(v.is_number() ? v.get<double>() : std::numeric_limits<double>::quiet_NaN());
    }
    if (out.size() != j["t"].size()) throw fail(std::string("\"") + key + "\" has a different length from \"t\"");
  };
  numbers("t", trace.t_s);
  numbers("x", trace.x_W_m);
  numbers("y", trace.y_W_m);
  numbers("z", trace.z_W_m);
  numbers("yaw", trace.yaw_rad);
  const auto time = [&](const char* key) -> std::optional<double> {
    if (!j.contains(key) || j[key].is_null()) return std::nullopt;
    if (!j[key].is_number()) throw fail(std::string("\"") + key + "\" is not a number");
    return j[key].get<double>();
  };
  trace.approach_start_s = time("approach_start_s");
  trace.cross_start_s = time("cross_start_s");
  return trace;
}

}  // namespace shelfcross::verification
