#include "verification/margin.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace shelfcross::verification {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

double number_or_nan(const nlohmann::json& j, const char* key) {
  const auto it = j.find(key);
  return it != j.end() && it->is_number() ? it->get<double>() : kNaN;
}

}  // namespace

const char* failure_class_name(FailureClass c) {
  switch (c) {
    case FailureClass::contact: return "contact";
    case FailureClass::crossing: return "crossing";
    case FailureClass::mission: return "mission";
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
  }
  return kNaN;
}

RunMargins run_margins(const Scenario& nominal, const std::string& outcome, const nlohmann::json& metrics) {
  RunMargins m;
  // Contact.
  const auto contact = metrics.find("contact");
  if (contact != metrics.end() && contact->is_object()) {
    m.contact_m = std::min(-number_or_nan(*contact, "depth_m"), -1e-6);
    if (std::isnan(m.contact_m)) m.contact_m = -1e-6;
  } else if (outcome == "left_arena" || outcome == "collision") {
    m.contact_m = -1e-6;  // left the arena box without a recorded contact
  } else {
    m.contact_m = number_or_nan(metrics, "min_clearance_m");
  }
  // Crossing: the room at the entered cell's front face.
  const double e_y = number_or_nan(metrics, "entry_offset_y_m");
  const double e_z = number_or_nan(metrics, "entry_offset_z_m");
  m.crossing_m = kNaN;
  if (!std::isnan(e_y) && !std::isnan(e_z) && !nominal.warehouse.shelves.empty()) {
    const ShelfSpec& shelf = nominal.warehouse.shelves.front();
    double pitch_y = *std::min_element(shelf.column_pitch_m.begin(), shelf.column_pitch_m.end());
    double pitch_z = *std::min_element(shelf.row_pitch_m.begin(), shelf.row_pitch_m.end());
    for (const char* key : {"target", "crossed"}) {  // the crossed cell wins over the target
      const auto cell = metrics.find(key);
      if (cell == metrics.end() || !cell->is_object()) continue;
      const int level = cell->value("level", 0), column = cell->value("column", 0);
      if (column >= 1 && column <= static_cast<int>(shelf.column_pitch_m.size()) && level >= 1 &&
          level <= static_cast<int>(shelf.row_pitch_m.size())) {
        pitch_y = shelf.column_pitch_m[static_cast<size_t>(column - 1)];
        pitch_z = shelf.row_pitch_m[static_cast<size_t>(level - 1)];
      }
    }
    const double s_y = 0.5 * nominal.vehicle.size_m.y() + nominal.cosim.vehicle_margin_m;
    const double s_z = 0.5 * nominal.vehicle.size_m.z() + nominal.cosim.vehicle_margin_m;
    const double room_y = 0.5 * (pitch_y - shelf.post_thickness_m) - s_y - std::abs(e_y);
    const double room_z = 0.5 * (pitch_z - shelf.beam_thickness_m) - s_z - std::abs(e_z);
    m.crossing_m = std::min(room_y, room_z);
  }
  // Mission.
  if (outcome == "success") {
    m.mission = 1.0 - number_or_nan(metrics, "mission_time_s") / nominal.cosim.timeout_s;
  } else {
    const double shelves = std::max(1.0, metrics.value("shelves", 1.0));
    const double crossed = metrics.value("shelves_crossed_target", 0.0);
    m.mission = -(1.0 - 0.9 * std::clamp(crossed / shelves, 0.0, 1.0));
  }
  return m;
}

}  // namespace shelfcross::verification
