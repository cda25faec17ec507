#include "flight_sw/perception/grid.hpp"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <limits>
#include <map>
#include <string>

#include "shelfcross/rotation.hpp"

namespace shelfcross::flight_sw {

GridLimits grid_limits(double w, double h) {
  assert(w > 0.0 && h > 0.0);
  const double diag = std::hypot(w, h);
  const double lo = std::min(w, h);
  GridLimits l;
  if (w >= h) {
    l.dx_lim_px = lo * lo / diag;
    l.dy_lim_px = w * h / diag;
  } else {
    l.dx_lim_px = w * h / diag;
    l.dy_lim_px = lo * lo / diag;
  }
  l.theta_lim_rad = std::atan(lo / std::max(w, h));
  return l;
}

GridLimits grid_limits(const KnownShelf& shelf, double px_per_m) {
  const auto [w_min, w_max] = std::minmax_element(shelf.column_pitch_m.begin(), shelf.column_pitch_m.end());
  const auto [h_min, h_max] = std::minmax_element(shelf.row_pitch_m.begin(), shelf.row_pitch_m.end());
  // Eq. 3-4 generalised. A row's chain must take its co-row neighbour, up to W
  // away (the widest column), at |dy| = W sin(theta), and never a point of the next row, whose
  // offset h cos(theta) - w sin(theta) (the diagonal neighbour) vanishes first for the lowest
  // row h_min over the widest column: theta < atan(h_min / W). Columns alike:
  // theta < atan(w_min / H). So theta_L = min(atan(h_min / W), atan(w_min / H)) and the windows
  // are the co-line offsets at theta_L: dy_lim = W sin(theta_L), dx_lim = H sin(theta_L).
  // For a uniform grid this is eq. 3-4 exactly (w >= h: theta_L = atan(h / w),
  // dy_lim = w h / sqrt(w^2 + h^2), dx_lim = h^2 / sqrt(w^2 + h^2)); eq. 3 with the largest
  // pitches alone gave rows of 0.30 m under columns of 0.52 m (W H / sqrt(W^2 + H^2) = 0.33 m
  // with H = 0.42 m) a row window wider than a row: theta_L = 0, every view refused.
  GridLimits l;
  l.theta_lim_rad = std::min(std::atan(*h_min / *w_max), std::atan(*w_min / *h_max));
  l.dy_lim_px = *w_max * px_per_m * std::sin(l.theta_lim_rad);
  l.dx_lim_px = *h_max * px_per_m * std::sin(l.theta_lim_rad);
  return l;
}

namespace {

// Eq. 2 along one axis: chains of points, each the nearest along `a` (strictly ahead) within
// |b_Q - b_P| <= lim of the previous one. Starts from the unassigned point with the smallest
// `a` (the corner end of its line). a = x, b = y for rows; a = y, b = x for columns.
template <class A, class B>
std::vector<std::vector<int>> stair_chains(const std::vector<cv::Point2d>& p, A a, B b, double lim) {
  const size_t n = p.size();
  std::vector<int> order(n);
  for (size_t i = 0; i < n; ++i) order[i] = static_cast<int>(i);
  std::stable_sort(order.begin(), order.end(), [&](int i, int j) { return a(p[i]) < a(p[j]); });
  std::vector<char> used(n, 0);
  std::vector<std::vector<int>> chains;
  for (int start : order) {
    if (used[start]) continue;
    std::vector<int> chain{start};
    used[start] = 1;
    int cur = start;
    for (;;) {
      int best = -1;
      double best_da = std::numeric_limits<double>::infinity();
      for (int q : order) {
        if (used[q]) continue;
        const double da = a(p[q]) - a(p[cur]);
        if (da <= 0.0 || std::abs(b(p[q]) - b(p[cur])) > lim) continue;
        if (da < best_da) {
          best_da = da;
          best = q;
        }
      }
      if (best < 0) break;
      chain.push_back(best);
      used[best] = 1;
      cur = best;
    }
    chains.push_back(std::move(chain));
  }
  return chains;
}

}  // namespace

TagGrid classify_grid(const std::vector<cv::Point2d>& pts, const GridLimits& lim,
                      double orthogonality_tolerance_rad) {
  TagGrid g;
  const size_t n = pts.size();
  g.row.assign(n, -1);
  g.column.assign(n, -1);
  if (n == 0) {
    g.refusal = "no tags";
    return g;
  }
  auto px = [](const cv::Point2d& q) { return q.x; };
  auto py = [](const cv::Point2d& q) { return q.y; };
  const auto rows = stair_chains(pts, px, py, lim.dy_lim_px);
  const auto cols = stair_chains(pts, py, px, lim.dx_lim_px);

  // Rotation from the summed chain steps: rows run along u = (cos t, sin t), columns (top to
  // bottom) along v = (-sin t, cos t).
  cv::Point2d row_sum(0, 0), col_sum(0, 0);
  int row_steps = 0, col_steps = 0;
  for (const auto& c : rows) {
    for (size_t k = 1; k < c.size(); ++k, ++row_steps) row_sum += pts[c[k]] - pts[c[k - 1]];
  }
  for (const auto& c : cols) {
    for (size_t k = 1; k < c.size(); ++k, ++col_steps) col_sum += pts[c[k]] - pts[c[k - 1]];
  }
  const double theta_r = row_steps ? std::atan2(row_sum.y, row_sum.x) : 0.0;
  const double theta_c = col_steps ? std::atan2(-col_sum.x, col_sum.y) : 0.0;
  auto deg = [](double r) { return std::to_string(rad_to_deg(r)); };
  if (std::abs(theta_r) >= lim.theta_lim_rad || std::abs(theta_c) >= lim.theta_lim_rad) {
    g.refusal = "grid rotated past the limit angle (rows " + deg(theta_r) + " deg, columns " +
                deg(theta_c) + " deg, limit " + deg(lim.theta_lim_rad) + " deg)";
    return g;
  }
  if (row_steps && col_steps && std::abs(theta_r - theta_c) > orthogonality_tolerance_rad) {
    g.refusal = "row and column directions disagree (" + deg(theta_r) + " vs " + deg(theta_c) +
                " deg): rotation near or past the limit";
    return g;
  }
  const double t = row_steps && col_steps ? 0.5 * (theta_r + theta_c) : (row_steps ? theta_r : theta_c);
  g.rotation_rad = t;
  const cv::Point2d u(std::cos(t), std::sin(t)), v(-std::sin(t), std::cos(t));

  // Order the lines: rows by their mean along v (largest = lowest in the image = row 0),
  // columns by their mean along u (smallest = leftmost = column 0).
  auto order_lines = [&](const std::vector<std::vector<int>>& lines, const cv::Point2d& axis,
                         bool descending, std::vector<int>& label) {
    std::vector<std::pair<double, size_t>> key;
    for (size_t i = 0; i < lines.size(); ++i) {
      double s = 0.0;
      for (int k : lines[i]) s += pts[k].dot(axis);
      s /= static_cast<double>(lines[i].size());
      key.emplace_back(descending ? -s : s, i);
    }
    std::sort(key.begin(), key.end());
    for (size_t rank = 0; rank < key.size(); ++rank) {
      for (int k : lines[key[rank].second]) label[k] = static_cast<int>(rank);
    }
  };
  order_lines(rows, v, true, g.row);
  order_lines(cols, u, false, g.column);
  g.rows = static_cast<int>(rows.size());
  g.columns = static_cast<int>(cols.size());

  // Consistency: one point per (row, column); columns increase along each row chain and rows
  // decrease (upward is +row) along each column chain (top to bottom).
  g.index.assign(static_cast<size_t>(g.rows * g.columns), -1);
  for (size_t k = 0; k < n; ++k) {
    int& slot = g.index[static_cast<size_t>(g.row[k] * g.columns + g.column[k])];
    if (slot >= 0) {
      g.refusal = "two tags on one grid position: classification inconsistent";
      return g;
    }
    slot = static_cast<int>(k);
  }
  for (const auto& c : rows) {
    for (size_t k = 1; k < c.size(); ++k) {
      if (g.column[c[k]] <= g.column[c[k - 1]]) {
        g.refusal = "row chain crosses columns backwards: classification inconsistent";
        return g;
      }
    }
  }
  for (const auto& c : cols) {
    for (size_t k = 1; k < c.size(); ++k) {
      if (g.row[c[k]] >= g.row[c[k - 1]]) {
        g.refusal = "column chain crosses rows backwards: classification inconsistent";
        return g;
      }
    }
  }
  g.valid = true;
  return g;
}

std::optional<std::array<int, 4>> cell_corner_indices(const TagGrid& grid, int r, int c) {
  if (!grid.valid || r < 0 || c < 0 || r + 1 >= grid.rows || c + 1 >= grid.columns) {
    return std::nullopt;
  }
  const std::array<int, 4> idx{grid.at(r, c), grid.at(r, c + 1), grid.at(r + 1, c + 1),
                               grid.at(r + 1, c)};
  for (int i : idx) {
    if (i < 0) return std::nullopt;
  }
  return idx;
}

}  // namespace shelfcross::flight_sw
