#include "flight_sw/navigation/navigation.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>

#include <opencv2/calib3d.hpp>

#include "shelfcross/rotation.hpp"

namespace shelfcross::flight_sw {

cv::Matx33d camera_matrix(const CameraIntrinsics& k) {
  return {k.fx_px, 0, k.cx_px, 0, k.fy_px, k.cy_px, 0, 0, 1};
}

cv::Vec<double, 5> distortion(const CameraIntrinsics& k) { return {k.k1, k.k2, k.p1, k.p2, k.k3}; }

std::optional<PoseEstimate> estimate_pose(const std::vector<cv::Point3d>& points_F_m,
                                          const std::vector<cv::Point2d>& pixels,
                                          const CameraIntrinsics& k, const CameraMount& mount) {
  if (points_F_m.size() < 4 || points_F_m.size() != pixels.size()) return std::nullopt;
  const cv::Matx33d K = camera_matrix(k);
  const cv::Vec<double, 5> dist = distortion(k);
  cv::Vec3d rvec, tvec;
  // All tag points are coplanar (x = -tag_offset): IPPE gives the planar solution directly.
  bool ok = false;
  try {
    ok = cv::solvePnP(points_F_m, pixels, K, dist, rvec, tvec, false, cv::SOLVEPNP_IPPE);
    if (ok) {
      cv::solvePnPRefineLM(points_F_m, pixels, K, dist, rvec, tvec);
    }
  } catch (const cv::Exception&) {
    return std::nullopt;  // degenerate configuration (collinear points)
  }
  if (!ok) return std::nullopt;
  cv::Matx33d R_CF_cv;
  cv::Rodrigues(rvec, R_CF_cv);  // eq. 8
  Eigen::Matrix3d R_CF;
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) R_CF(r, c) = R_CF_cv(r, c);
  }
  const Eigen::Vector3d t_CF(tvec[0], tvec[1], tvec[2]);
  PoseEstimate e;
  const Eigen::Matrix3d R_FC = R_CF.transpose();
  e.X_FC.linear() = R_FC;
  e.X_FC.translation() = -R_FC * t_CF;  // eq. 7 inverted
  const Eigen::Matrix3d R_FB = R_FC * rotation_body_from_camera(mount.pitch_rad).transpose();
  e.X_FB.linear() = R_FB;
  e.X_FB.translation() = e.X_FC.translation() - R_FB * mount.p_BC_B_m;
  const Eigen::Vector3d rpy_FB = euler_zyx(R_FB);  // ZYX Euler angles of R_FB
  e.roll_rad = rpy_FB.x();
  e.pitch_rad = rpy_FB.y();
  e.yaw_rad = rpy_FB.z();
  std::vector<cv::Point2d> reproj;
  cv::projectPoints(points_F_m, rvec, tvec, K, dist, reproj);
  double sq = 0.0;
  for (size_t i = 0; i < reproj.size(); ++i) {
    const cv::Point2d d = reproj[i] - pixels[i];
    sq += d.dot(d);
  }
  e.reprojection_rms_px = std::sqrt(sq / static_cast<double>(reproj.size()));
  return e;
}

namespace {
double sum(const std::vector<double>& v, int n) {
  return std::accumulate(v.begin(), v.begin() + n, 0.0);
}
}  // namespace

cv::Point3d grid_tag_G(const KnownShelf& s, int post, int beam) {
  const double width = sum(s.column_pitch_m, s.columns());
  const double height = sum(s.row_pitch_m, s.levels());
  return {-s.tag_offset_m, 0.5 * width - sum(s.column_pitch_m, post),
          -0.5 * height + sum(s.row_pitch_m, beam)};
}

Eigen::Vector3d cell_centre_G(const KnownShelf& s, CellIndex cell) {
  const cv::Point3d a = grid_tag_G(s, cell.column - 1, cell.level - 1);
  const cv::Point3d b = grid_tag_G(s, cell.column, cell.level);
  return {0.0, 0.5 * (a.y + b.y), 0.5 * (a.z + b.z)};
}

std::array<cv::Point3d, 4> cell_corner_tags_K(const KnownShelf& s, CellIndex cell) {
  const Eigen::Vector3d o = cell_centre_G(s, cell);
  const cv::Point3d origin(o.x(), o.y(), o.z());
  const int i = cell.column - 1, j = cell.level - 1;
  return {grid_tag_G(s, i, j) - origin, grid_tag_G(s, i + 1, j) - origin,
          grid_tag_G(s, i + 1, j + 1) - origin, grid_tag_G(s, i, j + 1) - origin};
}

Eigen::Vector2d cell_opening_m(const KnownShelf& s, CellIndex cell) {
  return {s.column_pitch_m[static_cast<size_t>(cell.column - 1)] - s.post_thickness_m,
          s.row_pitch_m[static_cast<size_t>(cell.level - 1)] - s.beam_thickness_m};
}

Eigen::Vector3d optimal_viewpoint_G(const KnownShelf& s, const CameraIntrinsics& k,
                                    const CameraMount& mount, double margin) {
  const double half_w = 0.5 * (sum(s.column_pitch_m, s.columns()) + s.tag_size_m) * (1.0 + margin);
  const double half_h = 0.5 * (sum(s.row_pitch_m, s.levels()) + s.tag_size_m) * (1.0 + margin);
  const double tan_h = std::min(k.cx_px, k.width_px - 1 - k.cx_px) / k.fx_px;
  const double tan_v = std::min(k.cy_px, k.height_px - 1 - k.cy_px) / k.fy_px;
  const double range = std::max(half_w / tan_h, half_h / tan_v);  // camera to tag plane
  const Eigen::Vector3d p_GC(-s.tag_offset_m - range, 0.0, range * std::tan(mount.pitch_rad));
  // Heading 0: R_GB = I, so the body sits p_BC_B behind the camera.
  return p_GC - mount.p_BC_B_m;
}

PoseEstimate pose_after_motion(const PoseEstimate& pose_K, double yaw_O_at_pose_rad, const Eigen::Vector3d& dp_O_m,
                               double dyaw_rad) {
  const double yaw_K_in_O = yaw_O_at_pose_rad - pose_K.yaw_rad;
  Eigen::Vector3d dp_K = dp_O_m;
  dp_K.head<2>() = Eigen::Rotation2Dd(-yaw_K_in_O) * dp_O_m.head<2>();
  PoseEstimate moved = pose_K;
  moved.X_FB.linear() = Eigen::AngleAxisd(dyaw_rad, Eigen::Vector3d::UnitZ()).toRotationMatrix() * pose_K.X_FB.linear();
  moved.X_FB.translation() += dp_K;
  moved.X_FC = moved.X_FB * (pose_K.X_FB.inverse() * pose_K.X_FC);
  moved.yaw_rad = wrap_pi(pose_K.yaw_rad + dyaw_rad);
  return moved;
}


Eigen::Vector3d crossing_direction_K(const KnownShelf& shelf, const PoseEstimate& pose) {
  const Eigen::Vector3d aim(0.5 * shelf.depth_m, 0.0, 0.0);
  return (aim - pose.p_FB_m()).normalized();
}

}  // namespace shelfcross::flight_sw
