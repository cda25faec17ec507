#pragma once
// Test helper for the mission's tests: the scene they fly to (the paper's test shelf 3 m ahead
// of the take-off point, a box in five of its cells, a second shelf 2.6 m behind it) and the
// pictures the camera takes of it from a body pose (shelf_drawing.hpp), stamped as the
// flight software gets them.

#include <utility>
#include <vector>

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include "flight_sw/config.hpp"
#include "flight_sw/perception/shelf_view.hpp"
#include "flight_sw/test/shelf_drawing.hpp"

namespace shelfcross::flight_sw::testing {

/// The front shelf's boxes (level, column, marker id): the empty cells between them are the
/// crossable ones (L2 C3 nearest the image centre from the viewpoint).
inline std::vector<DrawnBox> front_boxes() { return {{2, 2, 4}, {3, 2, 9}, {3, 3, 17}, {1, 1, 21}, {4, 4, 30}}; }

/// A box in every cell of the paper's 4 x 4 shelf: no empty cell to cross.
inline std::vector<DrawnBox> every_cell_boxed() {
  std::vector<DrawnBox> boxes;
  for (int level = 1; level <= 4; ++level) {
    for (int column = 1; column <= 4; ++column) boxes.push_back({level, column, 4 * (level - 1) + column});
  }
  return boxes;
}

/// Hovering in front of the mission scene's shelf, its whole grid in view, heading into it.
inline const Eigen::Vector3d kInFront_W_m(1.1, 0.0, 0.98);

/// The front shelf at x = 3 m with `boxes`, and the shelf behind it at x = 5.6 m with one box.
inline Scene mission_scene(std::vector<DrawnBox> boxes = front_boxes()) {
  DrawnShelf front = paper_shelf({3.0, 0.0, 0.0});
  front.boxes = std::move(boxes);
  DrawnShelf behind = paper_shelf({5.6, 0.0, 0.0});
  behind.boxes = {{2, 3, 44}};
  Scene scene;
  scene.shelves = {front, behind};
  return scene;
}

/// The camera of `config` (its lens distortion, its mount) over `scene`.
class SceneCamera {
 public:
  SceneCamera(const FlightConfig& config, Scene scene) : config_(config), scene_(std::move(scene)), drawer_(config.camera, true) {}
  /// What the camera sees from the body at p_WB_m with heading yaw_rad, level.
  cv::Mat draw(const Eigen::Vector3d& p_WB_m, double yaw_rad = 0.0) const {
    return drawer_.draw(scene_, camera_pose_W(p_WB_m, yaw_rad, 0.0, 0.0, config_.mount));
  }
  /// A bare wall: no shelf in view.
  cv::Mat wall() const {
    return cv::Mat(config_.camera.height_px, config_.camera.width_px, CV_8UC3, cv::Scalar(185, 185, 180));
  }

 private:
  const FlightConfig& config_;
  Scene scene_;
  Drawer drawer_;
};

/// A whole picture of `bgr` stamped t_ns (it decides and steers).
inline Picture whole_picture(const cv::Mat& bgr, TimeNs t_ns) { return Picture{bgr, t_ns}; }

}  // namespace shelfcross::flight_sw::testing
