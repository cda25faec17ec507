// LensMesher::build under a rolling shutter (rolling_shutter.hpp): the faces meshed at the
// readout's middle pose, then each vertex moved to the pose of its own row. Apart from
// lens_mesh.cpp so that the lens mesher's own file stays about the lens.
#include <algorithm>
#include <cmath>

#include "render/lens_mesh.hpp"
#include "render/rolling_shutter.hpp"

namespace shelfcross::render {

namespace {

// Moves a mesher's vertices (built at the readout's middle pose) to their rows' poses
// (rolling_shutter.hpp): clip coordinates and camera-frame points; texture coordinates stay (they
// belong to the face point). A vertex whose point would come nearer than half the near plane at
// its row's pose keeps the middle pose's projection (the clip there was made for the middle pose).
void move_to_rows(const LensProjection& projection, const ReadoutPoses& readout, std::vector<GpuVertex>& vertices,
                  std::vector<Eigen::Vector3d>& points_C) {
  const int s = projection.supersample();
  const double rows = projection.intrinsics().height_px, rows_s = s * rows;
  const double min_z = 0.5 * projection.near_m();
  // Readout fraction of a rasterised pixel row v_s = s v + (s - 1) / 2 (v the output row).
  auto tau_of = [&](double v_s) { return std::clamp((v_s - 0.5 * (s - 1)) / s / rows, -ReadoutPoses::kBeyond, 1.0 + ReadoutPoses::kBeyond); };
  auto pixel = [&](const Eigen::Vector3d& p) { return projection.pixel_of(Eigen::Vector2d(p.x() / p.z(), p.y() / p.z())); };
  for (std::size_t k = 0; k < vertices.size(); ++k) {
    const GpuVertex& g = vertices[k];
    // tau_0: the vertex's row at the middle pose, from its clip coordinates (y_ndc = 2 (v_s +
    // 0.5) / H_s - 1, gl_clip_from_camera); then one step of the iteration, and the point at
    // tau_1. Its error: |dv/dtau| / rows squared times the first guess's (see the file comment).
    const double tau0 = tau_of((0.5 * (static_cast<double>(g.clip[1]) / g.clip[3] + 1.0)) * rows_s - 0.5);
    ReadoutPoses::Track track(readout, readout.middle_pose() * points_C[k]);
    const Eigen::Vector3d p0_C = track.at(tau0);
    if (!(p0_C.z() >= min_z)) continue;
    const Eigen::Vector3d p_C = track.at(tau_of(pixel(p0_C).y()));
    if (!(p_C.z() >= min_z)) continue;
    const Eigen::Vector4d clip = projection.clip_of(pixel(p_C), p_C.z());
    for (int c = 0; c < 4; ++c) vertices[k].clip[c] = static_cast<float>(clip[c]);
    points_C[k] = p_C;
  }
}

}  // namespace

void LensMesher::build(const ReadoutPoses& readout) {
  build(readout.middle_pose());
  move_to_rows(projection_, readout, frame_.vertices, frame_.points_C);
}

}  // namespace shelfcross::render
