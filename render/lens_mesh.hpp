#pragma once
// The lens in the geometry: each frame, the static world's faces are culled, clipped, split
// and projected on the CPU, so that the rasteriser draws the distorted image directly at the
// output size (no undistorted render, no remap pass).
//
// Why straight chords are enough. A face is planar and convex, so its pinhole image in the
// normalised plane (x, y) = (X/Z, Y/Z) of camera C is a convex polygon with straight edges;
// the lens is the 2-D map D: (x, y) -> pixel (u, v) of camera_model.hpp. The rasteriser joins
// projected vertices by straight chords, whereas D bends the segment a -> b (length L,
// direction e) into the curve c(t) = D(a + t (b - a)). Linear interpolation of c gives
//   |c(t) - chord(t)| <= t (1 - t) / 2 max |c''|  <=  L^2 / 8 * max |D''(e, e)|      (1)
// (pixels; D'' in pixels per squared normalised unit). What decides which pixel centres a
// face covers is only the distance ACROSS the chord, n . (c(t) - chord(t)) with n the chord's
// unit normal in the image; n differs from the normal of J e (J = dD) at any point of the
// segment by at most L max |D''| / min |J e| radians, so
//   distance across <= L^2 / 8 * (max |n(e) . D''(e, e)| + L max |D''|^2 / min |J e|).   (2)
// A lens grid cuts the normalised plane into cells whose diagonal d keeps the bound below
// tolerance_px everywhere in the cell (statistics of D sampled every 4 px, 36 directions);
// every face is split along the cells' sides into convex pieces (each inside one cell, so
// every edge and fan diagonal of a piece is at most d long) and fan-triangulated. The grid is
// adaptive, a k-d tree: a box whose own statistics do not meet the bound for its diagonal is
// halved across its longer side (in pixels), so cells are large where the lens bends little
// (the centre) and small where it bends most (the corners); a tensor grid's columns and rows
// instead each take the worst statistics along their whole length. Two grids:
//   edges     bound (2), for flat faces: every drawn edge within tolerance_px of the true
//             curve; the interpolated interior (depth) may be off by bound (1), about 0.7 px
//             for the default lens, which decals absorb with a depth offset (renderer.cpp);
//   interior  bound (1), for textured faces: texture coordinates within tolerance_px too.
// Vertices themselves are exact: each is a point of the face, projected in double precision
// with camera_model's formula (the one of cv::projectPoints), handed to GL as clip coordinates
// (x_ndc Z, y_ndc Z, z_clip, Z) so that GL's perspective-correct interpolation uses the true
// depth Z.
//
// No cracks: split vertices on a cell side are computed once and shared by both sides, and
// every intersection is computed from its segment's end points in a canonical order, so the
// pieces of a face, and faces sharing an edge (split along the same grid), meet exactly. Where
// a large cell borders smaller ones (a T-junction), the smaller cells' corners on the large
// cell's side ("hanging" points) are inserted into the large cell's pieces too: the lens moves
// such a point off the straight chord of the large side (by up to the tolerance), and without
// it the two sides' drawn edges would differ and leave a sliver of pixel centres uncovered.
//
// Faces without texture and without measured corners (the room, shelves, boxes) need none of
// the grid's interior accuracy where it costs triangles: they are meshed along their own
// edges (edge_mesh.hpp: each edge cut until its chords meet the edges bound, the outline's
// image ear-clipped), so a bar crossing ten cells is a handful of triangles, not ten pieces.
// Where such a face is depth-tested, each of its triangles must still keep the interior
// bound of the edges grid (edges_interior_bound_px, which the decals' depth offset and the
// depth order of faces that meet rely on), through the smallest disc around it
// (LensStats::interior_px); a solid with a triangle beyond it is split along the edges grid
// for that frame, all its faces alike, so the edges they share get the same points. The room,
// drawn first without the depth test, takes its outline's triangles whatever their size.
//
// Culling: every face is single-sided (drawn only when the camera is strictly on the side
// its normal points to). The world is made of closed solids, one-sided tags with a backing,
// and the inside of the room, so this only removes faces that are hidden anyway.

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <utility>
#include <vector>

