#include "render/lens_mesh.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

#include "render/camera_model.hpp"
#include "render/edge_mesh.hpp"
#include "render/render_error.hpp"

namespace shelfcross::render {
namespace {

using Vec2 = Eigen::Vector2d;
using Vec3 = Eigen::Vector3d;

// The point where segment a-b crosses coordinate[axis] = value, computed from the end points
// in a canonical order (so that a segment shared by two polygons, traversed in opposite
// directions, gives bit-identical points) and with that coordinate set exactly.
Vec2 cross_line(Vec2 a, Vec2 b, int axis, double value) {
  if (b.x() < a.x() || (b.x() == a.x() && b.y() < a.y())) std::swap(a, b);
  const double t = (value - a[axis]) / (b[axis] - a[axis]);
  Vec2 q = a + t * (b - a);
  q[axis] = value;
  return q;
}

// Sutherland-Hodgman for both sides at once: the parts of convex `p` with coordinate[axis] <=
// value (into lo, if given) and >= value (into hi, if given). A crossing point is computed
// once and goes to both sides.
void split_line(const std::vector<Vec2>& p, int axis, double value, std::vector<Vec2>* lo,
                std::vector<Vec2>* hi) {
  if (lo) lo->clear();
  if (hi) hi->clear();
  const std::size_t n = p.size();
  for (std::size_t i = 0; i < n; ++i) {
    const Vec2& a = p[i];
    const Vec2& b = p[(i + 1) % n];
    const double da = a[axis] - value, db = b[axis] - value;
    if (da <= 0.0 && lo) lo->push_back(a);
    if (da >= 0.0 && hi) hi->push_back(a);
    if ((da < 0.0 && db > 0.0) || (da > 0.0 && db < 0.0)) {
      const Vec2 q = cross_line(a, b, axis, value);
      if (lo) lo->push_back(q);
      if (hi) hi->push_back(q);
    }
  }
}

// Scratch buffers of split_by_grid, one set per thread: the region clip's, and a lo/hi pair
// per depth of the k-d tree.
struct SplitScratch {
  std::vector<Vec2> a, b;
  std::vector<std::array<std::vector<Vec2>, 2>> level;
};

// The piece `p` of cell c, with the hanging points of each of c's sides inserted into the
// piece's edges along that side (in the edge's direction), appended to `pieces`.
void emit_piece(const LensGrid::Cell& c, const std::vector<Vec2>& p, std::vector<Vec2>& pieces,
                std::vector<int>& sizes) {
  const std::size_t first = pieces.size(), n = p.size();
  for (std::size_t i = 0; i < n; ++i) {
    const Vec2& a = p[i];
    const Vec2& b = p[(i + 1) % n];
    pieces.push_back(a);
    for (int side = 0; side < 4; ++side) {
      const std::vector<double>& h = c.hanging[static_cast<std::size_t>(side)];
      if (h.empty()) continue;
      const int axis = side < 2 ? 0 : 1;  // the coordinate that is constant along the side
      const double on = side == 0 ? c.x0 : side == 1 ? c.x1 : side == 2 ? c.y0 : c.y1;
      if (a[axis] != on || b[axis] != on) continue;
      const int along = 1 - axis;
      const double from = a[along], to = b[along];
      Vec2 q;
      q[axis] = on;
      if (from < to) {
        for (auto it = std::upper_bound(h.begin(), h.end(), from); it != h.end() && *it < to; ++it)
          q[along] = *it, pieces.push_back(q);
      } else {
        for (auto it = std::lower_bound(h.begin(), h.end(), from); it != h.begin() && *(it - 1) > to;)
          q[along] = *--it, pieces.push_back(q);
      }
      break;  // an edge lies on one side at most
    }
  }
  sizes.push_back(static_cast<int>(pieces.size() - first));
}

// Splits `poly` (inside node k's box) down the tree, emitting one piece per cell it covers.
void descend(const LensGrid& grid, int k, const std::vector<Vec2>& poly, std::size_t depth,
             SplitScratch& s, std::vector<Vec2>& pieces, std::vector<int>& sizes) {
  const LensGrid::Node& node = grid.nodes[static_cast<std::size_t>(k)];
  if (node.axis < 0) {
    emit_piece(grid.cells[static_cast<std::size_t>(node.cell)], poly, pieces, sizes);
    return;
  }
  double mn = std::numeric_limits<double>::infinity(), mx = -mn;
  for (const Vec2& v : poly) mn = std::min(mn, v[node.axis]), mx = std::max(mx, v[node.axis]);
  // Split only a polygon the line crosses; one touching it from a side stays whole.
  if (mx <= node.value) return descend(grid, node.child[0], poly, depth + 1, s, pieces, sizes);
  if (mn >= node.value) return descend(grid, node.child[1], poly, depth + 1, s, pieces, sizes);
  std::vector<Vec2>& lo = s.level[depth][0];
  std::vector<Vec2>& hi = s.level[depth][1];
  split_line(poly, node.axis, node.value, &lo, &hi);
  if (lo.size() >= 3) descend(grid, node.child[0], lo, depth + 1, s, pieces, sizes);
  if (hi.size() >= 3) descend(grid, node.child[1], hi, depth + 1, s, pieces, sizes);
}

// The cells' hanging points: for each side of each cell, the corners of the other cells that
// lie strictly inside it. (Coordinates are compared exactly: a child's box repeats its
// parent's split values bit for bit.) Quadratic in the number of cells, a few hundred.
void find_hanging_points(std::vector<LensGrid::Cell>& cells) {
  for (LensGrid::Cell& c : cells) {
    for (const LensGrid::Cell& o : cells) {
      if (&o == &c) continue;
      for (const double x : {o.x0, o.x1}) {
        for (const double y : {o.y0, o.y1}) {
          if (c.y0 < y && y < c.y1) {
            if (x == c.x0) c.hanging[0].push_back(y);
            if (x == c.x1) c.hanging[1].push_back(y);
          }
          if (c.x0 < x && x < c.x1) {
            if (y == c.y0) c.hanging[2].push_back(x);
            if (y == c.y1) c.hanging[3].push_back(x);
          }
        }
      }
    }
    for (std::vector<double>& h : c.hanging) {
      std::sort(h.begin(), h.end());
      h.erase(std::unique(h.begin(), h.end()), h.end());
    }
  }
}

// The k-d tree over g's region: a box that does not fit (`fits`: its cells' segments meet the
// bound) is halved across its longer side in pixels (x lengths count x_to_y_pixels = fx / fy
// times y lengths), and its halves are built likewise; cells are numbered low side first.
// (Planning the splits instead, halves or thirds across either axis to least total side
// length, gave more triangles on the test shelf's frames, not fewer.)
template <class Fits>
void build_kd_cells(LensGrid& g, Fits&& fits, double x_to_y_pixels) {
  g.nodes.assign(1, LensGrid::Node{});
  g.cells.clear();
  struct Box {
    double x0, x1, y0, y1;
  };
  std::vector<std::pair<int, Box>> todo{{0, {g.x_min, g.x_max, g.y_min, g.y_max}}};
  while (!todo.empty()) {
    const auto [k, b] = todo.back();
    todo.pop_back();
    if (fits(b.x0, b.x1, b.y0, b.y1)) {
      g.nodes[static_cast<std::size_t>(k)].cell = static_cast<int>(g.cells.size());
      g.cells.push_back({b.x0, b.x1, b.y0, b.y1, {}});
      continue;
    }
    const int axis = (b.x1 - b.x0) * x_to_y_pixels >= (b.y1 - b.y0) ? 0 : 1;
    const double value = axis == 0 ? 0.5 * (b.x0 + b.x1) : 0.5 * (b.y0 + b.y1);
    Box lo = b, hi = b;
    (axis == 0 ? lo.x1 : lo.y1) = value;
    (axis == 0 ? hi.x0 : hi.y0) = value;
    const int c0 = static_cast<int>(g.nodes.size());
    g.nodes.emplace_back();
    g.nodes.emplace_back();
    LensGrid::Node& node = g.nodes[static_cast<std::size_t>(k)];
    node.axis = axis;
    node.value = value;
    node.child[0] = c0;
    node.child[1] = c0 + 1;
    todo.push_back({c0 + 1, hi});
    todo.push_back({c0, lo});
  }
  find_hanging_points(g.cells);
}

// The lens's statistics at normalised point p by central differences of step h, over 36
// directions e: Mf = max |D''(e, e)|, Mp = max |n(e) . D''(e, e)| with n(e) the unit normal of
// J e (the image direction of e), Jmin = min |J e|. False where the Jacobian is not positive
// (the lens folds over).
bool second_derivative_stats(const CameraIntrinsics& K, const Vec2& p, double h, LensStats::Stats& st) {
  const Vec2 c = pixel_of_normalized(K, p);
  const Vec2 xp = pixel_of_normalized(K, p + Vec2(h, 0)), xm = pixel_of_normalized(K, p - Vec2(h, 0));
  const Vec2 yp = pixel_of_normalized(K, p + Vec2(0, h)), ym = pixel_of_normalized(K, p - Vec2(0, h));
  const Vec2 pp = pixel_of_normalized(K, p + Vec2(h, h)), pm = pixel_of_normalized(K, p + Vec2(h, -h));
  const Vec2 mp = pixel_of_normalized(K, p + Vec2(-h, h)), mm = pixel_of_normalized(K, p + Vec2(-h, -h));
  const Vec2 dxx = (xp - 2.0 * c + xm) / (h * h), dyy = (yp - 2.0 * c + ym) / (h * h);
  const Vec2 dxy = (pp - pm - mp + mm) / (4.0 * h * h);
  const Vec2 jx = (xp - xm) / (2.0 * h), jy = (yp - ym) / (2.0 * h);
  if (!(jx.x() * jy.y() - jx.y() * jy.x() > 0.0)) return false;
  for (int k = 0; k < 36; ++k) {
    const double th = M_PI * k / 36.0, ex = std::cos(th), ey = std::sin(th);
    const Vec2 d2 = ex * ex * dxx + 2.0 * ex * ey * dxy + ey * ey * dyy;
    const Vec2 je = ex * jx + ey * jy;
    const double jn = je.norm();
    st.Mf = std::max(st.Mf, d2.norm());
    st.Mp = std::max(st.Mp, std::abs(je.x() * d2.y() - je.y() * d2.x()) / jn);
    st.Jmin = std::min(st.Jmin, jn);
  }
  return true;
}

}  // namespace

LensGrids make_lens_grids(const CameraIntrinsics& K, double tolerance_px, double margin_px) {
  if (K.width_px <= 0 || K.height_px <= 0 || !(K.fx_px > 0) || !(K.fy_px > 0) ||
      !(tolerance_px > 0)) {
    std::ostringstream os;
    os << "camera intrinsics invalid: need width, height, fx, fy > 0 (got " << K.width_px << " x "
       << K.height_px << ", fx " << K.fx_px << ", fy " << K.fy_px << ")";
    throw RenderError(os.str());
  }
  auto fail = [&](double u, double v, const char* what) {
    std::ostringstream os;
    os << "lens distortion (k1 " << K.k1 << ", k2 " << K.k2 << ", p1 " << K.p1 << ", p2 " << K.p2
       << ", k3 " << K.k3 << ") " << what << " near pixel (" << u << ", " << v << ")";
    throw RenderError(os.str());
  };
  // Footprint: D maps the region's boundary onto the image rectangle's (grown by the margin,
  // pixel areas: centres +- 0.5), so the box around the undistorted boundary holds every
  // normalised point that lands in the image.
  double x_min = std::numeric_limits<double>::infinity(), x_max = -x_min;
  double y_min = x_min, y_max = -x_min;
  auto visit = [&](double u, double v) {
    Vec2 xy;
    if (!undistort_normalized(K, {(u - K.cx_px) / K.fx_px, (v - K.cy_px) / K.fy_px}, xy))
      fail(u, v, "cannot be inverted (the model folds over inside the image)");
    x_min = std::min(x_min, xy.x()), x_max = std::max(x_max, xy.x());
    y_min = std::min(y_min, xy.y()), y_max = std::max(y_max, xy.y());
  };
  const double u0 = -0.5 - margin_px, u1 = K.width_px - 0.5 + margin_px;
  const double v0 = -0.5 - margin_px, v1 = K.height_px - 0.5 + margin_px;
  for (double u = u0; u < u1; u += 1.0) visit(u, v0), visit(u, v1);
  for (double v = v0; v < v1; v += 1.0) visit(u0, v), visit(u1, v);
  visit(u1, v1);

  // On a lattice of 4-pixel pitch over the box (and one pitch beyond it), by central
  // differences (step 1e-4: rounding ~1e-5 px per unit^2), over 36 directions e:
  //   Mf = max |D''(e, e)|, Mp = max |n(e) . D''(e, e)| with n(e) the unit normal of J e (the
  //   image direction of e), Jmin = min |J e|; and the Jacobian's sign (no fold-over).
  const double step = 4.0 / std::max(K.fx_px, K.fy_px), h = 1e-4;
  const int nx = static_cast<int>(std::ceil((x_max - x_min) / step)) + 3;
  const int ny = static_cast<int>(std::ceil((y_max - y_min) / step)) + 3;
  const double ox = x_min - step, oy = y_min - step;
  using Stats = LensStats::Stats;
  std::vector<Stats> lattice(static_cast<std::size_t>(nx) * static_cast<std::size_t>(ny));
  LensGrids grids;
  for (int j = 0; j < ny; ++j) {
    for (int i = 0; i < nx; ++i) {
      const Vec2 p(ox + i * step, oy + j * step);
      const Vec2 c = pixel_of_normalized(K, p);
      Stats st;
      if (!second_derivative_stats(K, p, h, st))
        fail(c.x(), c.y(), "folds over (Jacobian not positive) in the region the image sees");
      // The direction samples are 5 degrees apart: a 2 % allowance for the maxima between them.
      st.Mf *= 1.02, st.Mp *= 1.02;
      lattice[static_cast<std::size_t>(j) * static_cast<std::size_t>(nx) + static_cast<std::size_t>(i)] = st;
      grids.max_second_derivative_px = std::max(grids.max_second_derivative_px, st.Mf);
    }
  }
  // The deviation bound of a segment of length L inside a region with statistics st:
  //   interior (any component): L^2 / 8 Mf;
  //   edges (across the chord only): L^2 / 8 (Mp + L Mf^2 / Jmin), the second term for the
  //   chord's direction differing from J e along the segment by at most L Mf / Jmin radians.
  auto deviation = [](bool edges, double L, const Stats& st) {
    return edges ? L * L / 8.0 * (st.Mp + L * st.Mf * st.Mf / st.Jmin) : L * L / 8.0 * st.Mf;
  };
  // Stats over the lattice points bracketing a box (one pitch beyond each side).
  auto box_stats = [&](double x0, double x1, double y0, double y1) {
    const int i0 = std::max(0, static_cast<int>(std::floor((x0 - ox) / step)) - 1);
    const int i1 = std::min(nx - 1, static_cast<int>(std::ceil((x1 - ox) / step)) + 1);
    const int j0 = std::max(0, static_cast<int>(std::floor((y0 - oy) / step)) - 1);
    const int j1 = std::min(ny - 1, static_cast<int>(std::ceil((y1 - oy) / step)) + 1);
    Stats st;
    for (int j = j0; j <= j1; ++j)
      for (int i = i0; i <= i1; ++i)
        st.merge(lattice[static_cast<std::size_t>(j) * static_cast<std::size_t>(nx) + static_cast<std::size_t>(i)]);
    return st;
  };
  // The blocks of the statistics kept for the meshes that follow faces' own edges.
  LensStats& ls = grids.stats;
  ls.step = step;
  for (int j = 0; j < ny; ++j) {
    for (int i = 0; i < nx; ++i) {
      const auto k = static_cast<std::size_t>(std::hypot(ox + i * step, oy + j * step) / step);
      if (ls.by_radius.size() <= k) ls.by_radius.resize(k + 1);
      ls.by_radius[k].merge(lattice[static_cast<std::size_t>(j) * static_cast<std::size_t>(nx) + static_cast<std::size_t>(i)]);
    }
  }
  for (std::size_t k = 1; k < ls.by_radius.size(); ++k) ls.by_radius[k].merge(ls.by_radius[k - 1]);
  for (LensGrid* g : {&grids.edges, &grids.interior}) {
    const bool edges = g == &grids.edges;
    g->x_min = x_min, g->x_max = x_max, g->y_min = y_min, g->y_max = y_max;
    // Any segment inside a cell is at most its diagonal long.
    auto fits = [&](double x0, double x1, double y0, double y1) {
      return deviation(edges, std::hypot(x1 - x0, y1 - y0), box_stats(x0, x1, y0, y1)) <= tolerance_px;
    };
    build_kd_cells(*g, fits, K.fx_px / K.fy_px);
    // The bounds achieved, cell by cell.
    for (const LensGrid::Cell& c : g->cells) {
      const double diagonal = std::hypot(c.x1 - c.x0, c.y1 - c.y0);
      const Stats st = box_stats(c.x0, c.x1, c.y0, c.y1);
      g->chord_bound_px = std::max(g->chord_bound_px, deviation(edges, diagonal, st));
      if (edges) grids.edges_interior_bound_px = std::max(grids.edges_interior_bound_px, deviation(false, diagonal, st));
    }
  }
  return grids;
}

LensGrid LensGrid::one_cell(double x0, double x1, double y0, double y1) {
  LensGrid g;
  g.x_min = x0, g.x_max = x1, g.y_min = y0, g.y_max = y1;
  g.nodes.emplace_back().cell = 0;
  g.cells.push_back({x0, x1, y0, y1, {}});
  return g;
}

void split_by_grid(const LensGrid& grid, const std::vector<Vec2>& poly, std::vector<Vec2>& pieces,
                   std::vector<int>& sizes) {
  thread_local SplitScratch s;
  // Clip to the region first (cheap rejection of everything outside it).
  split_line(poly, 0, grid.x_min, nullptr, &s.a);
  if (s.a.size() < 3) return;
  split_line(s.a, 0, grid.x_max, &s.b, nullptr);
  if (s.b.size() < 3) return;
  split_line(s.b, 1, grid.y_min, nullptr, &s.a);
  if (s.a.size() < 3) return;
  split_line(s.a, 1, grid.y_max, &s.b, nullptr);
  if (s.b.size() < 3) return;
  // One lo/hi pair per level, allocated before the descent holds references into them.
  if (s.level.size() < grid.nodes.size()) s.level.resize(grid.nodes.size());
  descend(grid, 0, s.b, 0, s, pieces, sizes);
}

LensProjection::LensProjection(const CameraIntrinsics& K, int supersample, double near_m, double far_m)
    : K_(K),
      s_(supersample),
      near_m_(near_m),
      far_m_(far_m),
      clip_from_camera_(gl_clip_from_camera(supersample * K.fx_px, supersample * K.fy_px,
                                            supersample * K.cx_px + 0.5 * (supersample - 1),
                                            supersample * K.cy_px + 0.5 * (supersample - 1),
                                            supersample * K.width_px, supersample * K.height_px,
                                            near_m, far_m)) {}

LensMesher::LensMesher(const CameraIntrinsics& K, int supersample, double near_m, double far_m,
                       double tolerance_px, double margin_px)
    : projection_(K, supersample, near_m, far_m),
      tolerance_px_(tolerance_px),
      grids_(make_lens_grids(K, tolerance_px, margin_px)),
      region_(LensGrid::one_cell(grids_.edges.x_min, grids_.edges.x_max, grids_.edges.y_min, grids_.edges.y_max)) {}

void LensMesher::set_faces(FaceGroup group, std::vector<MeshFace> faces) {
  std::vector<Face>& out = faces_[static_cast<std::size_t>(group)];
  out.clear();
  for (MeshFace& m : faces) {
    Face f;
    const Vec3 e1 = m.corners_W_m[1] - m.corners_W_m[0], e2 = m.corners_W_m[3] - m.corners_W_m[0];
    Eigen::Matrix2d G;
    G << e1.dot(e1), e1.dot(e2), e1.dot(e2), e2.dot(e2);
    const Eigen::Matrix2d Gi = G.inverse();
    f.e1_dual_W = Gi(0, 0) * e1 + Gi(0, 1) * e2;
    f.e2_dual_W = Gi(1, 0) * e1 + Gi(1, 1) * e2;
    f.face = std::move(m);
    out.push_back(std::move(f));
  }
}

std::vector<MeshFace> LensMesher::faces(FaceGroup group) const {
  std::vector<MeshFace> out;
  for (const Face& f : faces_[static_cast<std::size_t>(group)]) out.push_back(f.face);
  return out;
}

void LensMesher::set_depth_tested(FaceGroup group, bool depth_tested) {
  depth_tested_[static_cast<std::size_t>(group)] = depth_tested;
}

void LensMesher::build(const Eigen::Isometry3d& X_WC) {
  frame_.vertices.clear();
  frame_.indices.clear();
  frame_.points_C.clear();
  frame_.room_spans.clear();
  frame_.grid_solids = 0;
  const Eigen::Isometry3d X_CW = X_WC.inverse(Eigen::Isometry);
  const Vec3 p_WC = X_WC.translation();
  for (int g = 0; g < kFaceGroups; ++g) {
    frame_.group_start[static_cast<std::size_t>(g)] = frame_.indices.size();
    const std::vector<Face>& faces = faces_[static_cast<std::size_t>(g)];
    // Room and flat faces along their own edges, with the interior bound of the edges grid
    // where depth-tested (so decals' depth offset and the depth order of faces that meet hold
    // as with the grid); a solid with a face whose triangles exceed it goes along the grid.
    const bool outline = g == kRoomFaces || g == kFlatFaces;
    const double interior_px = depth_tested_[static_cast<std::size_t>(g)]
                                   ? grids_.edges_interior_bound_px
                                   : std::numeric_limits<double>::infinity();
    const Mesh grid_mesh = g == kTexturedFaces ? Mesh::kInteriorGrid : Mesh::kEdgesGrid;
    for (std::size_t k = 0; k < faces.size();) {
      std::size_t end = k + 1;
      while (end < faces.size() && faces[k].face.solid >= 0 && faces[end].face.solid == faces[k].face.solid) ++end;
      const std::size_t v0 = frame_.vertices.size(), i0 = frame_.indices.size();
      auto mesh_solid = [&](Mesh mesh) {
        scratch_.spans.clear();
        for (std::size_t j = k; j < end; ++j) {
          const std::size_t first = frame_.indices.size();
          if (!add_face(faces[j], X_CW, p_WC, mesh, interior_px)) return false;
          scratch_.spans.emplace_back(first, frame_.indices.size());
        }
        return true;
      };
      if (!outline || !mesh_solid(Mesh::kOutline)) {
        if (outline) ++frame_.grid_solids;
        frame_.vertices.resize(v0), frame_.points_C.resize(v0), frame_.indices.resize(i0);
        mesh_solid(grid_mesh);
      }
      if (g == kRoomFaces) {
        for (std::size_t j = k; j < end; ++j) {
          const auto [first, last] = scratch_.spans[j - k];
          if (last == first) continue;
          // Its area: the triangles' areas in window coordinates (x_ndc, y_ndc scaled).
          FaceSpan span{first, last, 0.0, faces[j].face.rgb};
          for (std::size_t i = first; i < last; i += 3) {
            Vec2 p[3];
            for (int c = 0; c < 3; ++c) {
              const GpuVertex& v = frame_.vertices[frame_.indices[i + static_cast<std::size_t>(c)]];
              p[c] = Vec2(v.clip[0] / v.clip[3] * 0.5 * projection_.supersample() * projection_.intrinsics().width_px, v.clip[1] / v.clip[3] * 0.5 * projection_.supersample() * projection_.intrinsics().height_px);
            }
            const Vec2 a = p[1] - p[0], b = p[2] - p[0];
            span.area_px2 += 0.5 * std::abs(a.x() * b.y() - a.y() * b.x());
          }
          frame_.room_spans.push_back(span);
        }
      }
      k = end;
    }
  }
  frame_.group_start[kFaceGroups] = frame_.indices.size();
}

bool LensMesher::clip_face(const MeshFace& m, const Eigen::Isometry3d& X_CW, const LensGrid& grid) {
  const Eigen::Matrix3d& R_CW = X_CW.linear();
  const Vec3 t_CW = X_CW.translation();
  scratch_.poly_C.clear();
  // Outcodes against the frustum that holds the lens region: a face entirely beyond one plane
  // is dropped before any clipping.
  const double xl = grid.x_min, xh = grid.x_max;
  const double yl = grid.y_min, yh = grid.y_max;
  unsigned all_out = 0x3f;
  bool needs_z_clip = false;
  for (const Vec3& c : m.corners_W_m) {
    const Vec3 p = R_CW * c + t_CW;
    scratch_.poly_C.push_back(p);
    unsigned out = 0;
    if (p.z() < projection_.near_m()) out |= 1u;
    if (p.z() > projection_.far_m()) out |= 2u;
    if (p.x() < xl * p.z()) out |= 4u;
    if (p.x() > xh * p.z()) out |= 8u;
    if (p.y() < yl * p.z()) out |= 16u;
    if (p.y() > yh * p.z()) out |= 32u;
    all_out &= out;
    needs_z_clip = needs_z_clip || (out & 3u);
  }
  if (all_out != 0) return false;
  if (needs_z_clip) {
    // Near and far planes in 3-D (Z = near, Z = far), crossings in canonical order.
    for (int side = 0; side < 2; ++side) {
      const double plane = side == 0 ? projection_.near_m() : projection_.far_m();
      const double sign = side == 0 ? 1.0 : -1.0;  // inside: sign (Z - plane) >= 0
      scratch_.clipped_C.clear();
      const std::size_t n = scratch_.poly_C.size();
      for (std::size_t i = 0; i < n; ++i) {
        const Vec3& a = scratch_.poly_C[i];
        const Vec3& b = scratch_.poly_C[(i + 1) % n];
        const double da = sign * (a.z() - plane), db = sign * (b.z() - plane);
        if (da >= 0.0) scratch_.clipped_C.push_back(a);
        if ((da < 0.0 && db > 0.0) || (da > 0.0 && db < 0.0)) {
          const bool swap = b.x() < a.x() || (b.x() == a.x() && (b.y() < a.y() || (b.y() == a.y() && b.z() < a.z())));
          const Vec3& p = swap ? b : a;
          const Vec3& q = swap ? a : b;
          Vec3 x = p + (plane - p.z()) / (q.z() - p.z()) * (q - p);
          x.z() = plane;
          scratch_.clipped_C.push_back(x);
        }
      }
      scratch_.poly_C.swap(scratch_.clipped_C);
      if (scratch_.poly_C.size() < 3) return false;
    }
  }
  scratch_.poly_n.clear();
  for (const Vec3& p : scratch_.poly_C) scratch_.poly_n.emplace_back(p.x() / p.z(), p.y() / p.z());
  return true;
}

bool LensMesher::add_face(const Face& f, const Eigen::Isometry3d& X_CW, const Vec3& p_WC, Mesh mesh,
                          double interior_px) {
  const MeshFace& m = f.face;
  // Single-sided: the camera strictly in front of the face's plane.
  if (!(m.normal_W.dot(p_WC - m.corners_W_m[0]) > 1e-9)) return true;
  const bool textured = mesh == Mesh::kInteriorGrid;
  const LensGrid& grid = textured ? grids_.interior : grids_.edges;
  if (!clip_face(m, X_CW, grid)) return true;
  const Eigen::Matrix3d& R_CW = X_CW.linear();
  const Vec3 t_CW = X_CW.translation();
  scratch_.pieces.clear();
  scratch_.sizes.clear();
  if (mesh == Mesh::kOutline) {
    // The region clip alone (one cell), then the outline's edges bisected.
    split_by_grid(region_, scratch_.poly_n, scratch_.pieces, scratch_.sizes);
    if (scratch_.sizes.empty()) return true;
    scratch_.poly_n.swap(scratch_.pieces);
    scratch_.pieces.clear();
    bisect_outline(grids_.stats, tolerance_px_, scratch_.poly_n, scratch_.pieces);
    scratch_.outline_px.clear();
    for (const Vec2& xy : scratch_.pieces) scratch_.outline_px.push_back(projection_.pixel_of(xy));
    scratch_.triangles.clear();
    triangulate_polygon(scratch_.outline_px, scratch_.triangles);
    for (std::size_t t = 0; t < scratch_.triangles.size(); t += 3) {
      const Vec2& a = scratch_.pieces[static_cast<std::size_t>(scratch_.triangles[t])];
      const Vec2& b = scratch_.pieces[static_cast<std::size_t>(scratch_.triangles[t + 1])];
      const Vec2& c = scratch_.pieces[static_cast<std::size_t>(scratch_.triangles[t + 2])];
      if (grids_.stats.interior_px(a, b, c) > interior_px) return false;
    }
  } else {
    split_by_grid(grid, scratch_.poly_n, scratch_.pieces, scratch_.sizes);
    if (scratch_.sizes.empty()) return true;
  }

  // The face's plane in C: n_C . p = d_C (< 0: the camera is on the normal side), so the point
  // of the face on the ray (x, y, 1) has depth Z = d_C / (n_C . (x, y, 1)).
  const Vec3 n_C = R_CW * m.normal_W;
  const Vec3 c0_C = R_CW * m.corners_W_m[0] + t_CW;
  const double d_C = n_C.dot(c0_C);
  // Texture coordinates, affine on the face: uv = uv0 + s (uv1 - uv0) + t (uv3 - uv0).
  const Vec3 g1_C = R_CW * f.e1_dual_W, g2_C = R_CW * f.e2_dual_W;
  const Eigen::Vector2f duv1 = m.uv[1] - m.uv[0], duv3 = m.uv[3] - m.uv[0];
  // Clip coordinates from the vertex's (distorted) pixel and its true depth Z (clip_of).
  auto add_vertex = [&](const Vec2& xy, const Vec2& px) {
    const double Z = d_C / n_C.dot(Vec3(xy.x(), xy.y(), 1.0));
    const Eigen::Vector4d clip = projection_.clip_of(px, Z);
    GpuVertex gv;
    for (int c = 0; c < 4; ++c) gv.clip[c] = static_cast<float>(clip[c]);
    for (int c = 0; c < 3; ++c) gv.rgb[c] = m.rgb[c];
    if (textured) {
      const Vec3 r = Z * Vec3(xy.x(), xy.y(), 1.0) - c0_C;
      const float s = static_cast<float>(g1_C.dot(r)), t = static_cast<float>(g2_C.dot(r));
      gv.uv[0] = m.uv[0].x() + s * duv1.x() + t * duv3.x();
      gv.uv[1] = m.uv[0].y() + s * duv1.y() + t * duv3.y();
    } else {
      gv.uv[0] = gv.uv[1] = 0.0f;
    }
    frame_.vertices.push_back(gv);
    frame_.points_C.push_back(Z * Vec3(xy.x(), xy.y(), 1.0));
  };
  const auto base = static_cast<std::uint32_t>(frame_.vertices.size());
  if (mesh == Mesh::kOutline) {
    for (std::size_t v = 0; v < scratch_.pieces.size(); ++v) add_vertex(scratch_.pieces[v], scratch_.outline_px[v]);
    for (const int t : scratch_.triangles) frame_.indices.push_back(base + static_cast<std::uint32_t>(t));
    return true;
  }
  std::size_t k = 0;
  for (int size : scratch_.sizes) {
    const auto first = static_cast<std::uint32_t>(frame_.vertices.size());
    for (int v = 0; v < size; ++v, ++k) add_vertex(scratch_.pieces[k], projection_.pixel_of(scratch_.pieces[k]));
    for (int v = 1; v + 1 < size; ++v) {
      frame_.indices.push_back(first);
      frame_.indices.push_back(first + static_cast<std::uint32_t>(v));
      frame_.indices.push_back(first + static_cast<std::uint32_t>(v + 1));
    }
  }
  return true;
}

}  // namespace shelfcross::render
