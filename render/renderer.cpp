#include "render/renderer.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <sstream>
#include <vector>

#define GL_GLEXT_PROTOTYPES 1
#include <GL/gl.h>
#include <GL/glext.h>

#include <opencv2/imgproc.hpp>

#include "render/frame_target.hpp"
#include "render/gl_program.hpp"
#include "render/lens_mesh.hpp"
#include "render/noise.hpp"
#include "render/rolling_shutter.hpp"
#include "render/scene.hpp"
#include "render/world_faces.hpp"

namespace shelfcross::render {
struct Renderer::Impl {
  Warehouse warehouse;
  CameraIntrinsics K;
  RenderOptions options;
  LensMesher mesher;
  int hi_width = 0, hi_height = 0;  // image size x supersample
  EglContext egl;
  std::string gl_renderer, gl_version;

  GLuint flat_program = 0, textured_program = 0, vao = 0, vbo = 0, ibo = 0, atlas = 0;
  FrameTarget target;  // the framebuffer: colour and depth textures
  // Every non-room face lies inside the arena box, so the room (whose visible faces never
  // overlap: the inside of a convex box) can be drawn first without the depth test.
  bool room_first = false;
  // The world box the room's faces bound, and the largest |(x, y, 1)| over the lens region
  // (for the test that the room covers every pixel, see draw).
  Eigen::AlignedBox3d arena;
  double max_ray_stretch = 1.0;

  std::unique_ptr<SensorNoise> noise;  // when options.noise_stddev > 0
  cv::Mat rgba_hi, rgba, acc;          // per-frame RGBA buffers, allocated once
  static constexpr int kBandRows = 48;
  cv::Mat band;                        // kBandRows RGBA rows (read_and_finish)

  Impl(const Warehouse& w, const CameraIntrinsics& k, const RenderOptions& o)
      : warehouse(w),
        K(k),
        options(o),
        mesher(k, o.supersample, o.near_m, o.far_m, kLensChordTolerance_px, 2.0 + o.rolling_shutter_margin_px),
        hi_width(k.width_px * o.supersample),
        hi_height(k.height_px * o.supersample),
        egl(o.egl_platform) {
    const LensGrid& g = mesher.grids().edges;
    for (double x : {g.x_min, g.x_max})
      for (double y : {g.y_min, g.y_max})
        max_ray_stretch = std::max(max_ray_stretch, std::sqrt(1.0 + x * x + y * y));
  }

  void build(const SceneLayout& layout);
  void release_gl();  // deletes the GL objects build() made (context current)
  // The frame into the framebuffer: row v exposed at the pose of readout fraction v / rows
  // between X_WC_start and X_WC_end (equal poses: a global shutter at X_WC_end).
  void draw(const Eigen::Isometry3d& X_WC_start, const Eigen::Isometry3d& X_WC_end);
  void read();                                // framebuffer -> image() (1x image size)
  void finish(std::uint64_t noise_seed, cv::Mat& bgr);  // image() -> bgr
  // RGBA rows first_row.. of the frame -> the same rows of bgr (allocated): BGR, noise added
  void convert_rows(const cv::Mat& rgba_rows, int first_row, std::uint64_t noise_seed, cv::Mat& bgr);
  void read_and_finish(std::uint64_t noise_seed, cv::Mat& bgr);  // framebuffer -> bgr
  cv::Mat& image() { return options.supersample > 1 ? rgba : rgba_hi; }
};

void Renderer::Impl::build(const SceneLayout& layout) {
  WorldFaces world = build_world_faces(warehouse, layout, options.light_scale);
  arena = world.arena;
  room_first = world.room_first;
  for (FaceGroup g : {kRoomFaces, kFlatFaces, kDecalFaces, kTexturedFaces})
    mesher.set_faces(g, std::move(world.faces[static_cast<std::size_t>(g)]));
  // Drawn first, without the depth test (draw): the room's faces need no depth inside.
  mesher.set_depth_tested(kRoomFaces, !room_first);

  // ---- GL objects ----
  egl.make_current();
  const char* r = reinterpret_cast<const char*>(glGetString(GL_RENDERER));
  const char* v = reinterpret_cast<const char*>(glGetString(GL_VERSION));
  gl_renderer = r ? r : "?";
  gl_version = v ? v : "?";

  flat_program = link_flat_program();
  textured_program = link_textured_program();
  glUseProgram(textured_program);
  glUniform1i(glGetUniformLocation(textured_program, "atlas"), 0);

  glGenVertexArrays(1, &vao);
  glBindVertexArray(vao);
  glGenBuffers(1, &vbo);
  glBindBuffer(GL_ARRAY_BUFFER, vbo);
  glGenBuffers(1, &ibo);
  glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, ibo);  // part of the VAO's state
  glVertexAttribPointer(0, 4, GL_FLOAT, GL_FALSE, sizeof(GpuVertex),
                        reinterpret_cast<const void*>(offsetof(GpuVertex, clip)));
  glVertexAttribPointer(1, 3, GL_FLOAT, GL_FALSE, sizeof(GpuVertex),
                        reinterpret_cast<const void*>(offsetof(GpuVertex, rgb)));
  glVertexAttribPointer(2, 2, GL_FLOAT, GL_FALSE, sizeof(GpuVertex),
                        reinterpret_cast<const void*>(offsetof(GpuVertex, uv)));
  for (GLuint a : {0u, 1u, 2u}) glEnableVertexAttribArray(a);