#include <Eigen/Geometry>

#include "render/camera_model.hpp"
#include "render/lens_stats.hpp"
#include "shelfcross/camera.hpp"

namespace shelfcross::render {

class ReadoutPoses;  // rolling_shutter.hpp

/// A lens grid over the part of the normalised plane that the image sees: a k-d tree of
/// cells over the region.
struct LensGrid {
  /// The region: the undistorted footprint of the image (pixel areas, plus margin_px) as a box.
  double x_min = 0.0, x_max = 0.0, y_min = 0.0, y_max = 0.0;
  /// nodes[0] is the root (the region). An inner node splits its box at coordinate[axis] =
  /// value into child[0] (the side <= value) and child[1] (>= value); a leaf (axis < 0) is
  /// the cell cells[cell].
  struct Node {
    int axis = -1;
    double value = 0.0;
    int child[2] = {-1, -1};
    int cell = -1;
  };
  /// A cell: its box, and on each side (0: x = x0, 1: x = x1, 2: y = y0, 3: y = y1) the
  /// corners of other cells strictly inside that side (their y for sides 0 and 1, x for 2 and
  /// 3; ascending), which split_by_grid inserts into the pieces' edges along the side.
  struct Cell {
    double x0 = 0.0, x1 = 0.0, y0 = 0.0, y1 = 0.0;
    std::array<std::vector<double>, 4> hanging;
  };
  std::vector<Node> nodes;
  std::vector<Cell> cells;
  /// Largest deviation bound over the cells' segments, output pixels (<= the tolerance).
  double chord_bound_px = 0.0;

  /// One cell, the box [x0, x1] x [y0, y1]: splitting along it only clips to the box.
  static LensGrid one_cell(double x0, double x1, double y0, double y1);
};

/// The two grids of one lens, over the same region:
///   edges     for flat faces: bounds the distance of a segment's image from its chord
///             (what decides which pixel centres a face covers), so cells are large;
///   interior  for textured faces: bounds the whole displacement of the interpolated
///             interior (texture coordinates along a segment), so cells are smaller.
struct LensGrids {
  LensGrid edges, interior;
  /// The interior bound of the edges grid: how far (pixels) the interpolated interior of a
  /// flat face (its depth) may sit from the true position. Decals are drawn with a depth
  /// offset of this many pixels' worth of slope (renderer.cpp).
  double edges_interior_bound_px = 0.0;
  /// Largest ||D''|| over the region, pixels per squared normalised unit.
  double max_second_derivative_px = 0.0;
  /// The statistics the grids were built from.
  LensStats stats;
};

/// Builds the grids for a tolerance (output pixels). Throws RenderError for invalid
/// intrinsics or a lens that cannot be inverted over the image or folds over in the region.
LensGrids make_lens_grids(const CameraIntrinsics& K, double tolerance_px, double margin_px = 2.0);

/// Splits the convex polygon `poly` (normalised coordinates, in order around its edge) along
/// the grid's cells, dropping what lies outside the region: `pieces` receives the convex
/// pieces' vertices one piece after the other (hanging points included: collinear extra
/// vertices on a side shared with smaller cells) and `sizes` their vertex counts (appended).
void split_by_grid(const LensGrid& grid, const std::vector<Eigen::Vector2d>& poly,
                   std::vector<Eigen::Vector2d>& pieces, std::vector<int>& sizes);

/// One face of the static world: a planar convex quad, single-sided, flat-coloured, with
/// texture coordinates at its corners if it is textured (the quad must then be a
/// parallelogram: texture coordinates are affine on it).
struct MeshFace {
  std::array<Eigen::Vector3d, 4> corners_W_m;  ///< in order around the edge
  Eigen::Vector3d normal_W = Eigen::Vector3d::Zero();  ///< drawn when the camera is on this side
  Eigen::Vector3f rgb = Eigen::Vector3f::Zero();       ///< final sRGB-encoded colour
  std::array<Eigen::Vector2f, 4> uv{};                 ///< atlas coordinates (textured faces)
  /// Faces of one closed solid (a cuboid, the room) share an id >= 0 and are set one after
  /// the other; -1: a face alone. The faces of a solid are meshed the same way each frame
  /// (along their edges, or all along the grid), so that the edges they share get the same
  /// points.
  int solid = -1;
};

/// A vertex as GL receives it: clip coordinates, face colour, texture coordinates.
struct GpuVertex {
  float clip[4];
  float rgb[3];
  float uv[2];
};

/// Faces in four groups, drawn in this order: the room (the inside of the arena box), the
/// other flat faces, flat decals (tags: a millimetre off the surface they are stuck on), and
/// textured decals (markers). Room and flat faces are meshed along their own edges
/// (edge_mesh.hpp) where the interior bound allows, else like decals along the edges grid;
/// tags and markers (whose corners and centroids the perception measures) always along a grid:
/// textured faces the interior grid, tags the edges grid.
enum FaceGroup { kRoomFaces = 0, kFlatFaces = 1, kDecalFaces = 2, kTexturedFaces = 3, kFaceGroups = 4 };

/// The camera as GL rasterises it: the x s pinhole of gl_clip_from_camera, and the lens's
/// exact pixel of a normalised point at that size.
class LensProjection {
 public:
  /// `supersample` s: the image is rasterised at s times the size, pixel u_s = s u + (s-1)/2
  /// (the centre of the s x s block that becomes pixel u). Clip planes at Z = near_m, far_m.
  LensProjection(const CameraIntrinsics& K, int supersample, double near_m, double far_m);

