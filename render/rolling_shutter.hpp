#pragma once
// A rolling shutter: the sensor reads its rows one after the other, so row r of the picture is
// exposed at t0 + r * readout / rows, and sees the world from the camera pose of that instant.
// Over one readout (at most a frame period, 33 ms at 30 fps) the pose moves little, so the
// poses between the readout's start (tau = 0) and its end (tau = 1) are interpolated:
// translation linearly, rotation by slerp (interpolate_pose).
//
// How it is drawn: per vertex, not per band. The lens mesher (lens_mesh.hpp) culls, clips and
// splits the faces at the middle pose as for a global shutter; then each vertex, a point P_W of
// its face, is moved to where the pose of its own row puts it: the row v it lands on depends on
// the pose, which depends on v, so tau is found by the fixed-point iteration
//   tau_{k+1} = v(P_W | pose(tau_k)) / rows,   tau_0 from the middle pose,
// which contracts by c = |dv/dtau| / rows (the picture's shear over the readout in rows, a few
// pixels against 720: c ~ 0.013 for 9 px). tau_0 is off by at most c / 2, so one step leaves
// tau within c^2 / 2 of the fixed point and the vertex within |dv/dtau| c^2 / 2 pixels of
// where its row's pose puts it: 0.001 px for a 9 px shear, 0.01 px for 20 px. The
// rasteriser then joins the moved vertices by straight chords: the map from the world to the
// picture stays continuous (faces that share an edge share its moved points, so no cracks), and
// a pose that moves smoothly over the readout bends a chord by far less than the lens does.
// Image row v is the output image's (supersampled rows are mapped back to it). A vertex outside
// the picture (above row 0 or below the last) takes tau outside [0, 1], the readout's motion
// extrapolated linearly (up to kBeyond readouts): the rows it is never seen in do not matter, but
// a chord from it into the picture then keeps the slope a clamped tau would bend.
//
// Faces are clipped at the middle pose, so the picture's border is covered only as far as the
// lens grids' region reaches outside the image: a renderer meant for a rolling shutter is built
// with RenderOptions::rolling_shutter_margin_px, at least the largest shift of the picture
// between the middle pose and the readout's ends.

#include <array>

#include <Eigen/Geometry>

namespace shelfcross::render {

/// X0 at s = 0, X1 at s = 1: translation linear, rotation by slerp.
Eigen::Isometry3d interpolate_pose(const Eigen::Isometry3d& X0, const Eigen::Isometry3d& X1, double s);

class ReadoutPoses {
 public:
  /// The camera poses X_WC at the readout's start (row 0 exposed) and end (tau = 1, one row
  /// past the last).
  ReadoutPoses(const Eigen::Isometry3d& X_WC_start, const Eigen::Isometry3d& X_WC_end);

  /// The pose at tau = 0.5, which the faces are culled and clipped at.
  const Eigen::Isometry3d& middle_pose() const { return X_WC_middle_; }
  /// Point p_W in the camera at the pose of readout fraction tau (in [0, 1] over the picture;
  /// cut to [-kBeyond, 1 + kBeyond]): between the table's poses (kSteps + 1, exact) the
  /// camera-frame points are interpolated linearly, which differs from the interpolated pose
  /// by |p| dtheta^2 / 8 for a table step of dtheta radians; beyond the readout, extrapolated
  /// linearly from the table's first or last step.
  Eigen::Vector3d point_C(const Eigen::Vector3d& p_W, double tau) const;
  static constexpr int kSteps = 32;
  static constexpr double kBeyond = 0.5;

  /// One point p_W seen over the readout: at(tau) is point_C(p_W, tau), value for value, and
  /// keeps the point in the two table poses it last used, so that a second fraction in the same
  /// table step (a vertex's fixed-point step mostly stays in it) takes no new pose products.
  class Track {
   public:
    Track(const ReadoutPoses& poses, const Eigen::Vector3d& p_W) : poses_(poses), p_W_(p_W) {}
    Eigen::Vector3d at(double tau);

   private:
    const ReadoutPoses& poses_;
    Eigen::Vector3d p_W_;
    int step_ = -1;                    ///< the table step of p0_C_, p1_C_ (-1: none yet)
    Eigen::Vector3d p0_C_, p1_C_;      ///< p_W at the step's first and last pose
  };

 private:
  Eigen::Isometry3d X_WC_middle_;
  std::array<Eigen::Isometry3d, kSteps + 1> X_CW_;  ///< at tau = k / kSteps
};

}  // namespace shelfcross::render
