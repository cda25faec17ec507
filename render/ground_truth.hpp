#pragma once
// Ground truth for tests and metrics (never for the flight software): where the tags and the
// marker corners of the warehouse appear in the image of a camera at X_WC, with the same
// camera model as the renderer (pinhole + plumb-bob distortion, camera_model.hpp, equal to
// cv::projectPoints) and the same geometry (scene.hpp).
//
// Visibility of a tag or marker: in front of the camera (all corners at Z > near), facing it
// (the camera is on the outer side of its plane), inside the image (all corners within
// [0, W-1] x [0, H-1] and inside the lens model's valid footprint), and not occluded (rays from
// the camera to a 5 x 5 grid of points on it hit no bar, rail, box or other tag). So
// `visible` means wholly visible; a partly hidden tag is reported with visible = false.

#include <array>
#include <optional>
#include <vector>

#include <Eigen/Geometry>
#include <opencv2/core/types.hpp>

#include "render/scene.hpp"
#include "shelfcross/camera.hpp"
#include "shelfcross/warehouse.hpp"

namespace shelfcross::render {

struct TagProjection {
  int shelf = 0;
  bool front_face = true;
  int column_boundary = 0;  ///< i, 0 = left edge as seen on approach .. ncols
  int level_boundary = 0;   ///< j, 0 = lowest beam .. nrows
  Eigen::Vector3d p_W_m = Eigen::Vector3d::Zero();  ///< tag centre
  cv::Point2d pixel;                   ///< projection of the centre
  std::array<cv::Point2d, 4> corners;  ///< TL, TR, BR, BL as seen facing the tag
  /// Centroid of the tag's image region (what a blob centroid estimates): the tag split in
  /// 16 x 16 patches, each projected, centroids weighted by image area. Differs from `pixel`
  /// under perspective and distortion.
  cv::Point2d area_centroid;
  double area_px2 = 0.0;
  bool in_front = false, facing = false, in_image = false, occluded = false;
  bool visible = false;  ///< in_front && facing && in_image && !occluded
};

struct MarkerProjection {
  int shelf = 0;
  int level = 1, column = 1;  ///< cell of the box carrying it
  int marker_id = 0;
  bool front_face = true;
  std::array<cv::Point2d, 4> corners;  ///< outer black-border corners, aruco order TL TR BR BL
  std::array<Eigen::Vector3d, 4> corners_W_m;
  bool in_front = false, facing = false, in_image = false, occluded = false;
  bool visible = false;
};

class GroundTruthProjector {
 public:
  /// Throws RenderError for a warehouse the renderer could not draw either.
  GroundTruthProjector(const Warehouse& warehouse, const CameraIntrinsics& intrinsics,
                       double near_m = 0.05);

  /// Pixel of a world point, or nullopt if it is not in front of the camera (Z <= near) or
  /// outside the region where the distortion model is valid (the undistorted footprint of the
  /// image plus a margin; beyond it the polynomial can fold far points back into the image).
  std::optional<cv::Point2d> project(const Eigen::Vector3d& p_W_m,
                                     const Eigen::Isometry3d& X_WC) const;
  /// Inside [0, W-1] x [0, H-1] (pixel centres of the image).
  bool in_image(const cv::Point2d& px) const;
  /// True if the segment from the camera centre to p_W_m hits a bar, rail, box or tag
  /// (`skip_tag`: index into layout().tags of the tag p lies on, or -1).
  bool occluded(const Eigen::Vector3d& p_W_m, const Eigen::Vector3d& p_WC_m,
                int skip_tag = -1) const;

  /// All tags of all shelves, both faces, in layout order (shelf, face, level j, column i).
  std::vector<TagProjection> tags(const Eigen::Isometry3d& X_WC) const;
  /// All markers (front and back of every box).
  std::vector<MarkerProjection> markers(const Eigen::Isometry3d& X_WC) const;

  const SceneLayout& layout() const { return layout_; }
  const CameraIntrinsics& intrinsics() const { return K_; }

 private:
  SceneLayout layout_;
  CameraIntrinsics K_;
  double near_m_;
  Eigen::Vector2d xy_min_, xy_max_;  // valid undistorted normalised footprint
};

/// X_WC = X_WB * X_BC with X_BC = (rotation_body_from_camera(mount.pitch_rad), mount.p_BC_B_m).
Eigen::Isometry3d camera_pose_W(const Eigen::Isometry3d& X_WB, const CameraMount& mount);

}  // namespace shelfcross::render