  /// The pixel (at the rasterised size) of a normalised point: exact, double precision.
  /// (This and clip_of run for every vertex of every frame: inline, like the lens formula.)
  Eigen::Vector2d pixel_of(const Eigen::Vector2d& xy) const {
    return s_ * pixel_of_normalized(K_, xy) + Eigen::Vector2d::Constant(0.5 * (s_ - 1));
  }
  /// GL's clip coordinates of a vertex at pixel px (rasterised size) with depth Z: the point
  /// with that depth that the x s pinhole camera of gl_clip_from_camera sees at px, so x_ndc =
  /// 2 (u_s + 0.5) / W - 1 as for any pinhole point and w = Z (perspective-correct interpolation).
  Eigen::Vector4d clip_of(const Eigen::Vector2d& px, double Z) const {
    const double fx_s = s_ * K_.fx_px, fy_s = s_ * K_.fy_px;
    const double cx_s = s_ * K_.cx_px + 0.5 * (s_ - 1), cy_s = s_ * K_.cy_px + 0.5 * (s_ - 1);
    return clip_from_camera_ * Eigen::Vector4d((px.x() - cx_s) / fx_s * Z, (px.y() - cy_s) / fy_s * Z, Z, 1.0);
  }
  int supersample() const { return s_; }
  const CameraIntrinsics& intrinsics() const { return K_; }
  double near_m() const { return near_m_; }
  double far_m() const { return far_m_; }

 private:
  CameraIntrinsics K_;
  int s_;
  double near_m_, far_m_;
  Eigen::Matrix4d clip_from_camera_;  // gl_clip_from_camera of the rasterised (x s) pinhole
};

class LensMesher {
 public:
  /// The projection's arguments (LensProjection); faces are clipped margin_px (output pixels)
  /// outside the image (the lens grids' region).
  LensMesher(const CameraIntrinsics& K, int supersample, double near_m, double far_m,
             double tolerance_px, double margin_px = 2.0);

  void set_faces(FaceGroup group, std::vector<MeshFace> faces);
  /// Whether the group is drawn with the depth test (the default). A group drawn without it
  /// (the room, drawn first) needs no depth inside its faces: they are meshed along their
  /// edges alone, however large their triangles.
  void set_depth_tested(FaceGroup group, bool depth_tested);

