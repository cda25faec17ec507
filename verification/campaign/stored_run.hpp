#pragma once
// A stored run's columns read typed: its metrics (run_metrics_json.hpp's StoredMetrics) and its
// drawn values. Every reader of stored runs goes through these, never a key spelt by hand.

#include "verification/campaign/results_store.hpp"
#include "verification/cosim/run_metrics_json.hpp"
#include "verification/scenario/dispersion.hpp"

namespace shelfcross::verification {

/// Both throw std::invalid_argument naming the run (and the key, for the metrics).
StoredMetrics stored_metrics(const RunRecord& record);
DrawnValues stored_draws(const RunRecord& record);

}  // namespace shelfcross::verification
