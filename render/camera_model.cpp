#include "render/camera_model.hpp"

namespace shelfcross::render {

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
  return pixel_of_normalized(K, {p_C.x() / p_C.z(), p_C.y() / p_C.z()});
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
