#pragma once
// Perception (paper section 3, docs/method.md section 2): colour tags, the front-shelf test of
// eq. 1, the stair classification of the tag grid (eq. 2 with the limits of eq. 3 and 4),
// ArUco markers and their cells.
//
// Image coordinates are OpenCV's: x right, y down, pixels, pixel centres at integer
// coordinates (the convention of cv::projectPoints and of blob moments).
// Grid indices: tag row 0 is the lowest row of tags in view, tag column 0 the leftmost (as
// seen on approach). With the whole grid in view, tag row j is beam j of the shelf (beam 0 the
// lowest) and tag column i is post i (post 0 the leftmost); cell (level L, column C), both
// from 1, lies between tag rows L-1, L and tag columns C-1, C.

#include <array>
#include <cstdint>
#include <deque>
#include <optional>
#include <string>
#include <vector>

#include <opencv2/aruco.hpp>
#include <opencv2/core.hpp>

#include "flight_sw/config.hpp"
#include "shelfcross/camera.hpp"
#include "shelfcross/cell_index.hpp"
#include "shelfcross/time.hpp"

namespace shelfcross::flight_sw {

/// OpenCV's id of a predefined ArUco dictionary name ("DICT_4X4_50", ...); empty if unknown.
std::optional<int> aruco_dictionary_id(const std::string& name);

/// One colour-tag blob.
struct TagBlob {
  cv::Point2d centre_px;  ///< centroid of the blob
  double area_px = 0.0;   ///< pixel count
  cv::Rect bbox_px;
};

/// Paper section 3 item 2: keep the tag colour (HSV range, hue may wrap through red), split
/// the mask into 8-connected blobs, reject blobs by area and shape (fill ratio, aspect).
/// Keeps its buffers between calls so that a steady stream of frames allocates nothing.
///
/// Two implementations, chosen by params.pipeline, giving the same blobs:
///  - reference: cv::cvtColor to HSV, cv::inRange, cv::connectedComponentsWithStats over the
///    whole window.
///  - fast: no HSV image and no full mask. The window is sampled every `stride` pixels
///    (rows and columns) with the exact colour test; each sample that passes seeds an
///    8-connected flood fill at full resolution with the same test, so a blob found is
///    measured exactly as connected components would (same pixels: same area, bounding box and
///    centroid, the latter from integer coordinate sums as OpenCV computes it). The colour
///    test is OpenCV's 8-bit BGR->HSV arithmetic (its division tables, rounding, hue sectors)
///    fused with the range test, bit-exact with cvtColor + inRange (checked on all 2^24
///    colours by the tests). A blob is missed only if no sample falls on it: never for a
///    solid tag of stride + 1 pixels a side or more.
///    Blobs come out in the order connected components numbers them (raster order of the
///    first 2 x 2 block, OpenCV's block-based 8-connected labelling).
class TagDetector {
 public:
  explicit TagDetector(const PerceptionParams& params);
  /// Appends to `out` the tags found inside `roi` of `bgr` (clipped to the image), in image
  /// coordinates. `stride` (fast pipeline only; 0: params.tag_seed_stride_px) is the seed
  /// sampling step.
  void detect(const cv::Mat& bgr, cv::Rect roi, std::vector<TagBlob>& out, int stride = 0);
  /// The fused colour test of one BGR pixel (fast pipeline's; exposed for tests).
  bool is_tag_colour(const std::uint8_t* bgr) const;

 private:
  void detect_reference(const cv::Mat& bgr, cv::Rect roi, std::vector<TagBlob>& out);
  void detect_fast(const cv::Mat& bgr, cv::Rect roi, std::vector<TagBlob>& out, int stride);

