#pragma once
// A stored run's columns read typed: its metrics (run_metrics_json.hpp's StoredMetrics), its
// drawn values and its trace. Every reader of stored runs goes through these, never a key spelt
// by hand.

#include <optional>
#include <string>
#include <vector>

#include "verification/campaign/results_store.hpp"
#include "verification/cosim/run_metrics_json.hpp"
#include "verification/scenario/dispersion.hpp"

namespace shelfcross::verification {

/// Both throw std::invalid_argument naming the run (and the key, for the metrics).
StoredMetrics stored_metrics(const RunRecord& record);
DrawnValues stored_draws(const RunRecord& record);

/// A run's stored trajectory (campaign.hpp's trace_json): the body origin in W and its yaw at
/// about 10 Hz, positions to 1 mm (NaN where a diverged run stored none), and when the approach
/// and the crossing started.
struct StoredTrace {
  std::vector<double> t_s, x_W_m, y_W_m, z_W_m, yaw_rad;  ///< one entry per sample, in time order
  std::optional<double> approach_start_s, cross_start_s;
};
/// Empty for a run that stored none (a worker that crashed measured nothing); throws
/// std::invalid_argument naming the run when the trace does not read back.
StoredTrace stored_trace(const RunRecord& record);

/// A near miss: a run whose outcome is not a contact (statistics.hpp's classes), that touched
/// nothing (no WorldTruth::contact), and whose least clearance to a shelf (min_clearance_m)
/// was below `near_miss_m` (the scenario's cosim.near_miss_m). A class apart from contacts
/// and from success: a successful run may be a near miss, a contact never is. A run with no
/// metrics (lost with its worker) or no clearance measured (never near a shelf) is not one.
bool is_near_miss(const std::string& outcome, const std::optional<RunMetrics>& run, double near_miss_m);

}  // namespace shelfcross::verification
