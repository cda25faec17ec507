#include "verification/world/metrics.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>


namespace shelfcross::verification {

StepResponse analyse_step_response(const std::vector<double>& t_s, const std::vector<double>& error,
                                   const SettlingBand& band) {
  if (t_s.size() != error.size()) throw std::invalid_argument("analyse_step_response: sizes differ");
  StepResponse r;
  if (t_s.empty()) return r;
  r.initial_error = error.front();
  r.band = std::max(band.fraction * std::abs(r.initial_error), band.floor);
  // Walk back from the end: the settling instant is the sample after the last one outside.
  size_t first_inside_for_good = t_s.size();
  for (size_t i = t_s.size(); i-- > 0;) {
    if (std::abs(error[i]) > r.band) break;
    first_inside_for_good = i;
  }
  if (first_inside_for_good < t_s.size()) r.settling_time_s = t_s[first_inside_for_good] - t_s.front();
  const double sign = r.initial_error >= 0.0 ? 1.0 : -1.0;
  double past_zero = 0.0;
  for (double e : error) {
    r.peak_abs_error = std::max(r.peak_abs_error, std::abs(e));
    past_zero = std::max(past_zero, -sign * e);
  }
  r.overshoot_abs = past_zero;
  if (std::abs(r.initial_error) > r.band) r.overshoot = past_zero / std::abs(r.initial_error);
  return r;
}

double path_length_m(const std::vector<std::array<double, 3>>& p) {
  double length = 0.0;
  for (size_t i = 1; i < p.size(); ++i) {
    length += std::sqrt((p[i][0] - p[i - 1][0]) * (p[i][0] - p[i - 1][0]) +
                        (p[i][1] - p[i - 1][1]) * (p[i][1] - p[i - 1][1]) +
                        (p[i][2] - p[i - 1][2]) * (p[i][2] - p[i - 1][2]));
  }
  return length;
}

InventoryScore score_inventory(const std::set<InventoryEntry>& reported, const std::set<InventoryEntry>& truth) {
  InventoryScore s;
  s.reported = static_cast<int>(reported.size());
  s.truth = static_cast<int>(truth.size());
  for (const auto& e : reported) s.correct += truth.count(e) ? 1 : 0;
  s.precision = s.reported ? static_cast<double>(s.correct) / s.reported : 1.0;
  s.recall = s.truth ? static_cast<double>(s.correct) / s.truth : 1.0;
  return s;
}

}  // namespace shelfcross::verification
