#pragma once
// 6-DOF navigation (paper eq. 5-8) and the geometry of the known shelf.
//
// Cell frame K (and grid frame G): x_K points into the shelf along the cell normal (the
// approach direction), y_K left as seen on approach, z_K up: the shelf frame S of
// shelfcross/warehouse.hpp, moved. K's origin is the cell centre on the front face: midway
// between the centre lines of the cell's two posts and of its two beams, on the front bars'
// centre plane. G's origin is the centre of the whole grid on that plane. A vehicle in front
// of the shelf has x < 0; heading yaw 0 faces into the shelf; yaw is counter-clockwise seen
// from above (the ZYX yaw of R_KB), so yaw > 0 is turned left.
// Tag centres lie tag_offset_m in front of the bars' centre plane: x = -tag_offset_m.

#include <array>
#include <optional>
#include <vector>

#include <Eigen/Geometry>
#include <opencv2/core.hpp>

#include "flight_sw/config.hpp"
#include "flight_sw/perception/shelf_view.hpp"

namespace shelfcross::flight_sw {

/// The vehicle's pose in a frame fixed on the shelf (K or G), from the camera's.
struct PoseEstimate {
  Eigen::Isometry3d X_FC = Eigen::Isometry3d::Identity();  ///< camera in the frame F (K or G)
  Eigen::Isometry3d X_FB = Eigen::Isometry3d::Identity();  ///< body in F
  double roll_rad = 0.0;   ///< ZYX Euler angles of R_FB
  double pitch_rad = 0.0;
  double yaw_rad = 0.0;    ///< heading relative to the cell normal, CCW positive
  double reprojection_rms_px = 0.0;
  Eigen::Vector3d p_FB_m() const { return X_FB.translation(); }
};

/// The intrinsics as OpenCV takes them: the camera matrix K and the plumb-bob distortion
/// (k1, k2, p1, p2, k3).
cv::Matx33d camera_matrix(const CameraIntrinsics& camera);
cv::Vec<double, 5> distortion(const CameraIntrinsics& camera);

/// Eq. 5-8: solves s p = K [R | t] P for the tag points P_F (in F) seen at the distorted pixels
/// p (cv::solvePnP with the intrinsics and distortion; IPPE for 4 coplanar points, then
/// Levenberg-Marquardt refinement on all), turns the Rodrigues vector into R (eq. 8,
/// cv::Rodrigues), inverts to the camera pose in F (eq. 7: P_C = R P_F + t, so
/// R_FC = R^T, p_FC = -R^T t) and moves through the mount to the body:
/// R_FB = R_FC R_BC^T, p_FB = p_FC - R_FB p_BC_B. Empty when fewer than 4 points or the
/// solver fails.
std::optional<PoseEstimate> estimate_pose(const std::vector<cv::Point3d>& points_F_m,
                                          const std::vector<cv::Point2d>& pixels,
                                          const CameraIntrinsics& camera, const CameraMount& mount);

/// Tag centre of post i (0 = leftmost) and beam j (0 = lowest) in the grid frame G.
cv::Point3d grid_tag_G(const KnownShelf& shelf, int post, int beam);
/// The four corner tags of a cell in its own frame K, in the order of cell_corner_indices
/// (bottom-left, bottom-right, top-right, top-left as seen on approach).
std::array<cv::Point3d, 4> cell_corner_tags_K(const KnownShelf& shelf, CellIndex cell);
/// The cell centre (origin of K) in G.
Eigen::Vector3d cell_centre_G(const KnownShelf& shelf, CellIndex cell);

/// Clear opening of a cell: column pitch less a post, row pitch less a beam (width, height).
Eigen::Vector2d cell_opening_m(const KnownShelf& shelf, CellIndex cell);

/// The optimal viewpoint (paper section 4): the closest body position, heading yaw 0, from
/// which the whole tag grid (tag edges included, grown by `margin` per side as a fraction)
/// fits the camera's view: range D = max(half width / tan(half horizontal FOV),
/// half height / tan(half vertical FOV)) with the half FOVs measured from the principal point
/// to the nearer image edge. The camera sits on the grid's centre line, raised by
/// D tan(mount pitch) so that a tilted optical axis still meets the grid centre.
Eigen::Vector3d optimal_viewpoint_G(const KnownShelf& shelf, const CameraIntrinsics& camera,
                                    const CameraMount& mount, double margin);

/// The pose `pose_K` (taken when the state yaw was `yaw_O_at_pose_rad`) carried by the
/// vehicle's own motion since: moved by `dp_O_m` and turned by `dyaw_rad` in the odometry frame,
/// its attitude otherwise unchanged. K's heading in O is yaw_O - pose yaw, so
/// dp_K = R_z(-(yaw_O - yaw_K)) dp_O; X_KB' = (R_z(dyaw) R_KB, p_KB + dp_K); the camera rides
/// on the body (X_KC' = X_KB' X_KB^-1 X_KC); the yaw grows by dyaw.
PoseEstimate pose_after_motion(const PoseEstimate& pose_K, double yaw_O_at_pose_rad, const Eigen::Vector3d& dp_O_m,
                               double dyaw_rad);

/// The crossing line (open loop, docs/method.md section 3): the unit direction in K from the pose's
/// body position through the cell's centre at mid-depth, so that a residual offset y0 at range r
/// leaves only y0 (depth/2) / (r + depth/2) at either face.
Eigen::Vector3d crossing_direction_K(const KnownShelf& shelf, const PoseEstimate& pose_K);

}  // namespace shelfcross::flight_sw
