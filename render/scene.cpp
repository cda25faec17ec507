#include "render/scene.hpp"
#include "shelfcross/aruco_dictionaries.hpp"

#include <algorithm>
#include <sstream>
#include <utility>

#include <opencv2/aruco.hpp>

#include "render/render_error.hpp"

namespace shelfcross::render {
namespace {


[[noreturn]] void fail(const ShelfSpec& s, int index, const std::string& what) {
  std::ostringstream os;
  os << "warehouse: shelf " << index << " ('" << s.name << "'): " << what;
  throw RenderError(os.str());
}

}  // namespace

int aruco_dictionary_id(const std::string& name) {
  if (const ArucoDictionaryEntry* e = find_aruco_dictionary(name)) return e->id;
  std::string known;
  for (const ArucoDictionaryEntry& e : kArucoDictionaries) known += std::string(known.empty() ? "" : ", ") + e.name;
  throw RenderError("warehouse: unknown ArUco dictionary '" + name + "' (known: " + known + ")");
}

namespace {

// A square on the plane x_S = x of shelf frame S, centred (y, z), half size h, corners in aruco
// order as seen from outside: on the front (normal -x_S) left is +y_S, on the back left is -y_S.
std::array<Eigen::Vector3d, 4> square_W(const Eigen::Isometry3d& X_WS, double x, double y, double z,
                                        double h, bool front) {
  const double l = front ? h : -h;  // y offset of the viewer's "left"
  return {X_WS * Eigen::Vector3d(x, y + l, z + h), X_WS * Eigen::Vector3d(x, y - l, z + h),
          X_WS * Eigen::Vector3d(x, y - l, z - h), X_WS * Eigen::Vector3d(x, y + l, z - h)};
}

// Shelf si's boxes (validated: in the grid, a known marker, fitting their cell, one per cell),
// each a cuboid with a marker on its front and back faces.
void add_boxes(const Warehouse& w, int si, const Eigen::Isometry3d& X_WS, int dictionary_size,
               double quiet_half_m, SceneLayout& out) {
  const ShelfSpec& s = w.shelves[static_cast<size_t>(si)];
  const int ncols = static_cast<int>(s.column_pitch_m.size());
  const int nrows = static_cast<int>(s.row_pitch_m.size());
  const double tp = s.post_thickness_m, d = s.depth_m;
  const Eigen::Vector3d n_front_W = X_WS.linear() * Eigen::Vector3d(-1, 0, 0);
  for (const BoxPlacement& b : s.boxes) {
    std::ostringstream where;
    where << "box at level " << b.level << ", column " << b.column;
    if (b.level < 1 || b.level > nrows || b.column < 1 || b.column > ncols)
      fail(s, si, where.str() + " is outside the " + std::to_string(nrows) + " x " +
                      std::to_string(ncols) + " grid");
    if (b.marker_id < 0 || b.marker_id >= dictionary_size)
      fail(s, si, where.str() + ": marker_id " + std::to_string(b.marker_id) +
                      " is not in " + w.aruco_dictionary + " (0.." +
                      std::to_string(dictionary_size - 1) + ")");
    const double clear_w = s.column_pitch_m[static_cast<size_t>(b.column - 1)] - tp;
    const double clear_h = cell_clear_height_m(s, b.level);
    if (w.box_size_m.y() > clear_w || w.box_size_m.z() > clear_h || w.box_size_m.x() > d - tp)
      fail(s, si, where.str() + ": the box does not fit in its cell");
    for (const BoxPlacement& other : s.boxes) {
      if (&other != &b && other.level == b.level && other.column == b.column)
        fail(s, si, where.str() + ": two boxes in one cell");
    }
    const Eigen::Vector3d c = cell_centre_S_m(s, b.level, b.column);
    const Eigen::Vector3d centre_S(0.5 * d, c.y(), cell_floor_z_S_m(s, b.level) + 0.5 * w.box_size_m.z());
    out.cuboids.push_back({si, Cuboid::Kind::kBox, centre_S - 0.5 * w.box_size_m, centre_S + 0.5 * w.box_size_m});
    for (bool front : {true, false}) {
      const double x = front ? centre_S.x() - 0.5 * w.box_size_m.x() - kSurfaceOffset_m
                             : centre_S.x() + 0.5 * w.box_size_m.x() + kSurfaceOffset_m;
      MarkerQuad m;
      m.shelf = si;
      m.level = b.level;
      m.column = b.column;
      m.marker_id = b.marker_id;
      m.front_face = front;
      m.centre_W_m = X_WS * Eigen::Vector3d(x, centre_S.y(), centre_S.z());
      m.normal_W = front ? n_front_W : Eigen::Vector3d(-n_front_W);
      m.corners_W_m = square_W(X_WS, x, centre_S.y(), centre_S.z(), 0.5 * w.marker_size_m, front);
      m.quiet_corners_W_m = square_W(X_WS, x, centre_S.y(), centre_S.z(), quiet_half_m, front);
      out.markers.push_back(m);
    }
  }
}

}  // namespace

SceneLayout build_scene_layout(const Warehouse& w) {
  SceneLayout out;
  out.aruco_dictionary_id = aruco_dictionary_id(w.aruco_dictionary);
  const cv::Ptr<cv::aruco::Dictionary> dict =
      cv::aruco::getPredefinedDictionary(out.aruco_dictionary_id);
  out.marker_bits = dict->markerSize;
  const int dictionary_size = dict->bytesList.rows;
  if (!(w.tag_size_m > 0.0)) throw RenderError("warehouse: tag_size_m must be > 0");
  if (!(w.marker_size_m > 0.0)) throw RenderError("warehouse: marker_size_m must be > 0");
  if (!(w.box_size_m.minCoeff() > 0.0)) throw RenderError("warehouse: box_size_m must be > 0");
  // The white square around a marker: marker cells of marker_size / (bits + 2), one quiet
  // cell on each side.
  const double cell_m = w.marker_size_m / (out.marker_bits + 2);
  const double quiet_half_m = 0.5 * w.marker_size_m + kQuietZoneCells * cell_m;
  if (2.0 * quiet_half_m > std::min(w.box_size_m.y(), w.box_size_m.z())) {
    std::ostringstream os;
    os << "warehouse: marker_size_m " << w.marker_size_m << " with its quiet zone ("
       << 2.0 * quiet_half_m << " m) does not fit on the box face (" << w.box_size_m.y() << " x "
       << w.box_size_m.z() << " m)";
    throw RenderError(os.str());
  }

  for (int si = 0; si < static_cast<int>(w.shelves.size()); ++si) {
    const ShelfSpec& s = w.shelves[static_cast<size_t>(si)];
    const int ncols = static_cast<int>(s.column_pitch_m.size());
    const int nrows = static_cast<int>(s.row_pitch_m.size());
    if (ncols < 1 || nrows < 1) fail(s, si, "needs at least one column and one row");
    if (!(s.post_thickness_m > 0.0) || !(s.beam_thickness_m > 0.0))
      fail(s, si, "post and beam thicknesses must be > 0");
    if (!(s.depth_m > s.post_thickness_m)) fail(s, si, "depth_m must exceed post_thickness_m");
    if (!(s.base_height_m > 0.5 * s.beam_thickness_m))
      fail(s, si, "base_height_m must be above half a beam thickness");
    for (double p : s.column_pitch_m)
      if (!(p > s.post_thickness_m)) fail(s, si, "every column pitch must exceed post_thickness_m");
    for (double p : s.row_pitch_m)
      if (!(p > s.beam_thickness_m)) fail(s, si, "every row pitch must exceed beam_thickness_m");

    const Eigen::Isometry3d X_WS = shelf_pose_W(s);
    out.X_WS.push_back(X_WS);
    const double tp = s.post_thickness_m, tb = s.beam_thickness_m, d = s.depth_m;
    const double y_left = post_y_S_m(s, 0) + 0.5 * tp, y_right = post_y_S_m(s, ncols) - 0.5 * tp;
    const double z_top = beam_z_S_m(s, nrows) + 0.5 * tb;
    auto add = [&](Cuboid::Kind kind, Eigen::Vector3d lo, Eigen::Vector3d hi) {
      out.cuboids.push_back({si, kind, lo, hi});
    };
    for (double x_face : {0.0, d}) {
      for (int i = 0; i <= ncols; ++i) {
        const double y = post_y_S_m(s, i);
        add(Cuboid::Kind::kPost, {x_face - 0.5 * tp, y - 0.5 * tp, 0.0},
            {x_face + 0.5 * tp, y + 0.5 * tp, z_top});
      }
      for (int j = 0; j <= nrows; ++j) {
        const double z = beam_z_S_m(s, j);
        add(Cuboid::Kind::kBeam, {x_face - 0.5 * tb, y_right, z - 0.5 * tb},
            {x_face + 0.5 * tb, y_left, z + 0.5 * tb});
      }
    }
    for (int i = 0; i <= ncols; ++i) {
      for (int j = 0; j <= nrows; ++j) {
        const double y = post_y_S_m(s, i), z = beam_z_S_m(s, j);
        add(Cuboid::Kind::kRail, {0.5 * tp, y - 0.5 * tb, z - 0.5 * tb},
            {d - 0.5 * tp, y + 0.5 * tb, z + 0.5 * tb});
      }
    }
    // Solid decks (warehouse.hpp) on every cell floor, drawn in the bars' colour (painted steel decking).
    for (int j = 0; s.deck_thickness_m > 0.0 && j < nrows; ++j) {
      const double z = beam_z_S_m(s, j) + 0.5 * tb;
      add(Cuboid::Kind::kRail, {0.0, post_y_S_m(s, ncols), z}, {d, post_y_S_m(s, 0), z + s.deck_thickness_m});
    }

    const Eigen::Vector3d n_front_W = X_WS.linear() * Eigen::Vector3d(-1, 0, 0);
    const double bar_half = 0.5 * std::max(tp, tb);
    for (bool front : {true, false}) {
      const double x = front ? -bar_half - kSurfaceOffset_m : d + bar_half + kSurfaceOffset_m;
      for (int j = 0; j <= nrows; ++j) {
        for (int i = 0; i <= ncols; ++i) {
          TagQuad t;
          t.shelf = si;
          t.front_face = front;
          t.column_boundary = i;
          t.level_boundary = j;
          t.centre_W_m = X_WS * Eigen::Vector3d(x, post_y_S_m(s, i), beam_z_S_m(s, j));
          t.normal_W = front ? n_front_W : Eigen::Vector3d(-n_front_W);
          t.corners_W_m = square_W(X_WS, x, post_y_S_m(s, i), beam_z_S_m(s, j), 0.5 * w.tag_size_m, front);
          out.tags.push_back(t);
        }
      }
    }

    add_boxes(w, si, X_WS, dictionary_size, quiet_half_m, out);
  }
  return out;
}

}  // namespace shelfcross::render
