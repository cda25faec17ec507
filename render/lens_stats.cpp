#include "render/lens_stats.hpp"

namespace shelfcross::render {

using Vec2 = Eigen::Vector2d;

double LensStats::across_chord_px(const Vec2& a, const Vec2& b) const {
  const Stats st = over(std::min(a.x(), b.x()), std::max(a.x(), b.x()), std::min(a.y(), b.y()),
                        std::max(a.y(), b.y()));
  const double L = (b - a).norm();
  return L * L / 8.0 * (st.Mp + L * st.Mf * st.Mf / st.Jmin);
}

double LensStats::interior_px(const Vec2& a, const Vec2& b, const Vec2& c) const {
  // The smallest disc holding a triangle: on its longest side as diameter when the angle
  // opposite is not acute, else the circumscribed one (R = abc / (4 area)).
  const double ab = (b - a).squaredNorm(), bc = (c - b).squaredNorm(), ca = (a - c).squaredNorm();
  const double longest = std::max({ab, bc, ca});
  double r2 = 0.25 * longest;
  if (2.0 * longest < ab + bc + ca) {  // acute: the longest side's square < the sum of the others'
    const Vec2 u = b - a, v = c - a;
    const double area2 = std::abs(u.x() * v.y() - u.y() * v.x());
    r2 = ab * bc * ca / (4.0 * area2 * area2);  // R = abc / (2 |u x v|)
  }
  const Stats st = over(std::min({a.x(), b.x(), c.x()}), std::max({a.x(), b.x(), c.x()}),
                        std::min({a.y(), b.y(), c.y()}), std::max({a.y(), b.y(), c.y()}));
  return 0.5 * st.Mf * r2;
}

}  // namespace shelfcross::render