  glGenTextures(1, &atlas);
  glActiveTexture(GL_TEXTURE0);
  glBindTexture(GL_TEXTURE_2D, atlas);
  glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
  glTexImage2D(GL_TEXTURE_2D, 0, GL_R8, world.atlas.cols, world.atlas.rows, 0, GL_RED, GL_UNSIGNED_BYTE,
               world.atlas.data);
  // Nearest: marker cells stay crisp; cell edges fall exactly where the geometry puts them.
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);

  target.create(hi_width, hi_height);
  glViewport(0, 0, hi_width, hi_height);
  glDepthFunc(GL_LESS);
  // Faces are clipped against the near and far planes in 3-D already (lens_mesh.cpp); depth
  // clamping keeps GL from clipping again at z_ndc = -1 +- rounding.
  glEnable(GL_DEPTH_CLAMP);
  glDisable(GL_CULL_FACE);  // culled per face on the CPU
  glDisable(GL_DITHER);
  glDisable(GL_MULTISAMPLE);
  glDisable(GL_BLEND);
  glPolygonOffset(-static_cast<float>(std::ceil(mesher.grids().edges_interior_bound_px) + 1.0), -1.f);
  glPixelStorei(GL_PACK_ALIGNMENT, 4);
  check_gl("renderer initialisation");

  // ---- per-frame buffers, once ----
  rgba_hi.create(hi_height, hi_width, CV_8UC4);
  rgba.create(K.height_px, K.width_px, CV_8UC4);
  band.create(kBandRows, K.width_px, CV_8UC4);
}

