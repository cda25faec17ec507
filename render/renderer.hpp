#pragma once
// The camera: renders the warehouse as the Tello's camera sees it from a camera pose X_WC
// (camera frame C of shelfcross/camera.hpp: x right, y down, z forward), headless, through
// EGL + OpenGL 3.3 core into a framebuffer object, with the lens distortion applied to the
// geometry; then adds the optional sensor noise on the CPU. Output: BGR, CV_8UC3, the
// intrinsics' width x height.
//
// Pipeline of one frame:
//   1. the static world's faces (each lit per face, ambient + Lambert directional, baked into
//      its sRGB-encoded colour since both are constant per planar face) are culled, clipped,
//      split along the lens grid (tags, markers) or along their own edges (the room, shelves,
//      boxes) and projected through the lens on the CPU (lens_mesh.hpp):
//      every vertex exactly as cv::projectPoints puts it, every drawn edge within
//      kLensChordTolerance_px of the true (curved) image of the face's edge;
//   2. rasterised at the output size (x supersample) into colour and depth textures
//      (frame_target.hpp; a frame starts with a fill of the colour, the room's largest face
//      when the room fills the view, and of the depth where depth-tested faces fall): the room
//      first, without depth test, then the shelves with it, then tags and markers with a
//      depth offset; point-sampled at pixel centres, no MSAA;
//   3. glReadPixels as RGBA (rows already in image order: the projection writes image row v
//      to GL row v);
//   4. [supersample s > 1: exact s x s block average (cv::resize INTER_AREA)]
//      [motion blur: average of the N sub-pose renders, integer, rounded]
//   5. RGBA -> BGR, fused with the noise when there is some: seeded, see noise.hpp (a field
//      drawn once, a seeded window of it per frame). Without supersampling or motion blur,
//      3 and 5 go band by band (a few dozen rows read, then converted while in the cache).
// A rolling shutter (render_rolling_into, rolling_shutter.hpp) changes step 1 alone: the faces
// are culled, clipped and split at the readout's middle pose, and every vertex is then moved to
// where the pose of its own image row puts it; a still camera takes the global path unchanged.
// Deterministic: the same warehouse, intrinsics, options, pose and seed give byte-identical
// images from one renderer or several (same machine and driver). No MSAA.
//
// Threads: each Renderer owns its own EGL context and makes it current on the calling thread
// at every call, so a renderer may be used from any one thread at a time (one per thread).

#include <cstdint>
#include <memory>
#include <string>

#include <Eigen/Geometry>
#include <opencv2/core/mat.hpp>

#include "render/camera_model.hpp"
#include "render/egl_context.hpp"
#include "render/lens_mesh.hpp"
#include "render/render_error.hpp"
#include "shelfcross/camera.hpp"
#include "shelfcross/warehouse.hpp"

namespace shelfcross::render {

/// Largest distance, in output pixels, between a drawn face edge (a chord between two exactly
/// projected vertices) and the true image of that edge under the lens, by construction of the
/// lens grid or of the edges' cuts (lens_mesh.hpp); the tests measure it against a 0.25 px
/// tolerance.
inline constexpr double kLensChordTolerance_px = 0.25;

struct RenderOptions {
  double noise_stddev = 0.0;      ///< additive sensor noise, grey levels (0 = none)
  int motion_blur_samples = 1;    ///< sub-poses averaged by render_blurred (1..64)
  double light_scale = 1.0;       ///< exposure: multiplies the warehouse's lighting
  int supersample = 1;            ///< s x s ordered supersampling, 1..4 (deterministic AA)
  double near_m = 0.05;           ///< clip planes of the camera
  double far_m = 50.0;
  /// Rolling shutter (render_rolling_into): how far, in output pixels, a row's pose may shift
  /// the picture against the readout's middle pose. Faces are clipped this much farther
  /// outside the image (2 px beyond it without), so that the border stays covered; 0 for a
  /// global shutter (rolling_shutter.hpp).
  double rolling_shutter_margin_px = 0.0;
  /// kFromEnvironment reads SHELFCROSS_EGL=auto|device|surfaceless (unset: auto).
  EglPlatform egl_platform = EglPlatform::kFromEnvironment;
};

class Renderer {
 public:
  /// Builds the scene and the lens grid (throws RenderError for a warehouse it cannot draw,
  /// bad options or a lens that folds over), creates the EGL context and the GL objects
  /// (throws RenderError with the EGL/GL reason if initialisation fails).
  Renderer(const Warehouse& warehouse, const CameraIntrinsics& intrinsics,
           RenderOptions options = {});
  ~Renderer();
  Renderer(const Renderer&) = delete;
  Renderer& operator=(const Renderer&) = delete;

