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

ReadoutPoses::ReadoutPoses(const Eigen::Isometry3d& X_WC_start, const Eigen::Isometry3d& X_WC_end) {
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
  const double rows = mesher.intrinsics().height_px, rows_s = s * rows;
  const double min_z = 0.5 * mesher.near_m();
  // Readout fraction of a rasterised pixel row v_s = s v + (s - 1) / 2 (v the output row).
  auto tau_of = [&](double v_s) { return std::clamp((v_s - 0.5 * (s - 1)) / s / rows, -kBeyond, 1.0 + kBeyond); };
  auto pixel = [&](const Eigen::Vector3d& p) { return mesher.pixel_of(Eigen::Vector2d(p.x() / p.z(), p.y() / p.z())); };
  for (std::size_t k = 0; k < vertices.size(); ++k) {
    const GpuVertex& g = vertices[k];
    // tau_0: the vertex's row at the middle pose, from its clip coordinates (y_ndc = 2 (v_s +
    // 0.5) / H_s - 1, gl_clip_from_camera); then one step of the iteration, and the point at
    // tau_1. Its error: |dv/dtau| / rows squared times the first guess's (see the file comment).
    const double tau0 = tau_of((0.5 * (static_cast<double>(g.clip[1]) / g.clip[3] + 1.0)) * rows_s - 0.5);
    const Eigen::Vector3d p_W = X_WC_middle_ * points_C[k];
    const Eigen::Vector3d p0_C = point_C(p_W, tau0);
    if (!(p0_C.z() >= min_z)) continue;
    const Eigen::Vector3d p_C = point_C(p_W, tau_of(pixel(p0_C).y()));
    if (!(p_C.z() >= min_z)) continue;
    const Eigen::Vector4d clip = mesher.clip_of(pixel(p_C), p_C.z());
    for (int c = 0; c < 4; ++c) vertices[k].clip[c] = static_cast<float>(clip[c]);
    points_C[k] = p_C;
  }
}

}  // namespace shelfcross::render