void Renderer::Impl::draw(const Eigen::Isometry3d& X_WC_start, const Eigen::Isometry3d& X_WC_end) {
  egl.make_current();
  if (X_WC_start.matrix() == X_WC_end.matrix()) {  // a still camera: the global shutter's path
    mesher.build(X_WC_end);
  } else {
    mesher.build(ReadoutPoses(X_WC_start, X_WC_end));
  }
  const std::vector<GpuVertex>& vertices = mesher.vertices();
  const std::vector<std::uint32_t>& indices = mesher.indices();
  target.bind();
  glBindVertexArray(vao);
  glBindBuffer(GL_ARRAY_BUFFER, vbo);
  glBufferData(GL_ARRAY_BUFFER, static_cast<GLsizeiptr>(vertices.size() * sizeof(GpuVertex)),
               vertices.data(), GL_STREAM_DRAW);
  glBufferData(GL_ELEMENT_ARRAY_BUFFER, static_cast<GLsizeiptr>(indices.size() * sizeof(std::uint32_t)),
               indices.data(), GL_STREAM_DRAW);
  // The room covers every pixel when the camera is inside the arena, farther than the near
  // plane from every wall along every ray (Z >= distance / max |(x, y, 1)|) and nearer than the
  // far plane to every corner (each pixel then shows exactly one room face or something in
  // front of it).
  // (Under a rolling shutter, from both ends of the readout: the straight path between them
  // stays inside the box the two bound.)
  double wall_distance = std::numeric_limits<double>::infinity(), farthest = 0.0;
  for (const Eigen::Isometry3d* X : {&X_WC_start, &X_WC_end}) {
    const Eigen::Vector3d p = X->translation();
    wall_distance = std::min({wall_distance, (p - arena.min()).minCoeff(), (arena.max() - p).minCoeff()});
    for (int c = 0; c < 8; ++c)
      farthest = std::max(farthest, (arena.corner(static_cast<Eigen::AlignedBox3d::CornerType>(c)) - p).norm());
  }
  const bool room_covers = room_first && wall_distance > options.near_m * max_ray_stretch &&
                           farthest < options.far_m;
  // When the room covers the view, its largest face is not drawn: the colour fill that starts
  // the frame (cheaper than shading its fragments) paints it, and the room's other faces and
  // everything else are drawn over it.
  const std::vector<LensMesher::FaceSpan>& room = mesher.room_spans();
  std::size_t skipped = room.size();
  if (room_covers) {
    for (std::size_t k = 0; k < room.size(); ++k)
      if (skipped == room.size() || room[k].area_px2 > room[skipped].area_px2) skipped = k;
  }
  std::array<std::uint8_t, 4> fill{0, 0, 0, 255};  // black where nothing covers a pixel
  if (skipped < room.size()) {
    // The face's colour is k / 255 (FaceBuilder::colour): its bytes k.
    for (int k = 0; k < 3; ++k)
      fill[static_cast<std::size_t>(k)] = static_cast<std::uint8_t>(std::lround(room[skipped].rgb[k] * 255.f));
  }
  // The depth buffer matters only where a depth-tested face is drawn: everything but the room
  // when the room goes first, else everything.
  const std::size_t depth_tested = mesher.first_index(room_first ? kFlatFaces : kRoomFaces);
  target.start_frame(fill, covered_pixels(vertices, indices, depth_tested, indices.size(),
                                          hi_width, hi_height));
  auto draw_range = [&](std::size_t a, std::size_t b) {
    if (b > a)
      glDrawElements(GL_TRIANGLES, static_cast<GLsizei>(b - a), GL_UNSIGNED_INT,
                     reinterpret_cast<const void*>(a * sizeof(std::uint32_t)));
  };
  auto draw = [&](int first_group, int end_group) {
    draw_range(mesher.first_index(first_group), mesher.first_index(end_group));
  };
  glUseProgram(flat_program);
  if (room_first) {
    // The room first, no depth test (its visible faces never overlap; everything else is in
    // front of it), then the rest with it.
    glDisable(GL_DEPTH_TEST);
    for (std::size_t k = 0; k < room.size(); ++k)
      if (k != skipped) draw_range(room[k].first_index, room[k].end_index);
    glEnable(GL_DEPTH_TEST);
    draw(kFlatFaces, kDecalFaces);
  } else {
    glEnable(GL_DEPTH_TEST);
    draw(kRoomFaces, kDecalFaces);
  }
  // Decals a millimetre off their surface: the depth of a large flat face is interpolated
  // across its lens cell or outline triangle and may sit up to edges_interior_bound_px pixels'
  // worth of depth slope off (lens_mesh.hpp), so decals are pulled forward by that much plus
  // one pixel.
  glEnable(GL_POLYGON_OFFSET_FILL);
  draw(kDecalFaces, kTexturedFaces);
  glUseProgram(textured_program);
  draw(kTexturedFaces, kFaceGroups);
  glDisable(GL_POLYGON_OFFSET_FILL);
  check_gl("draw");
}

// Rows come back bottom GL row first = image row 0 first (see gl_clip_from_camera).
// RGBA, the renderbuffer's own layout on Mesa: a plain copy (BGRA costs a swizzle pass,
// ~6x slower on llvmpipe); the channel order is fixed in finish().
void Renderer::Impl::read() {
  glReadPixels(0, 0, hi_width, hi_height, GL_RGBA, GL_UNSIGNED_BYTE, rgba_hi.data);
  check_gl("readback");
  if (options.supersample > 1) {
    // Exact s x s block means for an integer factor.
    cv::resize(rgba_hi, rgba, rgba.size(), 0, 0, cv::INTER_AREA);
  }
}

