#include "render/camera_model.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

#include "render/render_error.hpp"

namespace shelfcross::render {

Eigen::Vector2d distort_normalized(const CameraIntrinsics& K, const Eigen::Vector2d& xy) {
  const double x = xy.x(), y = xy.y();
  const double r2 = x * x + y * y;
  const double radial = 1.0 + r2 * (K.k1 + r2 * (K.k2 + r2 * K.k3));
  return {x * radial + 2.0 * K.p1 * x * y + K.p2 * (r2 + 2.0 * x * x),
          y * radial + K.p1 * (r2 + 2.0 * y * y) + 2.0 * K.p2 * x * y};
}

bool undistort_normalized(const CameraIntrinsics& K, const Eigen::Vector2d& xy_d,
                          Eigen::Vector2d& xy) {
  // Fixed point of x = (x_d - tangential(x)) / radial(x), started at x_d; then a check that
  // distorting the result gives back x_d.
  Eigen::Vector2d p = xy_d;
  for (int it = 0; it < 200; ++it) {
    const double x = p.x(), y = p.y();
    const double r2 = x * x + y * y;
    const double radial = 1.0 + r2 * (K.k1 + r2 * (K.k2 + r2 * K.k3));
    if (!(radial > 1e-6)) return false;
    const double dx = 2.0 * K.p1 * x * y + K.p2 * (r2 + 2.0 * x * x);
    const double dy = K.p1 * (r2 + 2.0 * y * y) + 2.0 * K.p2 * x * y;
    p = Eigen::Vector2d((xy_d.x() - dx) / radial, (xy_d.y() - dy) / radial);
    if ((distort_normalized(K, p) - xy_d).norm() < 1e-13) break;
  }
  xy = p;
  return (distort_normalized(K, p) - xy_d).norm() < 1e-9;
}

Eigen::Vector2d project_camera_point(const CameraIntrinsics& K, const Eigen::Vector3d& p_C) {
  const Eigen::Vector2d d = distort_normalized(K, {p_C.x() / p_C.z(), p_C.y() / p_C.z()});
  return {K.fx_px * d.x() + K.cx_px, K.fy_px * d.y() + K.cy_px};
}

RenderCamera make_render_camera(const CameraIntrinsics& K, int margin_px) {
  if (K.width_px <= 0 || K.height_px <= 0 || !(K.fx_px > 0) || !(K.fy_px > 0)) {
    std::ostringstream os;
    os << "camera intrinsics invalid: need width, height, fx, fy > 0 (got " << K.width_px << " x "
       << K.height_px << ", fx " << K.fx_px << ", fy " << K.fy_px << ")";
    throw RenderError(os.str());
  }
  RenderCamera rc;
  rc.fx_px = K.fx_px;
  rc.fy_px = K.fy_px;
  // Undistort every output pixel centre once; keep the normalised coordinates.
  const int W = K.width_px, H = K.height_px;
  cv::Mat xy_n(H, W, CV_64FC2);
  double x_min = std::numeric_limits<double>::infinity(), x_max = -x_min;
  double y_min = x_min, y_max = -x_min;
  double worst = 0.0;
  for (int v = 0; v < H; ++v) {
    auto* row = xy_n.ptr<cv::Vec2d>(v);
    for (int u = 0; u < W; ++u) {
      const Eigen::Vector2d xy_d((u - K.cx_px) / K.fx_px, (v - K.cy_px) / K.fy_px);
      Eigen::Vector2d xy;
      if (!undistort_normalized(K, xy_d, xy)) {
        std::ostringstream os;
        os << "lens distortion (k1 " << K.k1 << ", k2 " << K.k2 << ", p1 " << K.p1 << ", p2 "
           << K.p2 << ", k3 " << K.k3 << ") cannot be inverted at pixel (" << u << ", " << v
           << "): the model folds over inside the image";
        throw RenderError(os.str());
      }
      const Eigen::Vector2d back = distort_normalized(K, xy);
      worst = std::max(worst, std::hypot((back.x() - xy_d.x()) * K.fx_px,
                                         (back.y() - xy_d.y()) * K.fy_px));
      row[u] = cv::Vec2d(xy.x(), xy.y());
      x_min = std::min(x_min, xy.x());
      x_max = std::max(x_max, xy.x());
      y_min = std::min(y_min, xy.y());
      y_max = std::max(y_max, xy.y());
    }
  }
  rc.max_roundtrip_error_px = worst;
  // Render pixel u' = fx x + cx'. Put x_min at margin px and size to x_max + margin.
  rc.cx_px = std::floor(margin_px - K.fx_px * x_min) + (K.cx_px - std::floor(K.cx_px));
  rc.cy_px = std::floor(margin_px - K.fy_px * y_min) + (K.cy_px - std::floor(K.cy_px));
  rc.width_px = static_cast<int>(std::ceil(K.fx_px * x_max + rc.cx_px + margin_px)) + 1;
  rc.height_px = static_cast<int>(std::ceil(K.fy_px * y_max + rc.cy_px + margin_px)) + 1;
  rc.map_xy.create(H, W, CV_32FC2);
  for (int v = 0; v < H; ++v) {
    const auto* src = xy_n.ptr<cv::Vec2d>(v);
    auto* dst = rc.map_xy.ptr<cv::Vec2f>(v);
    for (int u = 0; u < W; ++u) {
      dst[u] = cv::Vec2f(static_cast<float>(rc.fx_px * src[u][0] + rc.cx_px),
                         static_cast<float>(rc.fy_px * src[u][1] + rc.cy_px));
    }
  }
  return rc;
}

Eigen::Matrix4d gl_clip_from_camera(double fx, double fy, double cx, double cy, int width,
                                    int height, double near_m, double far_m) {
  const double W = width, H = height;
  Eigen::Matrix4d P = Eigen::Matrix4d::Zero();
  // x_ndc = (2 (fx X/Z + cx) + 1)/W - 1  ->  x_clip = (2 fx / W) X + ((2 cx + 1)/W - 1) Z
  P(0, 0) = 2.0 * fx / W;
  P(0, 2) = (2.0 * cx + 1.0) / W - 1.0;
  // y_ndc = (2 (fy Y/Z + cy) + 1)/H - 1 (image row v -> GL row v, see header)
  P(1, 1) = 2.0 * fy / H;
  P(1, 2) = (2.0 * cy + 1.0) / H - 1.0;
  P(2, 2) = (far_m + near_m) / (far_m - near_m);
  P(2, 3) = -2.0 * far_m * near_m / (far_m - near_m);
  P(3, 2) = 1.0;
  return P;
}

}  // namespace shelfcross::render