  PerceptionParams params_;
  cv::Mat hsv_, mask_, mask_wrap_, labels_, stats_, centroids_;
  // Fast pipeline: per-pixel state of the window (0 unseen, 1 not tag, 2 tag), the fill
  // stack, blobs with their label-order keys, and OpenCV's HSV division tables.
  cv::Mat1b seen_;
  std::vector<cv::Point> stack_;
  std::vector<std::pair<std::int64_t, TagBlob>> found_;
  std::array<int, 256> sdiv_{}, hdiv_{};
};

/// Eq. 1: R_A = S_T / L_T with S_T a tag's area and L_T the largest tag area in `blobs`; tags
/// with R_A < threshold belong to shelves behind the front one and are removed (order kept).
/// Returns L_T (0 when empty).
double keep_front_shelf(std::vector<TagBlob>& blobs, double threshold);

/// Image scale at the front tags, px per metre. With two tags or more: the median distance
/// from each tag to its nearest neighbour over the smallest pitch of the shelf (the nearest
/// neighbour in a grid is one smallest pitch away whatever the rotation, and spacing is
/// measured far more precisely than blob area). With one tag: sqrt(area) / tag side.
double tag_scale_px_per_m(const std::vector<TagBlob>& blobs, const KnownShelf& shelf);

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

/// One ArUco marker in an image.
struct MarkerSighting {
  int id = 0;
  std::array<cv::Point2f, 4> corners_px;
  cv::Point2d centre_px;
  double area_px = 0.0;
};

/// cv::aruco::detectMarkers with the configured dictionary; keeps its buffers.
class MarkerDetector {
 public:
  explicit MarkerDetector(const std::string& dictionary_name);
  /// Reference pipeline: the whole frame at full resolution, OpenCV's default thresholds,
  /// sub-pixel corner refinement.
  void detect(const cv::Mat& bgr, std::vector<MarkerSighting>& out);
  /// Fast pipeline: only inside `region` (the shelf's cells), with thresholds sized for
  /// markers of about `expected_side_px`: one adaptive-threshold window instead of three,
  /// candidate perimeters limited to at most 2.5 times the expected one, no corner refinement
  /// (only a marker's cell and its area against the 45 % threshold of eq. 1 are used: corners
  /// a pixel off change neither; the contour's half-pixel inset is undone). At full
  /// resolution: reading markers on a half-resolution image lost a box on the five-shelf
  /// scenario (seed 12, over the tops: 39 of 40 boxes; all 40 at full resolution).
  /// Candidates whose perimeter is too short for their area to reach `min_area_ratio` of the
  /// expected one (eq. 1 on markers, which assign_markers applies) are skipped.
  void detect_in(const cv::Mat& bgr, cv::Rect region, double expected_side_px, double min_area_ratio,
                 std::vector<MarkerSighting>& out);

 private:
  void collect(double scale, cv::Point2d offset, double grow_px, std::vector<MarkerSighting>& out);
  cv::Ptr<cv::aruco::Dictionary> dictionary_;
  cv::Ptr<cv::aruco::DetectorParameters> parameters_, fast_parameters_;
  cv::Mat gray_;
  std::vector<std::vector<cv::Point2f>> corners_, rejected_;
  std::vector<int> ids_;
};

/// The fast pipeline's tracker of the target's box (the box of its four corner tags):
/// between measurements the box moves at the image velocity, and grows at the rate, fitted by
/// least squares to its measurements of the last kRateWindow_s (per second of input stamps),
/// from the last measurement on; after `coast_s` without one it stays where it was last
/// measured. The stamps are receive times: over a lossy or jittery link pictures arrive in
/// bursts a millisecond apart, and a two-point difference over such a gap turns a few pixels
/// of measurement noise into hundreds of pixels a second that throw the search window off the
/// tags. Measurements spanning less than kRateMinSpan_s give no rate (the box stays).
class BoxTracker {
 public:
  void init(const cv::Rect2d& box, TimeNs t_ns);
  void correct(const cv::Rect2d& box, TimeNs t_ns);
  std::optional<cv::Rect2d> predict(TimeNs t_ns) const;
  static constexpr double kCoast_s = 0.5;
  static constexpr double kRateWindow_s = 0.2;   ///< six frame periods at 30 frames/s
  static constexpr double kRateMinSpan_s = 0.05;  ///< a frame and a half

 private:
  struct Measured {
    TimeNs t_ns;
    cv::Vec4d v;  ///< centre x, centre y, width, height
  };
  std::deque<Measured> recent_;  ///< the window's measurements, oldest first
  cv::Vec4d rate_per_s_{0, 0, 0, 0};  ///< d/dt of (centre x, centre y, width, height)
};

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
/// top-left tag centres).
std::array<cv::Point2d, 4> cell_quad(const ShelfView& view, CellIndex cell);

}  // namespace shelfcross::flight_sw
