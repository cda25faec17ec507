#include "verification/search/margin.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "verification/campaign/stored_run.hpp"

namespace shelfcross::verification {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

}  // namespace

const char* failure_class_name(FailureClass c) {
  switch (c) {
    case FailureClass::contact: return "contact";
    case FailureClass::crossing: return "crossing";
    case FailureClass::mission: return "mission";
    case FailureClass::near_miss: return "near_miss";
  }
  return "?";
}

std::optional<FailureClass> parse_failure_class(const std::string& name) {
  for (FailureClass c : kFailureClasses) {
    if (name == failure_class_name(c)) return c;
  }
  return std::nullopt;
}

double RunMargins::of(FailureClass c) const {
  switch (c) {
    case FailureClass::contact: return contact_m;
    case FailureClass::crossing: return crossing_m;
    case FailureClass::mission: return mission;
    case FailureClass::near_miss: return near_miss_m;
  }
  return kNaN;
}

RunMargins run_margins(const Scenario& nominal, const std::string& outcome, const std::optional<RunMetrics>& metrics) {
  RunMargins m;
  // Contact: below zero by the first contact's depth (touching counts), else the least
  // clearance to a shelf part while near a mission shelf (WorldTruth::min_clearance_m).
  if (metrics && metrics->truth.contact) {
    m.contact_m = std::min(-metrics->truth.contact->depth_m, -1e-6);
  } else if (outcome == "left_arena" || outcome == "collision") {
    m.contact_m = -1e-6;  // left the arena box without a recorded contact
  } else {
    m.contact_m = metrics ? metrics->truth.min_clearance_m.value_or(kNaN) : kNaN;
  }
  // Near miss: the clearance below the scenario's threshold (contacts lower it too).
  m.near_miss_m = m.contact_m - nominal.cosim.near_miss_m;
  m.near_miss_run = is_near_miss(outcome, metrics, nominal.cosim.near_miss_m);
  // Crossing: the room at the entered cell's front face.
  m.crossing_m = kNaN;
  if (metrics && metrics->truth.entry_offset_y_m && metrics->truth.entry_offset_z_m && !nominal.warehouse.shelves.empty()) {
    const double e_y = *metrics->truth.entry_offset_y_m, e_z = *metrics->truth.entry_offset_z_m;
    const ShelfSpec& shelf = nominal.warehouse.shelves.front();
    double pitch_y = *std::min_element(shelf.column_pitch_m.begin(), shelf.column_pitch_m.end());
    double pitch_z = *std::min_element(shelf.row_pitch_m.begin(), shelf.row_pitch_m.end());
    for (const std::optional<CellIndex>& cell : {metrics->target, metrics->truth.crossed}) {  // the crossed cell wins
      if (!cell) continue;
      const int level = cell->level, column = cell->column;
      if (column >= 1 && column <= static_cast<int>(shelf.column_pitch_m.size()) && level >= 1 &&
          level <= static_cast<int>(shelf.row_pitch_m.size())) {
        pitch_y = shelf.column_pitch_m[static_cast<size_t>(column - 1)];
        pitch_z = shelf.row_pitch_m[static_cast<size_t>(level - 1)];
      }
    }
    const double s_y = 0.5 * nominal.vehicle.size_m.y() + nominal.cosim.vehicle_margin_m;
    const double s_z = 0.5 * nominal.vehicle.size_m.z() + nominal.cosim.vehicle_margin_m;
    const double room_y = 0.5 * (pitch_y - shelf.post_thickness_m) - s_y - std::abs(e_y);
    // A deck (warehouse.hpp) raises the opening's floor: its clear height loses the deck's
    // thickness t and its centre rises t / 2 above the cell centre.
    const double t = shelf.deck_thickness_m;
    const double room_z = 0.5 * (pitch_z - shelf.beam_thickness_m - t) - s_z - std::abs(e_z - 0.5 * t);
    m.crossing_m = std::min(room_y, room_z);
  }
  // Mission: a success by the share of the timeout left (0 for one that landed in the grace
  // after it, RunContext::limit_ns: a success, with no time to spare); a failure by the share of
  // the shelves not crossed through the target (-1 to -0.1).
  if (outcome == "success") {
    m.mission = metrics ? std::max(0.0, 1.0 - metrics->mission_time_s / nominal.cosim.timeout_s) : kNaN;
  } else {
    const double shelves = metrics ? std::max(1.0, static_cast<double>(metrics->shelves)) : 1.0;
    const double crossed = metrics ? static_cast<double>(metrics->shelves_crossed_target) : 0.0;
    m.mission = -(1.0 - 0.9 * std::clamp(crossed / shelves, 0.0, 1.0));
  }
  return m;
}

}  // namespace shelfcross::verification
