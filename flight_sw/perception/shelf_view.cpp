#include "flight_sw/perception/shelf_view.hpp"

#include <algorithm>
#include <cassert>
#include <cmath>

#include <opencv2/imgproc.hpp>

namespace shelfcross::flight_sw {

bool rows_touch(const std::vector<RowSpan>& rows, double top_px, double bottom_px) {
  return std::any_of(rows.begin(), rows.end(),
                     [&](const RowSpan& r) { return r.v_begin_px < bottom_px && r.v_end_px > top_px; });
}


void analyse_shelf(const cv::Mat& bgr, TagDetector& detector, const FlightConfig& config,
                   ShelfView& view) {
  view.tags.clear();
  view.full = false;
  view.grid = TagGrid{};
  detector.detect(bgr, cv::Rect(0, 0, bgr.cols, bgr.rows), view.tags);
  view.largest_tag_area_px = keep_front_shelf(view.tags, config.perception.area_ratio_threshold);
  view.px_per_m = tag_scale_px_per_m(view.tags, config.shelf);
  if (view.tags.empty()) {
    view.grid.refusal = "no tags";
    return;
  }
  std::vector<cv::Point2d> pts;
  pts.reserve(view.tags.size());
  for (const TagBlob& b : view.tags) pts.push_back(b.centre_px);
  view.grid = classify_grid(pts, grid_limits(config.shelf, view.px_per_m),
                            config.perception.grid_orthogonality_tolerance_rad);
  const int expect_rows = config.shelf.levels() + 1, expect_cols = config.shelf.columns() + 1;
  const size_t expect = static_cast<size_t>(expect_rows * expect_cols);
  // A shelf behind, seen from afar: eq. 1 keeps its tags when r / (r + d) > sqrt(0.45) (from
  // 3.5 m, a shelf up to 1.7 m behind), and the grid then holds more tags than the known
  // shelf has. The front shelf's tags are the nearer ones: with the vehicle turned by up to
  // psi, they lie within r +- (W/2) sin(psi) and those of a shelf d behind beyond
  // r + d - (W/2) sin(psi), so for d > W sin(psi) (1.2 m > 1.7 m x sin 20 deg = 0.58 m) the
  // known number of largest tags are the front shelf's. They are kept only if they then
  // classify as the whole known grid; otherwise the view stays as it was (not full).
  if (!(view.grid.valid && view.grid.rows == expect_rows && view.grid.columns == expect_cols) && view.tags.size() > expect) {
    std::vector<double> areas;
    for (const TagBlob& b : view.tags) areas.push_back(b.area_px);
    std::nth_element(areas.begin(), areas.begin() + static_cast<std::ptrdiff_t>(expect - 1), areas.end(), std::greater<>());
    const double smallest_kept = areas[expect - 1];
    std::vector<TagBlob> front;
    for (const TagBlob& b : view.tags) {
      if (b.area_px >= smallest_kept) front.push_back(b);
    }
    if (front.size() == expect) {
      std::vector<cv::Point2d> front_pts;
      for (const TagBlob& b : front) front_pts.push_back(b.centre_px);
      const double px_per_m = tag_scale_px_per_m(front, config.shelf);
      TagGrid grid = classify_grid(front_pts, grid_limits(config.shelf, px_per_m),
                                   config.perception.grid_orthogonality_tolerance_rad);
      if (grid.valid && grid.rows == expect_rows && grid.columns == expect_cols) {
        view.tags = std::move(front);
        view.px_per_m = px_per_m;
        view.grid = std::move(grid);
      }
    }
  }
  if (!view.grid.valid) return;
  view.full = view.grid.rows == expect_rows && view.grid.columns == expect_cols &&
              static_cast<int>(view.tags.size()) == expect_rows * expect_cols;
}

std::array<cv::Point2d, 4> cell_quad(const ShelfView& view, CellIndex cell) {
  const auto idx = cell_corner_indices(view.grid, cell.level - 1, cell.column - 1);
  assert(idx);
  std::array<cv::Point2d, 4> q;
  for (size_t k = 0; k < 4; ++k) q[k] = view.tags[static_cast<size_t>((*idx)[k])].centre_px;
  return q;
}

std::vector<std::pair<CellIndex, int>> assign_markers(const ShelfView& view,
                                                      const std::vector<MarkerSighting>& markers,
                                                      const FlightConfig& config) {
  assert(view.full);
  std::vector<std::pair<CellIndex, int>> out;
  const double side = config.shelf.marker_size_m * view.px_per_m;
  const double expected_area = side * side;
  for (const MarkerSighting& m : markers) {
    if (m.area_px < config.perception.marker_area_ratio_threshold * expected_area) continue;
    for (int level = 1; level <= config.shelf.levels(); ++level) {
      for (int column = 1; column <= config.shelf.columns(); ++column) {
        const auto q = cell_quad(view, {level, column});
        const std::vector<cv::Point2f> poly(q.begin(), q.end());
        if (cv::pointPolygonTest(poly, cv::Point2f(m.centre_px), false) > 0) {
          out.push_back({{level, column}, m.id});
        }
      }
    }
  }
  return out;
}

}  // namespace shelfcross::flight_sw