void Renderer::Impl::convert_rows(const cv::Mat& rgba_rows, int first_row, std::uint64_t noise_seed, cv::Mat& bgr) {
  if (noise) {
    noise->apply_rgba_rows_to_bgr(rgba_rows, first_row, bgr, noise_seed);
  } else {
    cv::Mat out = bgr.rowRange(first_row, first_row + rgba_rows.rows);
    cv::cvtColor(rgba_rows, out, cv::COLOR_RGBA2BGR);
  }
}

void Renderer::Impl::finish(std::uint64_t noise_seed, cv::Mat& bgr) {
  bgr.create(K.height_px, K.width_px, CV_8UC3);
  convert_rows(image(), 0, noise_seed, bgr);
}

void Renderer::Impl::read_and_finish(std::uint64_t noise_seed, cv::Mat& bgr) {
  if (options.supersample > 1) {
    read();
    finish(noise_seed, bgr);
    return;
  }
  // Supersample 1: read() and finish() band by band, the same bytes. A band of RGBA rows is
  // read into a buffer small enough to stay in the cache and converted from there, instead of
  // the whole RGBA image going out to memory and coming back.
  bgr.create(K.height_px, K.width_px, CV_8UC3);
  for (int r0 = 0; r0 < K.height_px; r0 += kBandRows) {
    const int r1 = std::min(K.height_px, r0 + kBandRows);
    cv::Mat rows = band.rowRange(0, r1 - r0);
    glReadPixels(0, r0, K.width_px, r1 - r0, GL_RGBA, GL_UNSIGNED_BYTE, rows.data);
    convert_rows(rows, r0, noise_seed, bgr);
  }
  check_gl("readback");
}

Renderer::Renderer(const Warehouse& warehouse, const CameraIntrinsics& intrinsics,
                   RenderOptions options) {
  if (!(options.noise_stddev >= 0.0) || options.motion_blur_samples < 1 ||
      options.motion_blur_samples > 64 || !(options.light_scale >= 0.0) ||
      options.supersample < 1 || options.supersample > 4 || !(options.near_m > 0.0) ||
      !(options.far_m > options.near_m) || !(options.rolling_shutter_margin_px >= 0.0) ||
      !(options.rolling_shutter_margin_px <= 1000.0)) {
    std::ostringstream os;
    os << "render options invalid: need noise_stddev >= 0 (" << options.noise_stddev
       << "), motion_blur_samples 1..64 (" << options.motion_blur_samples
       << "), light_scale >= 0 (" << options.light_scale << "), supersample 1..4 ("
       << options.supersample << "), 0 < near_m < far_m (" << options.near_m << ", "
       << options.far_m << "), rolling_shutter_margin_px 0..1000 ("
       << options.rolling_shutter_margin_px << ")";
    throw RenderError(os.str());
  }
  const SceneLayout layout = build_scene_layout(warehouse);  // validates before EGL
  impl_ = std::make_unique<Impl>(warehouse, intrinsics, options);
  if (options.noise_stddev > 0.0) {
    impl_->noise = std::make_unique<SensorNoise>(intrinsics.height_px, intrinsics.width_px, 3, options.noise_stddev);
  }
  impl_->build(layout);
}

void Renderer::Impl::release_gl() {
  target.release();
  glDeleteTextures(1, &atlas);
  glDeleteBuffers(1, &vbo);
  glDeleteBuffers(1, &ibo);
  glDeleteVertexArrays(1, &vao);
  glDeleteProgram(flat_program);
  glDeleteProgram(textured_program);
  atlas = vbo = ibo = vao = flat_program = textured_program = 0;
}

void Renderer::set_warehouse(const Warehouse& warehouse) {
  if (warehouse == impl_->warehouse) return;
  const SceneLayout layout = build_scene_layout(warehouse);  // validates before touching GL
  impl_->egl.make_current();
  impl_->release_gl();
  impl_->warehouse = warehouse;
  impl_->build(layout);
}

