#include "verification/report/crossing_push.hpp"

#include <algorithm>
#include <cmath>

#include <Eigen/Geometry>

#include "shelfcross/warehouse.hpp"

namespace shelfcross::verification {

std::optional<double> crossing_push_m(const Scenario& scenario, const StoredMetrics& metrics, const StoredTrace& trace) {
  if (!metrics.run || !metrics.run->truth.crossed || scenario.warehouse.shelves.empty()) return std::nullopt;
  const ShelfSpec& shelf = scenario.warehouse.shelves.front();
  const CellIndex& cell = *metrics.run->truth.crossed;
  const double y_centre_S_m = cell_centre_S_m(shelf, cell.level, cell.column).y();
  const double half_length_m = 0.5 * scenario.vehicle.size_m.x();
  const Eigen::Isometry3d X_SW = shelf_pose_W(shelf).inverse();
  // Passes through the shelf's depth, in time order; the push is that of the last one that
  // reached mid-depth.
  std::optional<double> push_m, pass_push_m;
  bool pass_reached_middle = false;
  const auto end_pass = [&] {
    if (pass_push_m && pass_reached_middle) push_m = pass_push_m;
    pass_push_m.reset();
    pass_reached_middle = false;
  };
  for (std::size_t k = 0; k < trace.t_s.size(); ++k) {
    const Eigen::Vector3d p_S = X_SW * Eigen::Vector3d(trace.x_W_m[k], trace.y_W_m[k], trace.z_W_m[k]);
    const bool inside = p_S.x() >= -half_length_m && p_S.x() <= shelf.depth_m + half_length_m;  // false for NaN
    if (!inside) {
      end_pass();
      continue;
    }
    pass_reached_middle = pass_reached_middle || p_S.x() >= 0.5 * shelf.depth_m;
    pass_push_m = std::max(pass_push_m.value_or(0.0), std::abs(p_S.y() - y_centre_S_m));
  }
  end_pass();
  return push_m;
}

double crossing_room_m(const Scenario& scenario, int column) {
  const ShelfSpec& shelf = scenario.warehouse.shelves.front();
  const double pitch_m = shelf.column_pitch_m[static_cast<std::size_t>(column - 1)];  // post centre to post centre
  return 0.5 * pitch_m - 0.5 * shelf.post_thickness_m - 0.5 * scenario.vehicle.size_m.y();
}

}  // namespace shelfcross::verification
