#include "render/rolling_shutter.hpp"

#include <algorithm>
#include <cmath>

#include "render/lens_mesh.hpp"

namespace shelfcross::render {

Eigen::Isometry3d interpolate_pose(const Eigen::Isometry3d& X0, const Eigen::Isometry3d& X1, double s) {
  const Eigen::Quaterniond q0(X0.linear()), q1(X1.linear());
  Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
  X.linear() = q0.slerp(s, q1).normalized().toRotationMatrix();
  X.translation() = (1.0 - s) * X0.translation() + s * X1.translation();
  return X;
}

ReadoutPoses::ReadoutPoses(const Eigen::Isometry3d& X_WC_start, const Eigen::Isometry3d& X_WC_end)
    : still_(X_WC_start.matrix() == X_WC_end.matrix()) {
  for (int k = 0; k <= kSteps; ++k) {
    const Eigen::Isometry3d X_WC = interpolate_pose(X_WC_start, X_WC_end, static_cast<double>(k) / kSteps);
    X_CW_[static_cast<std::size_t>(k)] = X_WC.inverse(Eigen::Isometry);
    if (2 * k == kSteps) X_WC_middle_ = X_WC;
  }
}

Eigen::Vector3d ReadoutPoses::point_C(const Eigen::Vector3d& p_W, double tau) const {
  const double a = std::clamp(tau, -kBeyond, 1.0 + kBeyond) * kSteps;
  const int k = std::clamp(static_cast<int>(std::floor(a)), 0, kSteps - 1);
  const double f = a - k;
  const auto i = static_cast<std::size_t>(k);
  return (1.0 - f) * (X_CW_[i] * p_W) + f * (X_CW_[i + 1] * p_W);
}

void ReadoutPoses::move_vertices(const LensMesher& mesher, std::vector<GpuVertex>& vertices,
                                 std::vector<Eigen::Vector3d>& points_C) const {
  const int s = mesher.supersample();
  const double rows = mesher.intrinsics().height_px;
  const double min_z = 0.5 * mesher.near_m();
  // Output image row of a rasterised pixel: v_s = s v + (s - 1) / 2.
  auto tau_of = [&](const Eigen::Vector2d& px) {
    return std::clamp((px.y() - 0.5 * (s - 1)) / s / rows, -kBeyond, 1.0 + kBeyond);
  };
  auto pixel = [&](const Eigen::Vector3d& p) { return mesher.pixel_of(Eigen::Vector2d(p.x() / p.z(), p.y() / p.z())); };
  for (std::size_t k = 0; k < vertices.size(); ++k) {
    const Eigen::Vector3d p_W = X_WC_middle_ * points_C[k];
    double tau = tau_of(pixel(points_C[k]));
    Eigen::Vector3d p_C = points_C[k];
    bool near = false;
    for (int step = 0; step < 3 && !near; ++step) {
      p_C = point_C(p_W, tau);
      near = !(p_C.z() >= min_z);
      if (!near) tau = tau_of(pixel(p_C));
    }
    if (near) continue;
    p_C = point_C(p_W, tau);
    if (!(p_C.z() >= min_z)) continue;
    const Eigen::Vector4d clip = mesher.clip_of(pixel(p_C), p_C.z());
    for (int c = 0; c < 4; ++c) vertices[k].clip[c] = static_cast<float>(clip[c]);
    points_C[k] = p_C;
  }
}

}  // namespace shelfcross::render
