#pragma once
// The warehouse as solid geometry, one description shared by the renderer (which turns it
// into triangles) and the ground-truth projector (which projects its tag and marker corners
// and ray-casts against it for occlusion). Conventions of shelfcross/warehouse.hpp:
//
//   posts  x_S in [-t_p/2, t_p/2] (front) or depth +- t_p/2 (back), y_S = post_y(i) +- t_p/2,
//          z_S from the floor to the top of the top beam;
//   beams  same x_S faces (+- t_b/2), z_S = beam_z(j) +- t_b/2, y_S over the whole width;
//   rails  at every (post i, level j), x_S between the front and back faces, section t_b;
//   tags   squares of tag_size centred on (post_y(i), beam_z(j)), kSurfaceOffset_m outside the
//          outer bar surface (x_S = -max(t_p, t_b)/2 - offset, or depth + ... on the back);
//   boxes  centred in the cell in x_S and y_S, standing on the beam: bottom at
//          beam_z(level - 1) + t_b/2;
//   markers centred on the box's front (-x_S) and back (+x_S) faces, kSurfaceOffset_m out,
//          inside a white quiet zone one marker cell wide.
// Corner order of tags and markers is OpenCV's aruco order as seen looking at the face from
// outside: top-left, top-right, bottom-right, bottom-left. On the front face "left" is +y_S
// (the viewer looks along +x_S); on the back face it is -y_S.

#include <array>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "shelfcross/warehouse.hpp"

namespace shelfcross::render {

/// Tags and markers stand this far off the surface they are stuck on, so that depth tests
/// never fight and the ground truth lies exactly on the drawn surface.
inline constexpr double kSurfaceOffset_m = 0.001;
/// Width of the white quiet zone around a marker, in marker cells (one cell = marker_size /
/// (bits + 2)); OpenCV's detector needs at least one.
inline constexpr int kQuietZoneCells = 1;

/// An axis-aligned box in its shelf's frame S.
struct Cuboid {
  enum class Kind { kPost, kBeam, kRail, kBox };
  int shelf = 0;
  Kind kind = Kind::kPost;
  Eigen::Vector3d min_S_m = Eigen::Vector3d::Zero();
  Eigen::Vector3d max_S_m = Eigen::Vector3d::Zero();
};

/// A square tag (flat, colour only).
struct TagQuad {
  int shelf = 0;
  bool front_face = true;
  int column_boundary = 0;  ///< i: 0 = left edge as seen on approach .. ncols
  int level_boundary = 0;   ///< j: 0 = lowest beam .. nrows
  Eigen::Vector3d centre_W_m = Eigen::Vector3d::Zero();
  Eigen::Vector3d normal_W = Eigen::Vector3d::Zero();      ///< outward, toward the viewer
  std::array<Eigen::Vector3d, 4> corners_W_m;              ///< TL, TR, BR, BL seen from outside
};

/// An ArUco marker on a box face.
struct MarkerQuad {
  int shelf = 0;
  int level = 1, column = 1;  ///< the box's cell
  int marker_id = 0;
  bool front_face = true;
  Eigen::Vector3d centre_W_m = Eigen::Vector3d::Zero();
  Eigen::Vector3d normal_W = Eigen::Vector3d::Zero();
  std::array<Eigen::Vector3d, 4> corners_W_m;        ///< black border's outer corners, TL TR BR BL
  std::array<Eigen::Vector3d, 4> quiet_corners_W_m;  ///< the white square around it, same order
};

struct SceneLayout {
  std::vector<Eigen::Isometry3d> X_WS;  ///< per shelf
  std::vector<Cuboid> cuboids;
  std::vector<TagQuad> tags;
  std::vector<MarkerQuad> markers;
  int aruco_dictionary_id = 0;  ///< cv::aruco::PREDEFINED_DICTIONARY_NAME value
  int marker_bits = 4;          ///< bits per side of the dictionary's markers
};

/// Builds the layout; throws RenderError (with the shelf name and what is wrong) for a
/// warehouse it cannot draw: empty grids, pitches not larger than the bars, boxes outside the
/// grid or larger than their cell, a marker (with quiet zone) larger than the box face, an
/// unknown dictionary or a marker ID outside it.
SceneLayout build_scene_layout(const Warehouse& warehouse);

/// The cv::aruco::PREDEFINED_DICTIONARY_NAME value of an OpenCV dictionary name such as
/// "DICT_4X4_50"; throws RenderError for an unknown name.
int aruco_dictionary_id(const std::string& name);

}  // namespace shelfcross::render
