#pragma once
// The camera model shared by the renderer and the ground-truth projector: OpenCV's pinhole
// with plumb-bob distortion (k1 k2 p1 p2 k3), pixel centres at integer coordinates.
//
// A point p_C = (X, Y, Z) in the camera frame C (x right, y down, z forward) with Z > 0 has
// normalised coordinates x = X/Z, y = Y/Z, r^2 = x^2 + y^2, and distorted coordinates
//   x_d = x (1 + k1 r^2 + k2 r^4 + k3 r^6) + 2 p1 x y + p2 (r^2 + 2 x^2)
//   y_d = y (1 + k1 r^2 + k2 r^4 + k3 r^6) + p1 (r^2 + 2 y^2) + 2 p2 x y
// and pixel u = fx x_d + cx, v = fy y_d + cy (the formula of cv::projectPoints).

#include <Eigen/Core>

#include "shelfcross/camera.hpp"

namespace shelfcross::render {

// distort_normalized and pixel_of_normalized run several times for every vertex of every
// frame (the lens mesher, the rolling shutter's moves): inline, so that a call costs no more
// than its few multiplications. Inlined or not, the same operations run in the same order
// (no fast-math, no fused multiply-adds on the baseline x86-64 target): the same bits.

/// Plumb-bob distortion of normalised coordinates (x, y) -> (x_d, y_d).
inline Eigen::Vector2d distort_normalized(const CameraIntrinsics& K, const Eigen::Vector2d& xy) {
  const double x = xy.x(), y = xy.y();
  const double r2 = x * x + y * y;
  const double radial = 1.0 + r2 * (K.k1 + r2 * (K.k2 + r2 * K.k3));
  return {x * radial + 2.0 * K.p1 * x * y + K.p2 * (r2 + 2.0 * x * x),
          y * radial + K.p1 * (r2 + 2.0 * y * y) + 2.0 * K.p2 * x * y};
}

/// Inverse of distort_normalized by fixed-point iteration (as cv::undistortPoints, but run to
/// convergence: |distort(result) - xy_d| < 1e-13 or 200 iterations). Returns false if it did
/// not converge (a lens model that is not invertible there).
bool undistort_normalized(const CameraIntrinsics& K, const Eigen::Vector2d& xy_d,
                          Eigen::Vector2d& xy);

/// Pixel of normalised coordinates (x, y) = (X/Z, Y/Z): distortion then K.
inline Eigen::Vector2d pixel_of_normalized(const CameraIntrinsics& K, const Eigen::Vector2d& xy) {
  const Eigen::Vector2d d = distort_normalized(K, xy);
  return {K.fx_px * d.x() + K.cx_px, K.fy_px * d.y() + K.cy_px};
}

/// Pixel of a camera-frame point (Z must be > 0): pixel_of_normalized(X/Z, Y/Z).
Eigen::Vector2d project_camera_point(const CameraIntrinsics& K, const Eigen::Vector3d& p_C);

/// The OpenGL clip-from-camera matrix (column-major, for glUniformMatrix4fv) of a pinhole
/// camera (fx, fy, cx, cy, width, height) looking along +z_C, with depth range [near, far].
///
/// OpenCV's pixel u has its centre at u; GL's window pixel i has its centre at i + 0.5, so
///   x_ndc = (2 (u + 0.5)) / W - 1 with u = fx X/Z + cx.
/// Rows are NOT flipped here: image row v is written to GL row v (y_ndc = 2 (v + 0.5)/H - 1),
/// so the image is upside down in GL terms and glReadPixels, which returns the bottom GL row
/// first, hands back rows already in image order (top row first) with no flip pass.
/// clip w = Z; z_ndc = (f + n)/(f - n) - 2 f n / ((f - n) Z): -1 at Z = n, +1 at Z = f.
Eigen::Matrix4d gl_clip_from_camera(double fx, double fy, double cx, double cy, int width,
                                    int height, double near_m, double far_m);

}  // namespace shelfcross::render
