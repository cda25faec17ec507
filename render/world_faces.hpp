#pragma once
// The static world as faces for the lens mesher (lens_mesh.hpp): every shelf part and box a
// lit cuboid, tags with their backing squares, the room as the inside of the arena box, and
// markers textured from an atlas of their ArUco bits. Each planar face is lit once (ambient +
// Lambert directional) and its sRGB-encoded colour baked in, since both are constant per face.

#include <array>
#include <vector>

#include <Eigen/Geometry>
#include <opencv2/core/mat.hpp>

#include "render/lens_mesh.hpp"
#include "render/scene.hpp"
#include "shelfcross/warehouse.hpp"

namespace shelfcross::render {

struct WorldFaces {
  std::array<std::vector<MeshFace>, kFaceGroups> faces;  ///< by FaceGroup
  /// The markers' texture: one row of square tiles (tile 0 white, then one per distinct marker
  /// ID), one texel per marker cell, CV_8UC1; black cells at the printed black's texel.
  cv::Mat atlas;
  Eigen::AlignedBox3d arena;  ///< the box the room's faces bound
  /// Every non-room face lies inside the arena box, so the room (whose visible faces never
  /// overlap: the inside of a convex box) can be drawn first without the depth test.
  bool room_first = false;
};

/// The faces of `warehouse` (its layout already built), lit with its lighting times light_scale.
WorldFaces build_world_faces(const Warehouse& warehouse, const SceneLayout& layout, double light_scale);

}  // namespace shelfcross::render
