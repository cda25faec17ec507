// The lens in the geometry (lens_mesh.hpp), against its fidelity conditions:
//   - every vertex of a frame is exactly where cv::projectPoints puts its 3-D point;
//   - every drawn edge between vertices lies within 0.25 px of the true (curved) image of the
//     face edge it stands for, measured densely along the curve, not taken from the bound;
//   - the pieces tile each face exactly (no gap, no overlap in the normalised plane);
//   - the rendered image equals a per-pixel ray cast of the same world at every pixel that no
//     edge passes within 0.3 px of (point sampling at pixel centres, the lens exact).
#include <gtest/gtest.h>

#include <iostream>
#include <limits>
#include <random>

#include <opencv2/calib3d.hpp>

#include "render/camera_model.hpp"
#include "render/lens_mesh.hpp"
#include "render/renderer.hpp"
#include "test_warehouse.hpp"

namespace shelfcross::render {
namespace {

using Vec2 = Eigen::Vector2d;

double area(const std::vector<Vec2>& p, std::size_t first, std::size_t n) {
  double a = 0.0;
  for (std::size_t i = 0; i < n; ++i) {
    const Vec2& u = p[first + i];
    const Vec2& v = p[first + (i + 1) % n];
    a += u.x() * v.y() - u.y() * v.x();
  }
  return 0.5 * a;
}

// Largest distance of the lens image of segment a-b from its chord (across: to the chord's
// line), and largest displacement of the image from the linearly interpolated point (the
// interior mapping, which the textured faces need), both from 257 points along the curve.
struct Deviation {
  double across_px = 0.0, along_px = 0.0;
};
Deviation deviation(const CameraIntrinsics& K, const Vec2& a, const Vec2& b) {
  const Vec2 pa = pixel_of_normalized(K, a), pb = pixel_of_normalized(K, b);
  const Vec2 chord = pb - pa;
  const double len = chord.norm();
  Deviation d;
  for (int k = 1; k < 256; ++k) {
    const double t = k / 256.0;
    const Vec2 c = pixel_of_normalized(K, a + t * (b - a));
    const Vec2 l = pa + t * chord;
    d.along_px = std::max(d.along_px, (c - l).norm());
    if (len > 0) d.across_px = std::max(d.across_px, std::abs(chord.x() * (c - pa).y() - chord.y() * (c - pa).x()) / len);
  }
  return d;
}

TEST(LensMesh, EveryDrawnEdgeIsWithinAQuarterPixelOfTheTrueCurve) {
  const CameraIntrinsics K;
  const LensGrids grids = make_lens_grids(K, kLensChordTolerance_px);
  EXPECT_LE(grids.edges.chord_bound_px, kLensChordTolerance_px);
  EXPECT_LE(grids.interior.chord_bound_px, kLensChordTolerance_px);
  std::cout << "[ lens grid ] edges " << grids.edges.cells.size() << " cells (bound "
            << grids.edges.chord_bound_px << " px), interior " << grids.interior.cells.size()
            << " cells (bound " << grids.interior.chord_bound_px << " px)" << std::endl;
  // Random convex quads (rectangles of random size, aspect and rotation) anywhere over and
  // beyond the region, split along each grid.
  std::mt19937_64 rng(16);
  std::uniform_real_distribution<double> uni(0.0, 1.0);
  const double x0 = grids.edges.x_min, x1 = grids.edges.x_max;
  const double y0 = grids.edges.y_min, y1 = grids.edges.y_max;
  for (const bool textured : {false, true}) {
    const LensGrid& g = textured ? grids.interior : grids.edges;
    double worst = 0.0, region_area = 0.0, piece_area = 0.0;
    long edges = 0;
    for (int trial = 0; trial < 400; ++trial) {
      const Vec2 c(x0 - 0.1 + (x1 - x0 + 0.2) * uni(rng), y0 - 0.1 + (y1 - y0 + 0.2) * uni(rng));
      const double length = 0.005 + 0.9 * uni(rng) * uni(rng), width = length * (0.02 + uni(rng));
      const double th = M_PI * uni(rng);
      const Vec2 e(std::cos(th), std::sin(th)), n(-std::sin(th), std::cos(th));
      const std::vector<Vec2> quad = {c - 0.5 * length * e - 0.5 * width * n, c + 0.5 * length * e - 0.5 * width * n,
                                      c + 0.5 * length * e + 0.5 * width * n, c - 0.5 * length * e + 0.5 * width * n};
      std::vector<Vec2> pieces;
      std::vector<int> sizes;
      split_by_grid(g, quad, pieces, sizes);
      std::size_t first = 0;
      for (int size : sizes) {
        const auto n_v = static_cast<std::size_t>(size);
        piece_area += area(pieces, first, n_v);
        for (std::size_t i = 0; i < n_v; ++i) {
          // Edges of the piece, and the fan diagonals from its first vertex.
          const Deviation d = deviation(K, pieces[first + i], pieces[first + (i + 1) % n_v]);
          worst = std::max(worst, textured ? d.along_px : d.across_px);
          if (i >= 2 && i + 1 < n_v) {
            const Deviation f = deviation(K, pieces[first], pieces[first + i]);
            worst = std::max(worst, textured ? f.along_px : f.across_px);
          }
          ++edges;
        }
        first += n_v;
      }
      // The pieces tile the quad's part inside the region: areas add up (no overlap, no gap).
      std::vector<Vec2> clipped;
      std::vector<int> one;
      const LensGrid region = LensGrid::one_cell(g.x_min, g.x_max, g.y_min, g.y_max);
      split_by_grid(region, quad, clipped, one);
      if (!one.empty()) region_area += area(clipped, 0, clipped.size());
    }
    std::cout << "[ lens " << (textured ? "interior" : "edges") << " ] " << edges
              << " piece edges, largest deviation " << worst << " px" << std::endl;
    EXPECT_LT(worst, 0.25);
    EXPECT_GT(edges, 1000);
    EXPECT_NEAR(piece_area, region_area, 1e-12 * std::max(1.0, region_area));
  }
}

// Pixel centres that no drawn triangle covers, when a quad larger than the region is split
// along `grid` and each piece drawn as its fan of chords (as LensMesher does): a crack between
// pieces (at a T-junction of a large cell with smaller ones, say) leaves some uncovered.
long uncovered_pixel_centres(const CameraIntrinsics& K, const LensGrid& grid) {
  const double mx = 0.1 * (grid.x_max - grid.x_min), my = 0.1 * (grid.y_max - grid.y_min);
  const std::vector<Vec2> quad = {{grid.x_min - mx, grid.y_min - my}, {grid.x_max + mx, grid.y_min - my},
                                  {grid.x_max + mx, grid.y_max + my}, {grid.x_min - mx, grid.y_max + my}};
  std::vector<Vec2> pieces;
  std::vector<int> sizes;
  split_by_grid(grid, quad, pieces, sizes);
  cv::Mat covered(K.height_px, K.width_px, CV_8UC1, cv::Scalar(0));
  std::size_t first = 0;
  for (int size : sizes) {
    for (int v = 1; v + 1 < size; ++v) {
      const Vec2 p[3] = {pixel_of_normalized(K, pieces[first]), pixel_of_normalized(K, pieces[first + static_cast<std::size_t>(v)]),
                         pixel_of_normalized(K, pieces[first + static_cast<std::size_t>(v) + 1])};
      const double area2 = (p[1] - p[0]).x() * (p[2] - p[0]).y() - (p[1] - p[0]).y() * (p[2] - p[0]).x();
      if (area2 == 0.0) continue;
      const int u0 = std::max(0, static_cast<int>(std::floor(std::min({p[0].x(), p[1].x(), p[2].x()}))));
      const int u1 = std::min(K.width_px - 1, static_cast<int>(std::ceil(std::max({p[0].x(), p[1].x(), p[2].x()}))));
      const int v0 = std::max(0, static_cast<int>(std::floor(std::min({p[0].y(), p[1].y(), p[2].y()}))));
      const int v1 = std::min(K.height_px - 1, static_cast<int>(std::ceil(std::max({p[0].y(), p[1].y(), p[2].y()}))));
      for (int y = v0; y <= v1; ++y) {
        for (int x = u0; x <= u1; ++x) {
          // Inside or on the boundary: the three edge functions share the triangle's sign.
          bool inside = true;
          for (int k = 0; k < 3 && inside; ++k) {
            const Vec2& a = p[k];
            const Vec2& b = p[(k + 1) % 3];
            const double e = (b.x() - a.x()) * (y - a.y()) - (b.y() - a.y()) * (x - a.x());
            inside = area2 > 0 ? e >= 0.0 : e <= 0.0;
          }
          if (inside) covered.at<std::uint8_t>(y, x) = 1;
        }
      }
    }
    first += static_cast<std::size_t>(size);
  }
  return static_cast<long>(covered.total()) - cv::countNonZero(covered);
}

TEST(LensMesh, AdaptiveCellsLeaveNoCrackAtTJunctions) {
  const CameraIntrinsics K;
  const LensGrids grids = make_lens_grids(K, kLensChordTolerance_px);
  for (const LensGrid* g : {&grids.edges, &grids.interior}) {
    // The grid is adaptive: cells of several sizes, so T-junctions (hanging points) exist.
    double smallest = std::numeric_limits<double>::infinity(), largest = 0.0;
    std::size_t hanging = 0;
    for (const LensGrid::Cell& c : g->cells) {
      const double d = std::hypot(K.fx_px * (c.x1 - c.x0), K.fy_px * (c.y1 - c.y0));
      smallest = std::min(smallest, d), largest = std::max(largest, d);
      for (const std::vector<double>& h : c.hanging) hanging += h.size();
    }
    EXPECT_GT(largest, 1.5 * smallest);
    EXPECT_GT(hanging, 0u);
    const long uncovered = uncovered_pixel_centres(K, *g);
    // The same split without the hanging points: the chords of a large cell's side and of its
    // smaller neighbours' sides part, and pixel centres fall between them.
    LensGrid without = *g;
    for (LensGrid::Cell& c : without.cells)
      for (std::vector<double>& h : c.hanging) h.clear();
    std::cout << "[ cracks ] " << g->cells.size() << " cells, diagonals " << smallest << " to " << largest
              << " px, " << hanging << " hanging points: " << uncovered
              << " pixel centres uncovered (without the hanging points: " << uncovered_pixel_centres(K, without)
              << ")" << std::endl;
    EXPECT_EQ(uncovered, 0);
  }
}

TEST(LensMesh, FrameVerticesAreWhereOpenCvProjectsTheirPoints) {
  const Warehouse w = test::paper_test_shelf();
  const CameraIntrinsics K;
  for (int supersample : {1, 2}) {
    RenderOptions o;
    o.supersample = supersample;
    Renderer r(w, K, o);
    const double s = supersample;
    for (const Eigen::Isometry3d& X_WC :
         {test::camera_looking_forward({0.8, 0.0, 0.98}), test::camera_looking_forward({2.4, 0.5, 0.6}, 0.6, -0.2)}) {
      r.render(X_WC);
      const LensMesher& m = r.lens_mesh();
      ASSERT_GT(m.vertices().size(), 100u);
      std::vector<cv::Point3d> pts;
      for (const Eigen::Vector3d& p : m.points_C()) pts.emplace_back(p.x(), p.y(), p.z());
      std::vector<cv::Point2d> px;
      const cv::Matx33d Kcv(K.fx_px, 0, K.cx_px, 0, K.fy_px, K.cy_px, 0, 0, 1);
      cv::projectPoints(pts, cv::Vec3d(0, 0, 0), cv::Vec3d(0, 0, 0), Kcv,
                        std::vector<double>{K.k1, K.k2, K.p1, K.p2, K.k3}, px);
      double worst = 0.0;
      for (std::size_t i = 0; i < m.vertices().size(); ++i) {
        // Back from GL's clip coordinates (float) to the 1x pixel: x_ndc = 2 (u_s + 0.5) / W_s - 1,
        // u_s = s u + (s - 1) / 2.
        const GpuVertex& v = m.vertices()[i];
        const double u_s = (v.clip[0] / v.clip[3] + 1.0) * 0.5 * s * K.width_px - 0.5;
        const double v_s = (v.clip[1] / v.clip[3] + 1.0) * 0.5 * s * K.height_px - 0.5;
        const cv::Point2d gl((u_s - 0.5 * (s - 1)) / s, (v_s - 0.5 * (s - 1)) / s);
        worst = std::max(worst, cv::norm(gl - px[i]));
        EXPECT_NEAR(v.clip[3], pts[i].z, 1e-6 * pts[i].z);  // w is the true depth
      }
      std::cout << "[ vertices, supersample " << supersample << " ] " << m.vertices().size()
                << " vertices, largest distance from cv::projectPoints " << worst << " px" << std::endl;
      EXPECT_LT(worst, 2e-3);  // float clip coordinates; GL snaps to 1/256 px anyway
    }
  }
}

// The nearest face hit by the ray through normalised point xy, or -1; its colour in rgb.
int ray_cast(const std::vector<MeshFace>& faces, const Eigen::Isometry3d& X_WC, const Vec2& xy,
             double near_m, double far_m, double& best_Z) {
  const Eigen::Vector3d d_W = X_WC.linear() * Eigen::Vector3d(xy.x(), xy.y(), 1.0);
  const Eigen::Vector3d o_W = X_WC.translation();
  int best = -1;
  best_Z = far_m;
  for (std::size_t f = 0; f < faces.size(); ++f) {
    const MeshFace& m = faces[f];
    const double side = m.normal_W.dot(o_W - m.corners_W_m[0]);
    const double denom = m.normal_W.dot(d_W);
    if (!(side > 1e-9) || !(denom < 0.0)) continue;
    const double Z = -side / denom;  // depth: d has unit z in C
    if (Z < near_m || Z >= best_Z) continue;
    const Eigen::Vector3d q = o_W + Z * d_W;
    bool inside = true;
    double sign = 0.0;
    for (int k = 0; k < 4 && inside; ++k) {
      const Eigen::Vector3d& a = m.corners_W_m[static_cast<std::size_t>(k)];
      const Eigen::Vector3d& b = m.corners_W_m[static_cast<std::size_t>((k + 1) % 4)];
      const double c = (b - a).cross(q - a).dot(m.normal_W);
      if (sign == 0.0) sign = c;
      inside = c * sign >= 0.0;
    }
    if (inside) best = static_cast<int>(f), best_Z = Z;
  }
  return best;
}

TEST(LensMesh, RenderedPixelsEqualARayCastAwayFromEdges) {
  const Warehouse w = test::paper_test_shelf();
  const CameraIntrinsics K;
  Renderer r(w, K);
  // One list of all faces; textured (marker) faces are in it for occlusion, but pixels that
  // show one are not compared (their colour depends on the texel).
  std::vector<MeshFace> faces;
  std::vector<bool> textured;
  for (FaceGroup g : {kRoomFaces, kFlatFaces, kDecalFaces, kTexturedFaces}) {
    for (const MeshFace& f : r.lens_mesh().faces(g)) {
      faces.push_back(f);
      textured.push_back(g == kTexturedFaces);
    }
  }
  std::mt19937_64 rng(7);
  // The last pose is close to the shelf: faces there are large enough that some solids'
  // outline triangles exceed the interior bound and go along the grid (both kinds compared).
  std::size_t grid_solids = 0;
  for (const Eigen::Isometry3d& X_WC :
       {test::camera_looking_forward({0.8, 0.0, 0.98}), test::camera_looking_forward({2.4, 0.5, 0.6}, 0.6, -0.2),
        test::camera_looking_forward({1.9, -0.3, 1.3}, -0.3, 0.35), test::camera_looking_forward({2.62, 0.05, 0.75}, 0.1, 0.1)}) {
    const cv::Mat img = r.render(X_WC);
    grid_solids = r.lens_mesh().grid_solids();
    int compared = 0, near_edges = 0, mismatched = 0;
    for (int k = 0; k < 6000; ++k) {
      const int u = static_cast<int>(rng() % static_cast<unsigned>(K.width_px));
      const int v = static_cast<int>(rng() % static_cast<unsigned>(K.height_px));
      // The face at the pixel centre and 0.3 px away in four directions: the same face at all
      // five means no drawn edge (within 0.25 px of its true place) can cross the centre.
      int face = -2;
      bool same = true;
      for (const auto& [du, dv] : {std::pair{0.0, 0.0}, {0.3, 0.0}, {-0.3, 0.0}, {0.0, 0.3}, {0.0, -0.3}}) {
        Vec2 xy;
        ASSERT_TRUE(undistort_normalized(K, {(u + du - K.cx_px) / K.fx_px, (v + dv - K.cy_px) / K.fy_px}, xy));
        double Z = 0.0;
        const int f = ray_cast(faces, X_WC, xy, r.options().near_m, r.options().far_m, Z);
        if (face == -2) face = f;
        same = same && f == face;
      }
      if (!same) {
        ++near_edges;
        continue;
      }
      if (face < 0 || textured[static_cast<std::size_t>(face)]) continue;
      ++compared;
      const Eigen::Vector3f& rgb = faces[static_cast<std::size_t>(face)].rgb;
      const cv::Vec3b got = img.at<cv::Vec3b>(v, u);
      bool ok = true;
      // Face colours are whole bytes k / 255 (renderer.cpp), so the pixel must be exactly k.
      for (int c = 0; c < 3; ++c) ok = ok && got[2 - c] == std::lround(255.0 * rgb[c]);
      if (!ok) {
        ++mismatched;
        ADD_FAILURE() << "pixel (" << u << ", " << v << ") is " << got << ", the ray cast gives face "
                      << face << " rgb " << rgb.transpose() * 255.0f;
        if (mismatched > 5) return;
      }
    }
    std::cout << "[ ray cast ] " << compared << " pixels compared, all equal; " << near_edges
              << " skipped within 0.3 px of an edge; " << grid_solids << " solids along the grid" << std::endl;
    EXPECT_GT(compared, 4000);
  }
  EXPECT_GT(grid_solids, 0u);
}

}  // namespace
}  // namespace shelfcross::render