  /// One frame from camera pose X_WC; noise (if enabled) from `noise_seed`, for instance
  /// a draw of the run's render-noise stream per frame.
  cv::Mat render(const Eigen::Isometry3d& X_WC, std::uint64_t noise_seed = 0);
  /// Same, into `bgr` (reallocated only if its size or type is wrong: no per-frame
  /// allocation when the caller keeps the Mat).
  void render_into(const Eigen::Isometry3d& X_WC, std::uint64_t noise_seed, cv::Mat& bgr);

  /// Rolling shutter (rolling_shutter.hpp): image row v (0 at the top) exposed at readout
  /// fraction tau = v / height, seen from the pose interpolated between X_WC_start (tau = 0,
  /// the readout's start) and X_WC_end (tau = 1): translation linearly, rotation by slerp.
  /// Equal poses (a still camera) give render_into(X_WC_end)'s picture bit for bit.
  void render_rolling_into(const Eigen::Isometry3d& X_WC_start, const Eigen::Isometry3d& X_WC_end,
                           std::uint64_t noise_seed, cv::Mat& bgr);

  /// Motion blur: the average of motion_blur_samples renders at the sub-poses
  /// s_k = (k + 1) / N, k = 0..N-1, between X_WC_prev (s = 0, excluded) and X_WC (s = 1),
  /// translation interpolated linearly and rotation by slerp. N = 1 is render(X_WC).
  cv::Mat render_blurred(const Eigen::Isometry3d& X_WC_prev, const Eigen::Isometry3d& X_WC,
                         std::uint64_t noise_seed = 0);
  void render_blurred_into(const Eigen::Isometry3d& X_WC_prev, const Eigen::Isometry3d& X_WC,
                           std::uint64_t noise_seed, cv::Mat& bgr);
  /// Motion blur under a rolling shutter whose readout ends at X_WC and starts at X_WC_start:
  /// each sub-pose X_k is the end of a readout with the same motion, from X_k X_WC^-1 X_WC_start
  /// to X_k. X_WC_start == X_WC gives render_blurred_into's picture.
  void render_blurred_rolling_into(const Eigen::Isometry3d& X_WC_prev, const Eigen::Isometry3d& X_WC_start,
                                   const Eigen::Isometry3d& X_WC, std::uint64_t noise_seed, cv::Mat& bgr);

  /// Re-targets the renderer at another warehouse (a run's dispersed boxes or lighting) in
  /// the same EGL context: the scene is rebuilt; a warehouse equal to the current one costs
  /// nothing. Throws RenderError like the constructor.
  void set_warehouse(const Warehouse& warehouse);
  /// GL_RENDERER, e.g. "llvmpipe (LLVM 15.0.6, 256 bits)".
  std::string gl_renderer_name() const;
  /// One line for logs: EGL platform, EGL vendor and version, GL_RENDERER, GL_VERSION.
  std::string backend_description() const;

  const CameraIntrinsics& intrinsics() const;
  const RenderOptions& options() const;
  /// The faces, the lens grid they are split along (so that the lens bends no drawn edge by
  /// more than kLensChordTolerance_px) and the last frame's triangles (for tests and the
  /// benchmark).
  const LensMesher& lens_mesh() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace shelfcross::render
