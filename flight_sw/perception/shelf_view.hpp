#pragma once
// Perception of one picture (paper section 3, docs/method.md section 2): what a picture is
// worth, and what one frame shows of the front shelf: its tags after eq. 1, their scale and
// grid, and the boxes' markers assigned to its cells.
//
// Image coordinates are OpenCV's: x right, y down, pixels, pixel centres at integer
// coordinates (the convention of cv::projectPoints and of blob moments).

#include <array>
#include <utility>
#include <vector>

#include <opencv2/core.hpp>

#include "flight_sw/config.hpp"
#include "flight_sw/perception/grid.hpp"
#include "flight_sw/perception/marker_detector.hpp"
#include "flight_sw/perception/tag_detector.hpp"
#include "shelfcross/camera.hpp"
#include "shelfcross/cell_index.hpp"
#include "shelfcross/time.hpp"

namespace shelfcross::flight_sw {

/// One picture as the phases see it: the image and what it is worth, decided once when it
/// arrives (flight_sw/README.md, "Damaged pictures") and handed to every step that uses it.
struct Picture {
  const cv::Mat& bgr;
  TimeNs t_ns = 0;         ///< its stamp (receive time)
  int damage_events = 0;   ///< lost bands since its key frame; 0: whole
  bool decides = true;     ///< damage_events <= perception.decide_max_damage_events
  /// Where a damaged picture may be damaged (CameraFrame::damaged_rows); null or empty: nowhere.
  const std::vector<RowSpan>* damaged_rows = nullptr;
  bool whole() const { return damage_events == 0; }
};

/// Whether any of `rows` overlaps the picture rows (top_px, bottom_px).
bool rows_touch(const std::vector<RowSpan>& rows, double top_px, double bottom_px);

/// What one frame shows of the front shelf.
struct ShelfView {
  std::vector<TagBlob> tags;  ///< front-shelf tags (after eq. 1)
  double largest_tag_area_px = 0.0;
  double px_per_m = 0.0;
  TagGrid grid;
  bool full = false;  ///< the whole known grid is in view and classified
};

/// Analyses a whole frame: tags, eq. 1, scale, grid. `full` when the grid has exactly the
/// known (columns + 1) x (levels + 1) tags.
void analyse_shelf(const cv::Mat& bgr, TagDetector& detector, const FlightConfig& config,
                   ShelfView& view);

/// Markers of boxes on the front shelf (eq. 1 on marker area against the area expected at the
/// front tags' scale) assigned to the cell whose four corner tags enclose their centre.
/// `view` must be full. Returns (cell, marker id) pairs.
std::vector<std::pair<CellIndex, int>> assign_markers(const ShelfView& view,
                                                      const std::vector<MarkerSighting>& markers,
                                                      const FlightConfig& config);

/// Image quadrilateral of a cell of a full view (bottom-left, bottom-right, top-right,
/// top-left tag centres). The view must be full and the cell on its grid (asserted).
std::array<cv::Point2d, 4> cell_quad(const ShelfView& view, CellIndex cell);


}  // namespace shelfcross::flight_sw
