#pragma once
// A run's metrics as JSON, both ways: the text every run stores (results database, worker
// messages, `shelfcross run --json`) and that its run hash covers.
//
// Reading is strict: every key of the format must be there with its type (a number where a
// number is due, an integer where a count is, null only where the value is optional), and an
// unknown key is refused; each error names the key path (e.g. "link.frames_lost"). So a
// misspelt or renamed metric fails a test instead of silently dropping a statistic, and every
// reader of stored runs uses the typed RunMetrics, never a key spelt by hand.

#include <optional>
#include <string>

#include <nlohmann/json.hpp>

#include "plant/collision.hpp"
#include "verification/cosim/run_result.hpp"
#include "verification/scenario/dispersion.hpp"

namespace shelfcross::verification {

void to_json(nlohmann::json& j, const RunMetrics& m);
/// Throws std::invalid_argument naming the key on a missing, unknown or mistyped key.
void from_json(const nlohmann::json& j, RunMetrics& m);

/// json(m).dump(): exact doubles (nlohmann writes the shortest text that reads back to the same
/// double), keys in sorted order, so the text and the run hash depend on the values only.
std::string run_metrics_json(const RunMetrics& m);


/// What a stored run's metrics_json holds: the co-simulation's metrics when the run finished in
/// a worker (absent for crashed, hung and worker_error runs), the outcome's detail (the contact
/// element, the exception, why a worker was lost) and, for a crashed worker, its signal.
struct StoredMetrics {
  std::optional<RunMetrics> run;
  std::string detail;
  std::optional<int> signal;
  bool operator==(const StoredMetrics&) const;
};
std::string stored_metrics_json(const StoredMetrics& s);
/// Throws std::invalid_argument naming the key (see above).
StoredMetrics parse_stored_metrics(const std::string& text);


}  // namespace shelfcross::verification
