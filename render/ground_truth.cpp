#include "render/ground_truth.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "render/camera_model.hpp"

namespace shelfcross::render {
namespace {

// Does the segment a + t (b - a), t in [0, 1 - 1e-7], meet the box [lo, hi]? (slab test)
bool segment_hits_box(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& lo,
                      const Eigen::Vector3d& hi) {
  const Eigen::Vector3d d = b - a;
  double t_in = 0.0, t_out = 1.0 - 1e-7;
  for (int k = 0; k < 3; ++k) {
    if (std::abs(d[k]) < 1e-15) {
      if (a[k] < lo[k] || a[k] > hi[k]) return false;
      continue;
    }
    double t1 = (lo[k] - a[k]) / d[k], t2 = (hi[k] - a[k]) / d[k];
    if (t1 > t2) std::swap(t1, t2);
    t_in = std::max(t_in, t1);
    t_out = std::min(t_out, t2);
    if (t_in > t_out) return false;
  }
  return true;
}

// Does the segment meet the parallelogram TL, TR, BL (corners c[0], c[1], c[3])?
bool segment_hits_square(const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                         const std::array<Eigen::Vector3d, 4>& c) {
  const Eigen::Vector3d e1 = c[1] - c[0], e2 = c[3] - c[0];
  const Eigen::Vector3d n = e1.cross(e2);
  const double denom = n.dot(b - a);
  if (std::abs(denom) < 1e-15) return false;
  const double t = n.dot(c[0] - a) / denom;
  if (t <= 0.0 || t >= 1.0 - 1e-7) return false;
  const Eigen::Vector3d q = a + t * (b - a) - c[0];
  const double s1 = q.dot(e1) / e1.squaredNorm(), s2 = q.dot(e2) / e2.squaredNorm();
  return s1 >= 0.0 && s1 <= 1.0 && s2 >= 0.0 && s2 <= 1.0;
}

// Point at (s, t) in [0,1]^2 of the quad TL TR BR BL (bilinear; exact for a square).
Eigen::Vector3d quad_point(const std::array<Eigen::Vector3d, 4>& c, double s, double t) {
  return (1 - t) * ((1 - s) * c[0] + s * c[1]) + t * ((1 - s) * c[3] + s * c[2]);
}

}  // namespace

GroundTruthProjector::GroundTruthProjector(const Warehouse& warehouse,
                                           const CameraIntrinsics& intrinsics, double near_m)
    : layout_(build_scene_layout(warehouse)), K_(intrinsics), near_m_(near_m) {
  // Undistorted footprint of the image border, grown by 10 % on each side: the region where
  // the distortion polynomial is trusted (monotone over the image by construction).
  xy_min_ = Eigen::Vector2d::Constant(std::numeric_limits<double>::infinity());
  xy_max_ = -xy_min_;
  auto add = [&](double u, double v) {
    Eigen::Vector2d xy;
    if (undistort_normalized(K_, {(u - K_.cx_px) / K_.fx_px, (v - K_.cy_px) / K_.fy_px}, xy)) {
      xy_min_ = xy_min_.cwiseMin(xy);
      xy_max_ = xy_max_.cwiseMax(xy);
    }
  };
  const double W = K_.width_px - 0.5, H = K_.height_px - 0.5;
  for (int k = 0; k <= 64; ++k) {
    const double f = k / 64.0;
    add(-0.5 + f * (W + 0.5), -0.5);
    add(-0.5 + f * (W + 0.5), H);
    add(-0.5, -0.5 + f * (H + 0.5));
    add(W, -0.5 + f * (H + 0.5));
  }
  const Eigen::Vector2d grow = 0.1 * (xy_max_ - xy_min_);
  xy_min_ -= grow;
  xy_max_ += grow;
}

std::optional<cv::Point2d> GroundTruthProjector::project(const Eigen::Vector3d& p_W_m,
                                                         const Eigen::Isometry3d& X_WC) const {
  const Eigen::Vector3d p_C = X_WC.inverse(Eigen::Isometry) * p_W_m;
  if (!(p_C.z() > near_m_)) return std::nullopt;
  const Eigen::Vector2d xy(p_C.x() / p_C.z(), p_C.y() / p_C.z());
  if ((xy.array() < xy_min_.array()).any() || (xy.array() > xy_max_.array()).any())
    return std::nullopt;
  const Eigen::Vector2d px = project_camera_point(K_, p_C);
  return cv::Point2d(px.x(), px.y());
}

bool GroundTruthProjector::in_image(const cv::Point2d& px) const {
  return px.x >= 0.0 && px.y >= 0.0 && px.x <= K_.width_px - 1.0 && px.y <= K_.height_px - 1.0;
}

bool GroundTruthProjector::occluded(const Eigen::Vector3d& p_W_m, const Eigen::Vector3d& p_WC_m,
                                    int skip_tag) const {
  // Cuboids are axis-aligned in their shelf frame: test there.
  std::vector<Eigen::Vector3d> a_S(layout_.X_WS.size()), b_S(layout_.X_WS.size());
  for (size_t s = 0; s < layout_.X_WS.size(); ++s) {
    const Eigen::Isometry3d X_SW = layout_.X_WS[s].inverse(Eigen::Isometry);
    a_S[s] = X_SW * p_WC_m;
    b_S[s] = X_SW * p_W_m;
  }
  for (const Cuboid& c : layout_.cuboids) {
    const auto s = static_cast<size_t>(c.shelf);
    if (segment_hits_box(a_S[s], b_S[s], c.min_S_m, c.max_S_m)) return true;
  }
  for (size_t t = 0; t < layout_.tags.size(); ++t) {
    if (static_cast<int>(t) == skip_tag) continue;
    if (segment_hits_square(p_WC_m, p_W_m, layout_.tags[t].corners_W_m)) return true;
  }
  return false;
}

std::vector<TagProjection> GroundTruthProjector::tags(const Eigen::Isometry3d& X_WC) const {
  const Eigen::Vector3d p_WC = X_WC.translation();
  std::vector<TagProjection> out;
  out.reserve(layout_.tags.size());
  for (size_t ti = 0; ti < layout_.tags.size(); ++ti) {
    const TagQuad& q = layout_.tags[ti];
    TagProjection t;
    t.shelf = q.shelf;
    t.front_face = q.front_face;
    t.column_boundary = q.column_boundary;
    t.level_boundary = q.level_boundary;
    t.p_W_m = q.centre_W_m;
    t.facing = q.normal_W.dot(p_WC - q.centre_W_m) > 0.0;
    t.in_front = true;
    t.in_image = true;
    const auto centre = project(q.centre_W_m, X_WC);
    if (centre) t.pixel = *centre;
    t.in_front = t.in_front && centre.has_value();
    for (size_t k = 0; k < 4; ++k) {
      const auto c = project(q.corners_W_m[k], X_WC);
      t.in_front = t.in_front && c.has_value();
      if (c) {
        t.corners[k] = *c;
        t.in_image = t.in_image && in_image(*c);
      }
    }
    t.in_image = t.in_image && t.in_front;
    if (t.in_front) {
      // Area centroid over 16 x 16 patches (shoelace on each projected patch).
      constexpr int n = 16;
      std::array<std::array<cv::Point2d, n + 1>, n + 1> g;
      bool ok = true;
      for (int i = 0; i <= n && ok; ++i)
        for (int j = 0; j <= n && ok; ++j) {
          const auto p = project(quad_point(q.corners_W_m, double(i) / n, double(j) / n), X_WC);
          ok = p.has_value();
          if (ok) g[i][j] = *p;
        }
      double area = 0.0, cx = 0.0, cy = 0.0;
      for (int i = 0; i < n && ok; ++i)
        for (int j = 0; j < n; ++j) {
          const cv::Point2d poly[4] = {g[i][j], g[i + 1][j], g[i + 1][j + 1], g[i][j + 1]};
          for (int k = 0; k < 4; ++k) {
            const cv::Point2d& p0 = poly[k];
            const cv::Point2d& p1 = poly[(k + 1) % 4];
            const double cr = p0.x * p1.y - p1.x * p0.y;
            area += cr;
            cx += (p0.x + p1.x) * cr;
            cy += (p0.y + p1.y) * cr;
          }
        }
      if (ok && std::abs(area) > 1e-12) {
        t.area_centroid = {cx / (3.0 * area), cy / (3.0 * area)};
        t.area_px2 = 0.5 * std::abs(area);
      } else {
        t.area_centroid = t.pixel;
      }
    }
    if (t.in_front && t.facing && t.in_image) {
      for (int i = 0; i < 5 && !t.occluded; ++i)
        for (int j = 0; j < 5 && !t.occluded; ++j)
          t.occluded = occluded(quad_point(q.corners_W_m, 0.01 + 0.245 * i, 0.01 + 0.245 * j), p_WC,
                                static_cast<int>(ti));
    }
    t.visible = t.in_front && t.facing && t.in_image && !t.occluded;
    out.push_back(t);
  }
  return out;
}

std::vector<MarkerProjection> GroundTruthProjector::markers(const Eigen::Isometry3d& X_WC) const {
  const Eigen::Vector3d p_WC = X_WC.translation();
  std::vector<MarkerProjection> out;
  out.reserve(layout_.markers.size());
  for (const MarkerQuad& q : layout_.markers) {
    MarkerProjection m;
    m.shelf = q.shelf;
    m.level = q.level;
    m.column = q.column;
    m.marker_id = q.marker_id;
    m.front_face = q.front_face;
    m.corners_W_m = q.corners_W_m;
    m.facing = q.normal_W.dot(p_WC - q.centre_W_m) > 0.0;
    m.in_front = true;
    m.in_image = true;
    for (size_t k = 0; k < 4; ++k) {
      const auto c = project(q.corners_W_m[k], X_WC);
      m.in_front = m.in_front && c.has_value();
      if (c) {
        m.corners[k] = *c;
        m.in_image = m.in_image && in_image(*c);
      }
    }
    m.in_image = m.in_image && m.in_front;
    if (m.in_front && m.facing && m.in_image) {
      for (int i = 0; i < 5 && !m.occluded; ++i)
        for (int j = 0; j < 5 && !m.occluded; ++j)
          m.occluded = occluded(quad_point(q.corners_W_m, 0.01 + 0.245 * i, 0.01 + 0.245 * j), p_WC);
    }
    m.visible = m.in_front && m.facing && m.in_image && !m.occluded;
    out.push_back(m);
  }
  return out;
}

Eigen::Isometry3d camera_pose_W(const Eigen::Isometry3d& X_WB, const CameraMount& mount) {
  Eigen::Isometry3d X_BC = Eigen::Isometry3d::Identity();
  X_BC.linear() = rotation_body_from_camera(mount.pitch_rad);
  X_BC.translation() = mount.p_BC_B_m;
  return X_WB * X_BC;
}

}  // namespace shelfcross::render
