#include "render/rolling_shutter.hpp"

#include <algorithm>
#include <cmath>

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

Eigen::Vector3d ReadoutPoses::point_C(const Eigen::Vector3d& p_W, double tau) const { return Track(*this, p_W).at(tau); }

Eigen::Vector3d ReadoutPoses::Track::at(double tau) {
  const double a = std::clamp(tau, -kBeyond, 1.0 + kBeyond) * kSteps;
  const int k = std::clamp(static_cast<int>(std::floor(a)), 0, kSteps - 1);
  const double f = a - k;
  if (k != step_) {
    const auto i = static_cast<std::size_t>(k);
    p0_C_ = poses_.X_CW_[i] * p_W_;
    p1_C_ = poses_.X_CW_[i + 1] * p_W_;
    step_ = k;
  }
  return (1.0 - f) * p0_C_ + f * p1_C_;
}

}  // namespace shelfcross::render
