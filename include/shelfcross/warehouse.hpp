#pragma once
// The warehouse as plant/ (collision), render/ (camera) and verification/ (metrics) all see
// it: ground truth. The flight software never receives this type; it gets its own "known
// geometry" configuration, built from it by verification/ or typed in by a Tello user.
//
// World frame W: x forward (toward the shelves), y left, z up, origin on the floor.
//
// Shelf frame S: origin on the floor, in the plane of the front face (the face the vehicle
// approaches), laterally at the centre of the tag grid; x_S points into the shelf (the
// approach direction), y_S left as seen on approach, z_S up. X_WS = (R_z(yaw_rad), origin_W_m).
//
// Grid: columns are counted from the left as seen on approach (column 1 at the largest y_S),
// levels from the floor (level 1 lowest). `column_pitch_m` and `row_pitch_m` are centre-line
// spacings of the posts and beams, so a cell's clear opening is its pitch less one post
// (width) or one beam (height) thickness. Tags sit at every post/beam intersection of both
// faces, on the outer surface, facing out.
//
// Structure of one shelf, all square-section bars:
//   posts: vertical, at each of the ncols+1 column boundaries, on the front and back faces,
//          from the floor to the top beam;
//   beams: horizontal along y_S, at each of the nrows+1 level boundaries, on both faces;
//   rails: horizontal along x_S, joining front and back at every post and level boundary;
//   decks (only where deck_thickness_m > 0, as real racking often has decking): a solid board
//          on every cell floor (level boundaries 0..nrows-1), resting on the beams and rails
//          (from z = beam_z_S_m(j) + T_b / 2 up by deck_thickness_m), spanning the shelf's width
//          between the outer posts' centre lines and its depth between the faces' centre lines.
// Cells are open front to back; a box stands on its cell's floor: the rails, or the deck on
// them (cell_floor_z_S_m).

#include <string>
#include <vector>

#include <Eigen/Geometry>

namespace shelfcross {

/// Linear RGB, each 0..1.
struct Rgb {
  double r = 0.0, g = 0.0, b = 0.0;
  bool operator==(const Rgb&) const = default;
};

/// A box in a cell, carrying one ArUco marker centred on its front face and one on its back.
struct BoxPlacement {
  int level = 1;      ///< 1 = lowest
  int column = 1;     ///< 1 = leftmost as seen on approach
  int marker_id = 0;  ///< ID in the warehouse's ArUco dictionary
  bool operator==(const BoxPlacement&) const = default;
};

struct ShelfSpec {
  std::string name;
  Eigen::Vector3d origin_W_m = Eigen::Vector3d::Zero();
  double yaw_rad = 0.0;
  std::vector<double> column_pitch_m;  ///< left to right as seen on approach
  std::vector<double> row_pitch_m;     ///< bottom to top
  double base_height_m = 0.30;         ///< centre line of the lowest beam above the floor
  double depth_m = 0.34;               ///< front-face to back-face centre lines
  double post_thickness_m = 0.02;
  double beam_thickness_m = 0.02;
  /// Solid decks: 0 none (open bars, the paper's shelf); > 0 a board this thick on every cell
  /// floor (see the file comment). A deck narrows each cell's clear height by its thickness.
  double deck_thickness_m = 0.0;
  std::vector<BoxPlacement> boxes;
  bool operator==(const ShelfSpec&) const = default;
};

struct Lighting {
  double ambient = 0.45;           ///< 0..1, fraction of albedo lit without direction
  double directional = 0.65;       ///< 0..1, intensity of the directional light
  Eigen::Vector3d direction_W = Eigen::Vector3d(0.4, -0.3, -1.0);  ///< light travel direction
  bool operator==(const Lighting&) const = default;
};

struct Warehouse {
  std::vector<ShelfSpec> shelves;
  // Tags: square, coloured, at every bar intersection of every shelf.
  Rgb tag_colour{0.10, 0.75, 0.20};
  double tag_size_m = 0.06;
  // Boxes: cardboard cubes centred in their cell, markers on front and back faces.
  Eigen::Vector3d box_size_m = Eigen::Vector3d(0.24, 0.24, 0.24);  ///< x_S depth, y_S width, z height
  Rgb box_colour{0.62, 0.46, 0.30};
  std::string aruco_dictionary = "DICT_4X4_50";  ///< OpenCV predefined dictionary name
  double marker_size_m = 0.10;                   ///< black border included
  // Room: floor everywhere, walls on the faces of this axis-aligned box (the arena).
  Eigen::Vector3d arena_min_W_m = Eigen::Vector3d(-2.0, -4.0, 0.0);
  Eigen::Vector3d arena_max_W_m = Eigen::Vector3d(6.0, 4.0, 3.0);
  Rgb floor_colour{0.35, 0.35, 0.38};
  Rgb wall_colour{0.80, 0.80, 0.78};
  Rgb bar_colour{0.15, 0.25, 0.55};
  Lighting lighting;
  bool operator==(const Warehouse&) const = default;
};

// ---- Conventions stated as functions (positions in the shelf frame S) ----

/// Lateral position y_S of the centre line of column boundary i (0 = left edge .. ncols).
/// Requires 0 <= i <= ncols (not checked: a larger i reads past column_pitch_m).
inline double post_y_S_m(const ShelfSpec& s, int i) {
  double width = 0.0;
  for (double w : s.column_pitch_m) width += w;
  double y = 0.5 * width;
  for (int k = 0; k < i; ++k) y -= s.column_pitch_m[static_cast<size_t>(k)];
  return y;
}

/// Height z_S of the centre line of level boundary j (0 = lowest beam .. nrows).
/// Requires 0 <= j <= nrows (not checked: a larger j reads past row_pitch_m).
inline double beam_z_S_m(const ShelfSpec& s, int j) {
  double z = s.base_height_m;
  for (int k = 0; k < j; ++k) z += s.row_pitch_m[static_cast<size_t>(k)];
  return z;
}

/// Centre of cell (level, column), both from 1, on the front-face plane x_S = 0. Requires
/// 1 <= level <= nrows and 1 <= column <= ncols (not checked, as above).
inline Eigen::Vector3d cell_centre_S_m(const ShelfSpec& s, int level, int column) {
  return {0.0, 0.5 * (post_y_S_m(s, column - 1) + post_y_S_m(s, column)),
          0.5 * (beam_z_S_m(s, level - 1) + beam_z_S_m(s, level))};
}

/// Height z_S of the floor of a cell of `level` (from 1): the top of the rails, or of the deck
/// on them. Requires 1 <= level <= nrows (not checked, as above).
inline double cell_floor_z_S_m(const ShelfSpec& s, int level) {
  return beam_z_S_m(s, level - 1) + 0.5 * s.beam_thickness_m + s.deck_thickness_m;
}

/// The clear height of a cell of `level` (from 1): its pitch less one beam and the deck.
inline double cell_clear_height_m(const ShelfSpec& s, int level) {
  return s.row_pitch_m[static_cast<size_t>(level - 1)] - s.beam_thickness_m - s.deck_thickness_m;
}

/// X_WS: shelf frame to world frame.
inline Eigen::Isometry3d shelf_pose_W(const ShelfSpec& s) {
  Eigen::Isometry3d X_WS = Eigen::Isometry3d::Identity();
  X_WS.linear() = Eigen::AngleAxisd(s.yaw_rad, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  X_WS.translation() = s.origin_W_m;
  return X_WS;
}

}  // namespace shelfcross
