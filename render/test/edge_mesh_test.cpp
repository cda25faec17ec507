// Flat faces meshed along their own edges (edge_mesh.hpp), against the fidelity conditions:
//   - every drawn outline chord lies within 0.25 px of the true (curved) image of its edge,
//     measured densely along the curve;
//   - the triangles tile the outline's image exactly (areas add up, none turned over);
//   - two faces sharing an edge get the same points on it;
//   - pixel coverage: every pixel centre whose neighbourhood (0.26 px each way) lies inside the
//     true image of a face is covered, and every one whose neighbourhood lies outside is not.
#include <gtest/gtest.h>

#include <array>
#include <iostream>
#include <random>

#include "render/camera_model.hpp"
#include "render/edge_mesh.hpp"
#include "render/lens_mesh.hpp"
#include "render/renderer.hpp"

namespace shelfcross::render {
namespace {

using Vec2 = Eigen::Vector2d;

double signed_area(const Vec2& a, const Vec2& b, const Vec2& c) {
  return 0.5 * ((b - a).x() * (c - a).y() - (b - a).y() * (c - a).x());
}

// The largest distance across the chord of the lens image of a-b, from 257 points.
double across_px(const CameraIntrinsics& K, const Vec2& a, const Vec2& b) {
  const Vec2 pa = pixel_of_normalized(K, a), pb = pixel_of_normalized(K, b), chord = pb - pa;
  const double len = chord.norm();
  double worst = 0.0;
  for (int k = 1; k < 256 && len > 0; ++k) {
    const Vec2 c = pixel_of_normalized(K, a + k / 256.0 * (b - a)) - pa;
    worst = std::max(worst, std::abs(chord.x() * c.y() - chord.y() * c.x()) / len);
  }
  return worst;
}

// A random rectangle (size, aspect, rotation) over and beyond the region, clipped to it.
std::vector<Vec2> random_face(std::mt19937_64& rng, const LensGrid& g) {
  std::uniform_real_distribution<double> uni(0.0, 1.0);
  const Vec2 c(g.x_min - 0.1 + (g.x_max - g.x_min + 0.2) * uni(rng), g.y_min - 0.1 + (g.y_max - g.y_min + 0.2) * uni(rng));
  const double length = 0.005 + 0.9 * uni(rng) * uni(rng), width = length * (0.02 + uni(rng));
  const double th = M_PI * uni(rng);
  const Vec2 e(std::cos(th), std::sin(th)), n(-std::sin(th), std::cos(th));
  const std::vector<Vec2> quad = {c - 0.5 * length * e - 0.5 * width * n, c + 0.5 * length * e - 0.5 * width * n,
                                  c + 0.5 * length * e + 0.5 * width * n, c - 0.5 * length * e + 0.5 * width * n};
  std::vector<Vec2> clipped;
  std::vector<int> sizes;
  split_by_grid(LensGrid::one_cell(g.x_min, g.x_max, g.y_min, g.y_max), quad, clipped, sizes);
  return clipped;
}

TEST(LensMeshOutline, ChordsWithinAQuarterPixelAndTrianglesTileTheOutline) {
  const CameraIntrinsics K;
  const LensGrids grids = make_lens_grids(K, kLensChordTolerance_px);
  std::mt19937_64 rng(29);
  double worst = 0.0, worst_area = 0.0;
  long chords = 0, faces = 0, points = 0;
  for (int trial = 0; trial < 600; ++trial) {
    const std::vector<Vec2> poly = random_face(rng, grids.edges);
    if (poly.size() < 3) continue;
    ++faces;
    std::vector<Vec2> outline, px;
    bisect_outline(grids.stats, kLensChordTolerance_px, poly, outline);
    points += static_cast<long>(outline.size());
    for (std::size_t i = 0; i < outline.size(); ++i) {
      worst = std::max(worst, across_px(K, outline[i], outline[(i + 1) % outline.size()]));
      ++chords;
      px.push_back(pixel_of_normalized(K, outline[i]));
    }
    std::vector<int> tri;
    triangulate_polygon(px, tri);
    double polygon = 0.0;
    for (std::size_t i = 1; i + 1 < px.size(); ++i) polygon += signed_area(px[0], px[i], px[i + 1]);
    ASSERT_EQ(tri.size(), 3 * (px.size() - 2));
    double sum = 0.0, turned = 0.0;
    for (std::size_t t = 0; t < tri.size(); t += 3) {
      const double a = signed_area(px[static_cast<std::size_t>(tri[t])], px[static_cast<std::size_t>(tri[t + 1])],
                                   px[static_cast<std::size_t>(tri[t + 2])]);
      sum += std::abs(a);
      if (a * polygon < 0.0) turned += std::abs(a);
    }
    EXPECT_EQ(turned, 0.0) << "trial " << trial;
    worst_area = std::max(worst_area, std::abs(sum - std::abs(polygon)) / std::max(1.0, std::abs(polygon)));
  }
  std::cout << "[ outline ] " << faces << " faces, " << points << " outline points, " << chords
            << " chords, largest distance across " << worst << " px; triangle areas off by "
            << worst_area << " of the polygon's" << std::endl;
  EXPECT_GT(faces, 400);
  EXPECT_LT(worst, kLensChordTolerance_px);
  EXPECT_LT(worst_area, 1e-9);
}

TEST(LensMeshOutline, FacesSharingAnEdgeGetTheSamePointsOnIt) {
  const CameraIntrinsics K;
  const LensGrids grids = make_lens_grids(K, kLensChordTolerance_px);
  // Two quads on either side of the long edge p-q, which they traverse in opposite
  // directions (as two faces of one solid do).
  const Vec2 p(-0.55, -0.3), q(0.52, 0.37), up(0.0, -0.2), down(0.0, 0.25);
  std::vector<Vec2> a, b;
  bisect_outline(grids.stats, kLensChordTolerance_px, {p, q, q + down, p + down}, a);
  bisect_outline(grids.stats, kLensChordTolerance_px, {q, p, p + up, q + up}, b);
  // a: p, (points of p-q), q, ...; b: q, (points of q-p), p, ...
  std::vector<Vec2> on_a, on_b;
  for (std::size_t i = 1; a[i] != q; ++i) on_a.push_back(a[i]);
  for (std::size_t i = 1; b[i] != p; ++i) on_b.push_back(b[i]);
  std::reverse(on_b.begin(), on_b.end());
  ASSERT_GT(on_a.size(), 2u);
  ASSERT_EQ(on_a.size(), on_b.size());
  for (std::size_t i = 0; i < on_a.size(); ++i) EXPECT_TRUE(on_a[i] == on_b[i]) << i;  // bit for bit
}

// Whether normalised point xy is inside the convex polygon (either orientation).
bool inside(const std::vector<Vec2>& poly, const Vec2& xy) {
  double sign = 0.0;
  for (std::size_t i = 0; i < poly.size(); ++i) {
    const double c = signed_area(poly[i], poly[(i + 1) % poly.size()], xy);
    if (c == 0.0) continue;
    if (sign == 0.0) sign = c;
    if (c * sign < 0.0) return false;
  }
  return true;
}

TEST(LensMeshOutline, CoveredPixelsAreThoseInsideTheTrueImage) {
  const CameraIntrinsics K;
  const LensGrids grids = make_lens_grids(K, kLensChordTolerance_px);
  // Every other pixel's centre and its four neighbours 0.26 px away, undistorted once.
  constexpr int kStride = 2;
  const std::pair<double, double> offsets[5] = {{0.0, 0.0}, {0.26, 0.0}, {-0.26, 0.0}, {0.0, 0.26}, {0.0, -0.26}};
  std::vector<std::array<Vec2, 5>> around;
  for (int v = 0; v < K.height_px; v += kStride) {
    for (int u = 0; u < K.width_px; u += kStride) {
      std::array<Vec2, 5>& a = around.emplace_back();
      for (int k = 0; k < 5; ++k)
        ASSERT_TRUE(undistort_normalized(K, {(u + offsets[k].first - K.cx_px) / K.fx_px,
                                             (v + offsets[k].second - K.cy_px) / K.fy_px}, a[static_cast<std::size_t>(k)]));
    }
  }
  std::mt19937_64 rng(7);
  long checked = 0, wrong = 0;
  for (int trial = 0; trial < 12; ++trial) {
    const std::vector<Vec2> poly = random_face(rng, grids.edges);
    if (poly.size() < 3) continue;
    std::vector<Vec2> outline, px;
    bisect_outline(grids.stats, kLensChordTolerance_px, poly, outline);
    for (const Vec2& xy : outline) px.push_back(pixel_of_normalized(K, xy));
    std::vector<int> tri;
    triangulate_polygon(px, tri);
    std::size_t k = 0;
    for (int v = 0; v < K.height_px; v += kStride) {
      for (int u = 0; u < K.width_px; u += kStride, ++k) {
        // The true answer where it does not depend on where within 0.26 px the edge is.
        int in = 0;
        for (const Vec2& xy : around[k]) in += inside(poly, xy) ? 1 : 0;
        if (in != 0 && in != 5) continue;
        // Covered: inside or on some triangle.
        bool covered = false;
        const Vec2 c(u, v);
        for (std::size_t t = 0; t < tri.size() && !covered; t += 3) {
          const Vec2& a = px[static_cast<std::size_t>(tri[t])];
          const Vec2& b = px[static_cast<std::size_t>(tri[t + 1])];
          const Vec2& d = px[static_cast<std::size_t>(tri[t + 2])];
          const double s = signed_area(a, b, d);
          if (s == 0.0) continue;
          covered = signed_area(a, b, c) * s >= 0.0 && signed_area(b, d, c) * s >= 0.0 && signed_area(d, a, c) * s >= 0.0;
        }
        ++checked;
        if (covered != (in == 5) && ++wrong <= 5)
          ADD_FAILURE() << "trial " << trial << " pixel (" << u << ", " << v << ") covered " << covered;
      }
    }
  }
  std::cout << "[ outline coverage ] " << checked << " pixel centres away from edges, " << wrong << " wrong" << std::endl;
  EXPECT_GT(checked, 1500000);
  EXPECT_EQ(wrong, 0);
}

}  // namespace
}  // namespace shelfcross::render
