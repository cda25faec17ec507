#pragma once
// Metrics of one run computed from its logged time series: settling time and overshoot of
// the altitude and heading responses during the approach (paper Fig. 26, 27), the lateral
// response (Fig. 28), path length, and inventory precision and recall against the truth.

#include <array>
#include <optional>
#include <set>
#include <tuple>
#include <vector>

namespace shelfcross::verification {

/// A settling band: |e| <= max(fraction * |e(t0)|, floor).
/// Defaults: 2 % of the initial error, never tighter than 1 cm (altitude) or 0.5 deg
/// (heading); the floor is given in the error's unit.
struct SettlingBand {
  double fraction = 0.02;
  double floor = 0.0;
};

struct StepResponse {
  double initial_error = 0.0;
  double band = 0.0;                     ///< the absolute band used
  std::optional<double> settling_time_s; ///< from t0 until |e| stays inside the band for good
  /// Largest excursion past zero against e(t0)'s sign, in the error's unit (0 when none).
  double overshoot_abs = 0.0;
  /// The same as a fraction of |e(t0)|; only when |e(t0)| exceeds the band, i.e. when there
  /// was a step to respond to (a response that starts inside its band and is then disturbed,
  /// as the heading is when the vehicle turns toward its target cell, has no meaningful ratio).
  std::optional<double> overshoot;
  double peak_abs_error = 0.0;           ///< max |e| after t0
};

/// Analyses e(t) from the first sample (t0) to the last. Samples must be in time order.
/// Throws std::invalid_argument when t_s and error differ in length.
/// The settling time is t_first - t0 where t_first is the earliest sample after which every
/// sample is inside the band; empty when the last sample is outside (never settled).
StepResponse analyse_step_response(const std::vector<double>& t_s, const std::vector<double>& error,
                                   const SettlingBand& band);

/// Length of the polyline through the positions (x, y, z triples), m.
double path_length_m(const std::vector<std::array<double, 3>>& positions_m);

/// One inventory line: (marker id, shelf, level, column).
using InventoryEntry = std::tuple<int, int, int, int>;

struct InventoryScore {
  double precision = 1.0;  ///< correct reported / reported (1 when nothing reported)
  double recall = 0.0;     ///< correct reported / true boxes (1 when there are none)
  int correct = 0, reported = 0, truth = 0;
  bool exact() const { return correct == reported && correct == truth; }
};

InventoryScore score_inventory(const std::set<InventoryEntry>& reported, const std::set<InventoryEntry>& truth);

}  // namespace shelfcross::verification
