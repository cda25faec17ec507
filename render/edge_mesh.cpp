#include "render/edge_mesh.hpp"

#include <algorithm>
#include <limits>

namespace shelfcross::render {
namespace {

using Vec2 = Eigen::Vector2d;

// An edge is cut into at most this many parts whatever the bound says (far below a pixel
// for any edge inside the region).
constexpr int kMaxParts = 256;

// The points strictly between a and b (a < b in canonical order), in order from a, that cut
// a-b into the fewest equal parts k for which the bound holds on every part.
void cut(const LensStats& stats, double tolerance_px, const Vec2& a, const Vec2& b, std::vector<Vec2>& out) {
  int k = 1;
  for (; k < kMaxParts; ++k) {
    bool fits = true;
    for (int i = 0; i < k && fits; ++i)
      fits = stats.across_chord_px(a + (static_cast<double>(i) / k) * (b - a), a + (static_cast<double>(i + 1) / k) * (b - a)) <= tolerance_px;
    if (fits) break;
  }
  for (int i = 1; i < k; ++i) out.push_back(a + (static_cast<double>(i) / k) * (b - a));
}

bool canonical_less(const Vec2& a, const Vec2& b) {
  return a.x() < b.x() || (a.x() == b.x() && a.y() < b.y());
}

// Twice the signed area of triangle a b c (> 0: counter-clockwise in x right, y up terms).
double orient(const Vec2& a, const Vec2& b, const Vec2& c) {
  return (b.x() - a.x()) * (c.y() - a.y()) - (b.y() - a.y()) * (c.x() - a.x());
}

}  // namespace

void bisect_outline(const LensStats& stats, double tolerance_px, const std::vector<Vec2>& poly,
                    std::vector<Vec2>& out) {
  const std::size_t n = poly.size();
  for (std::size_t i = 0; i < n; ++i) {
    const Vec2& a = poly[i];
    const Vec2& b = poly[(i + 1) % n];
    out.push_back(a);
    const std::size_t first = out.size();
    // Cut in canonical order, so that the edge traversed the other way (by the other face of
    // a solid that shares it) gets the same points.
    if (canonical_less(a, b)) {
      cut(stats, tolerance_px, a, b, out);
    } else {
      cut(stats, tolerance_px, b, a, out);
      std::reverse(out.begin() + static_cast<std::ptrdiff_t>(first), out.end());
    }
  }
}

void triangulate_polygon(const std::vector<Vec2>& p, std::vector<int>& triangles) {
  const int n = static_cast<int>(p.size());
  if (n < 3) return;
  double area2 = 0.0;
  for (int i = 1; i + 1 < n; ++i) area2 += orient(p[0], p[static_cast<std::size_t>(i)], p[static_cast<std::size_t>(i + 1)]);
  if (area2 == 0.0) return;
  const double sign = area2 > 0.0 ? 1.0 : -1.0;
  // The ring as a doubly linked list (prev[i] = -1 once i is cut off); turn[i] = sign *
  // orient(prev, i, next): > 0 at a convex vertex. Only a non-convex vertex can lie inside an
  // ear's triangle (the triangle lies in the polygon's convex part around the ear), so only
  // those are tested: `reflex` lists them (cut or since turned convex ones are skipped).
  thread_local std::vector<int> prev, next, reflex;
  thread_local std::vector<double> turn;
  const auto N = static_cast<std::size_t>(n);
  prev.resize(N);
  next.resize(N);
  turn.resize(N);
  reflex.clear();
  auto P = [&](int i) -> const Vec2& { return p[static_cast<std::size_t>(i)]; };
  auto U = [](int i) { return static_cast<std::size_t>(i); };
  for (int i = 0; i < n; ++i) prev[U(i)] = (i + n - 1) % n, next[U(i)] = (i + 1) % n;
  auto update = [&](int i) {
    turn[U(i)] = sign * orient(P(prev[U(i)]), P(i), P(next[U(i)]));
    if (!(turn[U(i)] > 0.0)) reflex.push_back(i);
  };
  for (int i = 0; i < n; ++i) update(i);
  int head = 0;
  for (int left = n; left > 3; --left) {
    int best = -1;
    double best_side = std::numeric_limits<double>::infinity();
    int i = head;
    for (int k = 0; k < left; ++k, i = next[U(i)]) {
      if (!(turn[U(i)] > 0.0)) continue;
      const int a = prev[U(i)], c = next[U(i)];
      const double side = (P(c) - P(a)).squaredNorm();
      if (side >= best_side) continue;
      // An ear: no non-convex vertex inside or on its triangle.
      bool ear = true;
      for (std::size_t r = 0; r < reflex.size() && ear; ++r) {
        const int j = reflex[r];
        if (j == a || j == c || prev[U(j)] < 0 || turn[U(j)] > 0.0) continue;
        const Vec2& q = P(j);
        ear = !(sign * orient(P(a), P(i), q) >= 0.0 && sign * orient(P(i), P(c), q) >= 0.0 &&
                sign * orient(P(c), P(a), q) >= 0.0);
      }
      if (ear) best = i, best_side = side;
    }
    if (best < 0) {
      // No ear within rounding (a polygon thinner than its points' precision): cut the most
      // convex vertex.
      best = head;
      for (int k = 0, j = head; k < left; ++k, j = next[U(j)])
        if (turn[U(j)] > turn[U(best)]) best = j;
    }
    const int a = prev[U(best)], c = next[U(best)];
    triangles.insert(triangles.end(), {a, best, c});
    next[U(a)] = c;
    prev[U(c)] = a;
    prev[U(best)] = -1;
    if (head == best) head = c;
    update(a);
    update(c);
  }
  triangles.insert(triangles.end(), {prev[U(head)], head, next[U(head)]});
}

}  // namespace shelfcross::render