Renderer::~Renderer() {
  if (!impl_) return;
  try {
    impl_->egl.make_current();
    impl_->release_gl();
  } catch (const RenderError&) {
    // The context is current elsewhere: destroying it below frees its objects anyway.
  }
}

cv::Mat Renderer::render(const Eigen::Isometry3d& X_WC, std::uint64_t noise_seed) {
  cv::Mat bgr;
  render_into(X_WC, noise_seed, bgr);
  return bgr;
}

void Renderer::render_into(const Eigen::Isometry3d& X_WC, std::uint64_t noise_seed,
                           cv::Mat& bgr) {
  impl_->draw(X_WC, X_WC);
  impl_->read_and_finish(noise_seed, bgr);
}

void Renderer::render_rolling_into(const Eigen::Isometry3d& X_WC_start, const Eigen::Isometry3d& X_WC_end,
                                   std::uint64_t noise_seed, cv::Mat& bgr) {
  impl_->draw(X_WC_start, X_WC_end);
  impl_->read_and_finish(noise_seed, bgr);
}

cv::Mat Renderer::render_blurred(const Eigen::Isometry3d& X_WC_prev, const Eigen::Isometry3d& X_WC,
                                 std::uint64_t noise_seed) {
  cv::Mat bgr;
  render_blurred_into(X_WC_prev, X_WC, noise_seed, bgr);
  return bgr;
}

void Renderer::render_blurred_into(const Eigen::Isometry3d& X_WC_prev,
                                   const Eigen::Isometry3d& X_WC, std::uint64_t noise_seed,
                                   cv::Mat& bgr) {
  render_blurred_rolling_into(X_WC_prev, X_WC, X_WC, noise_seed, bgr);
}

void Renderer::render_blurred_rolling_into(const Eigen::Isometry3d& X_WC_prev,
                                           const Eigen::Isometry3d& X_WC_start,
                                           const Eigen::Isometry3d& X_WC, std::uint64_t noise_seed,
                                           cv::Mat& bgr) {
  const int n = impl_->options.motion_blur_samples;
  if (n == 1) {
    render_rolling_into(X_WC_start, X_WC, noise_seed, bgr);
    return;
  }
  const bool still = X_WC_start.matrix() == X_WC.matrix();
  const Eigen::Isometry3d X_CC_readout = X_WC.inverse(Eigen::Isometry) * X_WC_start;
  Impl& m = *impl_;
  cv::Mat& image = m.image();
  m.acc.create(image.size(), CV_16UC4);
  m.acc.setTo(cv::Scalar::all(0));
  for (int k = 0; k < n; ++k) {
    const Eigen::Isometry3d X =
        k == n - 1 ? X_WC : interpolate_pose(X_WC_prev, X_WC, static_cast<double>(k + 1) / n);
    // Each sub-pose's readout ends at it, with the readout's own motion (start relative to end).
    m.draw(still ? X : X * X_CC_readout, X);
    m.read();
    cv::add(m.acc, image, m.acc, cv::noArray(), CV_16U);
  }
  // Integer mean rounded half up: (sum + n/2) / n, exact (sum <= 64 * 255).
  const int half = n / 2;
  for (int r = 0; r < m.acc.rows; ++r) {
    const std::uint16_t* a = m.acc.ptr<std::uint16_t>(r);
    std::uint8_t* o = image.ptr<std::uint8_t>(r);
    for (int c = 0; c < m.acc.cols * 4; ++c) o[c] = static_cast<std::uint8_t>((a[c] + half) / n);
  }
  m.finish(noise_seed, bgr);
}

std::string Renderer::gl_renderer_name() const { return impl_->gl_renderer; }

std::string Renderer::backend_description() const {
  return "EGL platform " + impl_->egl.platform_name() + " (" + impl_->egl.egl_vendor() +
         "), GL_RENDERER " + impl_->gl_renderer + ", GL_VERSION " + impl_->gl_version;
}

const CameraIntrinsics& Renderer::intrinsics() const { return impl_->K; }
const RenderOptions& Renderer::options() const { return impl_->options; }
const LensMesher& Renderer::lens_mesh() const { return impl_->mesher; }

}  // namespace shelfcross::render
