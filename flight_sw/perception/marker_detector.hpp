#pragma once
// The boxes' ArUco markers (paper section 3, docs/method.md section 2): OpenCV's detector with
// the configured dictionary, for the whole frame (reference pipeline) or the shelf's cells
// (fast pipeline).

#include <array>
#include <optional>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

// The detector's dictionary and parameters, declared as opencv2/aruco.hpp does: held by
// pointer here, so only marker_detector.cpp reads the aruco module's headers.
namespace cv::aruco {
class Dictionary;
struct DetectorParameters;
}  // namespace cv::aruco

namespace shelfcross::flight_sw {

/// OpenCV's id of a predefined ArUco dictionary name ("DICT_4X4_50", ...); empty if unknown.
std::optional<int> aruco_dictionary_id(const std::string& name);

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
  /// Throws std::invalid_argument for a dictionary name OpenCV does not predefine.
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

}  // namespace shelfcross::flight_sw
