#pragma once
// The stair classification of the tag grid (paper eq. 2 with the limits of eq. 3 and 4,
// docs/method.md section 2).
//
// Grid indices: tag row 0 is the lowest row of tags in view, tag column 0 the leftmost (as
// seen on approach). With the whole grid in view, tag row j is beam j of the shelf (beam 0 the
// lowest) and tag column i is post i (post 0 the leftmost); cell (level L, column C), both
// from 1, lies between tag rows L-1, L and tag columns C-1, C.

#include <array>
#include <optional>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "flight_sw/config.hpp"

namespace shelfcross::flight_sw {

/// The stair-classification windows and the rotation up to which they work.
struct GridLimits {
  double dx_lim_px = 0.0;      ///< column window: |x_Q - x_P| <= dx_lim
  double dy_lim_px = 0.0;      ///< row window: |y_Q - y_P| <= dy_lim
  double theta_lim_rad = 0.0;  ///< largest grid rotation classified correctly
};

/// Eq. 3 and 4 for a uniform grid of column spacing w and row spacing h (same unit):
///   w >= h: dx_lim = h^2 / sqrt(w^2+h^2), dy_lim = w h / sqrt(w^2+h^2)
///   w <  h: dx_lim = w h / sqrt(w^2+h^2), dy_lim = w^2 / sqrt(w^2+h^2)
///   theta_L = atan(min(w,h) / max(w,h)).
/// w and h must be > 0 (asserted).
GridLimits grid_limits(double w, double h);

/// Limits for the known (possibly non-uniform) shelf at `px_per_m`: eq. 3-4 generalised,
/// theta_L = min(atan(h_min / w_max), atan(w_min / h_max)) (the flattest diagonal of a cell,
/// where a point of the next row or column first comes level), dy_lim = w_max sin(theta_L),
/// dx_lim = h_max sin(theta_L) (the farthest co-row / co-column neighbour at theta_L). For a
/// uniform grid this is eq. 3-4 exactly.
GridLimits grid_limits(const KnownShelf& shelf, double px_per_m);

/// The result of the stair classification of a set of points.
struct TagGrid {
  bool valid = false;
  std::string refusal;      ///< why not valid
  std::vector<int> row;     ///< per input point: tag row, 0 = lowest
  std::vector<int> column;  ///< per input point: tag column, 0 = leftmost
  int rows = 0;
  int columns = 0;
  double rotation_rad = 0.0;  ///< image angle of the rows, atan2(dy, dx), y down
  std::vector<int> index;     ///< rows x columns, row-major: point index or -1

  int at(int tag_row, int tag_column) const {
    return index[static_cast<size_t>(tag_row * columns + tag_column)];
  }
};

/// Eq. 2: rows by chaining from the leftmost unassigned point to the nearest (in x) point to
/// its right within |dy| <= dy_lim, until none is left; columns alike from the topmost point
/// downward within |dx| <= dx_lim. Refuses (valid = false, never a guess) when the grid is
/// rotated by theta_L or more, when the row and column directions disagree by more than
/// `orthogonality_tolerance_rad`, or when two points fall on one (row, column).
TagGrid classify_grid(const std::vector<cv::Point2d>& points_px, const GridLimits& limits,
                      double orthogonality_tolerance_rad);

/// Corner tag points of cell (tag row r, tag column c)..(r+1, c+1) in the order
/// bottom-left, bottom-right, top-right, top-left (as seen on approach); empty if one is
/// missing from the grid.
std::optional<std::array<int, 4>> cell_corner_indices(const TagGrid& grid, int tag_row,
                                                      int tag_column);

}  // namespace shelfcross::flight_sw
