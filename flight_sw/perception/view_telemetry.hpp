#pragma once
// What the shelf survey saw of the front shelf, for the telemetry (mission/telemetry.hpp).

#include <string>
#include <vector>

#include <Eigen/Core>
#include <opencv2/core.hpp>

namespace shelfcross::flight_sw {

/// One tag of the last analysed frame.
struct TagTelemetry {
  cv::Point2d centre_px;
  double area_px = 0.0;
  int tag_row = -1;     ///< -1 when not classified
  int tag_column = -1;
};

/// What the shelf survey saw (ShelfSurvey: FindShelf, GoToViewpoint, TakeInventory, and the
/// approach's re-acquisition): the last analysed view.
struct ViewTelemetry {
  std::vector<TagTelemetry> tags;
  bool grid_valid = false;
  int grid_rows = 0;
  int grid_columns = 0;
  bool full_view = false;
  std::string grid_refusal;
  int markers_seen = 0;
  Eigen::Vector3d e1_G_m = Eigen::Vector3d::Zero();  ///< to the optimal viewpoint
};

}  // namespace shelfcross::flight_sw
