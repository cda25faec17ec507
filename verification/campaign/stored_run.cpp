#include "verification/campaign/stored_run.hpp"

#include <stdexcept>
#include <string>

#include <nlohmann/json.hpp>

namespace shelfcross::verification {

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

}  // namespace shelfcross::verification
