#pragma once
// The paper's test shelf (docs/method.md, Table 3) as a Warehouse, for render/ tests: 4 x 4 cells,
// columns 0.34, 0.48, 0.34, 0.48 m, rows 0.34 m, depth 0.34 m, base height 0.30 m, 6 cm tags,
// 10 cm DICT_4X4_50 markers on 0.22 m boxes in a few cells, shelf origin at x = 3 m.

#include <cmath>

#include "shelfcross/camera.hpp"
#include "shelfcross/warehouse.hpp"

namespace shelfcross::render::test {

inline Warehouse paper_test_shelf() {
  Warehouse w;
  ShelfSpec s;
  s.name = "paper_test_shelf";
  s.origin_W_m = Eigen::Vector3d(3.0, 0.0, 0.0);
  s.column_pitch_m = {0.34, 0.48, 0.34, 0.48};
  s.row_pitch_m = {0.34, 0.34, 0.34, 0.34};
  s.base_height_m = 0.30;
  s.depth_m = 0.34;
  s.boxes = {{1, 1, 3}, {2, 3, 7}, {3, 2, 12}, {4, 4, 21}, {1, 4, 42}};
  w.shelves.push_back(s);
  w.tag_size_m = 0.06;
  w.marker_size_m = 0.10;
  w.aruco_dictionary = "DICT_4X4_50";
  w.box_size_m = Eigen::Vector3d(0.22, 0.22, 0.22);
  return w;
}

/// Camera pose looking along +x_W (the approach direction) from p_WC, rotated by yaw (about
/// z_W, + left) and pitch (+ down) : X_WC = [R_z(yaw) R_y(pitch) R_BC0 | p].
inline Eigen::Isometry3d camera_looking_forward(const Eigen::Vector3d& p_WC_m, double yaw_rad = 0.0,
                                                double pitch_rad = 0.0) {
  Eigen::Isometry3d X_WC = Eigen::Isometry3d::Identity();
  X_WC.linear() = Eigen::AngleAxisd(yaw_rad, Eigen::Vector3d::UnitZ()).toRotationMatrix() *
                  rotation_body_from_camera(pitch_rad);
  X_WC.translation() = p_WC_m;
  return X_WC;
}

}  // namespace shelfcross::render::test