  /// The triangles of one frame from camera pose X_WC: vertices() and indices(), the
  /// indices of group g at [first_index(g), first_index(g + 1)).
  void build(const Eigen::Isometry3d& X_WC);
  /// The same under a rolling shutter (rolling_shutter.hpp): culled, clipped and split at the
  /// readout's middle pose, then every vertex moved to where the pose of its own row puts its
  /// point of the face.
  void build(const ReadoutPoses& readout);

  const std::vector<GpuVertex>& vertices() const { return frame_.vertices; }
  const std::vector<std::uint32_t>& indices() const { return frame_.indices; }
  /// The camera-frame point (metres) of each vertex, in double precision: what the vertex is
  /// the projection of (for tests; under a rolling shutter, in the camera at its row's pose).
  const std::vector<Eigen::Vector3d>& points_C() const { return frame_.points_C; }
  std::size_t first_index(int group) const { return frame_.group_start[static_cast<std::size_t>(group)]; }

  /// The room faces of the last frame, each with its index range and its area in the image
  /// (pixels at the rasterised size), in drawing order.
  struct FaceSpan {
    std::size_t first_index = 0, end_index = 0;
    double area_px2 = 0.0;
    Eigen::Vector3f rgb = Eigen::Vector3f::Zero();
  };
  const std::vector<FaceSpan>& room_spans() const { return frame_.room_spans; }
  const LensGrids& grids() const { return grids_; }
  /// Solids (or lone faces) of the room and flat groups that the last frame meshed along the
  /// edges grid because a triangle of their outline exceeded the interior bound.
  std::size_t grid_solids() const { return frame_.grid_solids; }
  /// The faces of a group, as set.
  std::vector<MeshFace> faces(FaceGroup group) const;
  const LensProjection& projection() const { return projection_; }

 private:
  struct Face {
    MeshFace face;
    Eigen::Vector3d e1_dual_W, e2_dual_W;  // s = e1_dual . (p - c0), t = e2_dual . (p - c0)
  };
  // What build() makes of one frame.
  struct FrameMesh {
    std::vector<GpuVertex> vertices;
    std::vector<std::uint32_t> indices;
    std::vector<Eigen::Vector3d> points_C;
    std::vector<FaceSpan> room_spans;
    std::array<std::size_t, kFaceGroups + 1> group_start{};
    std::size_t grid_solids = 0;
  };
  // Buffers a face's clip and split reuse from face to face.
  struct Scratch {
    std::vector<Eigen::Vector3d> poly_C, clipped_C;
    std::vector<Eigen::Vector2d> poly_n, pieces, outline_px;
    std::vector<int> sizes, triangles;
    std::vector<std::pair<std::size_t, std::size_t>> spans;  // index range of each face of a solid
  };
  // How a face is meshed: along the edges grid, the interior grid (textured), or its own
  // edges; with kOutline, `interior_px` is the largest interior bound allowed (infinite where
  // depth does not matter), and add_face returns false, having added a part of the face or
  // nothing, when a triangle exceeds it.
  enum class Mesh { kEdgesGrid, kInteriorGrid, kOutline };
  bool add_face(const Face& f, const Eigen::Isometry3d& X_CW, const Eigen::Vector3d& p_WC, Mesh mesh,
                double interior_px);
  // The face in C, dropped if entirely outside the frustum of grid's region, clipped against
  // the near and far planes, then projected to the normalised plane: scratch_.poly_n. False if
  // nothing is left.
  bool clip_face(const MeshFace& m, const Eigen::Isometry3d& X_CW, const LensGrid& grid);

  LensProjection projection_;
  double tolerance_px_;
  LensGrids grids_;
  LensGrid region_;  // one cell over the grids' region: the clip of faces meshed along their edges
  std::array<std::vector<Face>, kFaceGroups> faces_;
  std::array<bool, kFaceGroups> depth_tested_{true, true, true, true};
  FrameMesh frame_;
  Scratch scratch_;
};

}  // namespace shelfcross::render
