#pragma once
// The camera: pinhole intrinsics with plumb-bob distortion (OpenCV's model), its mount on
// the body, and the camera frame message.
//
// Frames: camera C is OpenCV's (x right, y down, z forward along the optical axis).
// With zero mount pitch, C's axes in the body frame B (x forward, y left, z up) are
//   x_C = -y_B,  y_C = -z_B,  z_C = x_B.
// Mount pitch rotates the camera about y_B; positive pitch tilts the optical axis down
// (the same sign as the body's pitch in the ZYX convention of sdk_messages.hpp).

#include <cmath>
#include <cstdint>
#include <vector>

#include <Eigen/Geometry>
#include <opencv2/core/mat.hpp>

#include "shelfcross/time.hpp"

namespace shelfcross {

/// Pinhole intrinsics and lens distortion k1 k2 p1 p2 k3 (OpenCV order), pixels.
struct CameraIntrinsics {
  int width_px = 960;
  int height_px = 720;
  double fx_px = 921.17;
  double fy_px = 919.02;
  double cx_px = 459.90;
  double cy_px = 351.24;
  double k1 = -0.0335;
  double k2 = 0.1052;
  double p1 = 0.0013;
  double p2 = -0.0066;
  double k3 = 0.0;
  bool operator==(const CameraIntrinsics&) const = default;
};

/// Where the camera sits on the body.
struct CameraMount {
  double pitch_rad = 0.0;                              ///< + tilts the optical axis down
  Eigen::Vector3d p_BC_B_m = Eigen::Vector3d(0.045, 0.0, 0.0);  ///< optical centre in B
  bool operator==(const CameraMount&) const = default;
};

/// R_BC: the rotation taking camera-frame vectors to body-frame vectors, for a mount pitch.
/// R_BC = R_y(pitch) * R_BC0 with R_BC0 the zero-pitch axes above (columns x_C, y_C, z_C in B).
/// Any finite pitch; a rotation matrix (orthonormal, det +1).
inline Eigen::Matrix3d rotation_body_from_camera(double mount_pitch_rad) {
  Eigen::Matrix3d R_BC0;
  R_BC0 << 0, 0, 1,
          -1, 0, 0,
           0, -1, 0;
  return Eigen::AngleAxisd(mount_pitch_rad, Eigen::Vector3d::UnitY()).toRotationMatrix() * R_BC0;
}

/// A band of picture rows, [v_begin_px, v_end_px), top to bottom.
struct RowSpan {
  int v_begin_px = 0;
  int v_end_px = 0;
  bool operator==(const RowSpan&) const = default;
};

/// One decoded camera frame as the flight software receives it.
///
/// Damage: a lost video datagram loses a band of the picture; the decoder fills it in from
/// the previous picture (error concealment) and, through prediction, the damage lasts until
/// the next key frame. `damage_events` counts the damaged pictures since the last key frame
/// (this one included): 0 for a whole picture, and each lost datagram adds a band of
/// guesswork. `damaged_rows` says where: the rows that may differ from what the camera saw
/// (the concealed bands of this picture and of the pictures it was predicted from, moved
/// along the stream's motion vectors), the rest of the picture decoded from data that
/// arrived. It is empty when `damaged` is false or when the damage has left the picture
/// (the receiver followed it out), and the whole height when the receiver cannot tell. The co-simulation's ideal link hands whole frames (it drops frames, it does
/// not damage them); the sdk link and tello_pilot copy all three from the video receiver.
struct CameraFrame {
  TimeNs t_ns = 0;           ///< receive time (after the video link's latency)
  std::int64_t index = 0;    ///< frame counter of the source; gaps mean dropped frames
  cv::Mat bgr;               ///< CV_8UC3, width x height of the intrinsics
  bool damaged = false;      ///< error-concealed: part of the picture is guessed
  int damage_events = 0;     ///< damaged pictures since the last key frame (0 when whole)
  std::vector<RowSpan> damaged_rows = {};  ///< where the guessed part may lie, disjoint, top down
};

}  // namespace shelfcross
