#include "render/renderer.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <sstream>
#include <vector>

#define GL_GLEXT_PROTOTYPES 1
#include <GL/gl.h>
#include <GL/glext.h>

#include <opencv2/aruco.hpp>
#include <opencv2/imgproc.hpp>

#include "render/noise.hpp"
#include "render/scene.hpp"

namespace shelfcross::render {
namespace {

// One vertex of the static world: position in W, final sRGB colour of its face (lighting
// baked in), texture coordinate in the marker atlas (unused by untextured faces).
struct Vertex {
  float p_W[3];
  float rgb[3];
  float uv[2];
};

// Printed black is not black: ~4 % reflectance; in the sRGB-encoded product texel * colour
// this is about 0.2 of white.
constexpr std::uint8_t kBlackTexel = 51;
// Tags are lit only lightly so that their colour survives the lighting range:
// shade_tag = kTagFlat + (1 - kTagFlat) * shade.
constexpr double kTagFlat = 0.7;
// Albedo of the marker paper.
constexpr double kPaperAlbedo = 0.90;

double srgb_encode(double linear) {
  const double c = std::clamp(linear, 0.0, 1.0);
  return c <= 0.0031308 ? 12.92 * c : 1.055 * std::pow(c, 1.0 / 2.4) - 0.055;
}

const char* kVertexShader = R"(#version 330 core
layout(location = 0) in vec3 p_W;
layout(location = 1) in vec3 rgb;
layout(location = 2) in vec2 uv;
uniform mat4 clip_from_world;
flat out vec3 v_rgb;
out vec2 v_uv;
void main() {
  gl_Position = clip_from_world * vec4(p_W, 1.0);
  v_rgb = rgb;
  v_uv = uv;
}
)";

// Untextured faces: the colour alone. (On llvmpipe a texture fetch per pixel costs more than
// the rest of the pipeline, so only marker faces pay for it.)
const char* kFlatFragmentShader = R"(#version 330 core
flat in vec3 v_rgb;
in vec2 v_uv;
layout(location = 0) out vec4 colour;
void main() {
  colour = vec4(v_rgb, 1.0);
}
)";

const char* kTexturedFragmentShader = R"(#version 330 core
flat in vec3 v_rgb;
in vec2 v_uv;
uniform sampler2D atlas;
layout(location = 0) out vec4 colour;
void main() {
  colour = vec4(v_rgb * texture(atlas, v_uv).r, 1.0);
}
)";

GLuint compile_shader(GLenum type, const char* source) {
  GLuint s = glCreateShader(type);
  glShaderSource(s, 1, &source, nullptr);
  glCompileShader(s);
  GLint ok = 0;
  glGetShaderiv(s, GL_COMPILE_STATUS, &ok);
  if (!ok) {
    char log[2048] = {0};
    glGetShaderInfoLog(s, sizeof log, nullptr, log);
    glDeleteShader(s);
    throw RenderError(std::string("OpenGL: shader compilation failed: ") + log);
  }
  return s;
}

GLuint link_program(const char* vertex_source, const char* fragment_source) {
  const GLuint vs = compile_shader(GL_VERTEX_SHADER, vertex_source);
  const GLuint fs = compile_shader(GL_FRAGMENT_SHADER, fragment_source);
  const GLuint program = glCreateProgram();
  glAttachShader(program, vs);
  glAttachShader(program, fs);
  glLinkProgram(program);
  glDeleteShader(vs);
  glDeleteShader(fs);
  GLint ok = 0;
  glGetProgramiv(program, GL_LINK_STATUS, &ok);
  if (!ok) {
    char log[2048] = {0};
    glGetProgramInfoLog(program, sizeof log, nullptr, log);
    glDeleteProgram(program);
    throw RenderError(std::string("OpenGL: program link failed: ") + log);
  }
  return program;
}

void check_gl(const char* where) {
  const GLenum e = glGetError();
  if (e != GL_NO_ERROR) {
    std::ostringstream os;
    os << "OpenGL: error 0x" << std::hex << e << " during " << where;
    throw RenderError(os.str());
  }
}

// Builds the triangles of the whole static world.
class MeshBuilder {
 public:
  MeshBuilder(const Lighting& lighting, double light_scale)
      : lighting_(lighting), light_scale_(light_scale) {
    light_to_W_ = -lighting.direction_W.normalized();
  }

  // Lambert: ambient + directional * max(0, n . l), l toward the light.
  double shade(const Eigen::Vector3d& n_W) const {
    return lighting_.ambient + lighting_.directional * std::max(0.0, n_W.dot(light_to_W_));
  }
  Eigen::Vector3f colour(const Rgb& albedo, double shade_factor) const {
    const double k = shade_factor * light_scale_;
    return {static_cast<float>(srgb_encode(albedo.r * k)),
            static_cast<float>(srgb_encode(albedo.g * k)),
            static_cast<float>(srgb_encode(albedo.b * k))};
  }

  // Quad c0 c1 c2 c3 (in order around its edge) as triangles (0 1 2) (0 2 3).
  static void quad(const std::array<Eigen::Vector3d, 4>& c, const Eigen::Vector3f& rgb,
                   const std::array<Eigen::Vector2f, 4>& uv, std::vector<Vertex>& out) {
    for (int k : {0, 1, 2, 0, 2, 3}) {
      Vertex v;
      for (int a = 0; a < 3; ++a) {
        v.p_W[a] = static_cast<float>(c[static_cast<size_t>(k)][a]);
        v.rgb[a] = rgb[a];
      }
      v.uv[0] = uv[static_cast<size_t>(k)].x();
      v.uv[1] = uv[static_cast<size_t>(k)].y();
      out.push_back(v);
    }
  }
  void flat_quad(const std::array<Eigen::Vector3d, 4>& c, const Eigen::Vector3f& rgb) {
    const Eigen::Vector2f uv0 = Eigen::Vector2f::Zero();
    quad(c, rgb, {uv0, uv0, uv0, uv0}, flat_);
  }
  void textured_quad(const std::array<Eigen::Vector3d, 4>& c, const Eigen::Vector3f& rgb,
                     const std::array<Eigen::Vector2f, 4>& uv) {
    quad(c, rgb, uv, textured_);
  }

  // An axis-aligned box [lo, hi] in a frame X_WF: six faces, lit by their outward normals.
  void cuboid(const Eigen::Isometry3d& X_WF, const Eigen::Vector3d& lo, const Eigen::Vector3d& hi,
              const Rgb& albedo) {
    for (int axis = 0; axis < 3; ++axis) {
      const int a1 = (axis + 1) % 3, a2 = (axis + 2) % 3;
      for (int side = 0; side < 2; ++side) {
        Eigen::Vector3d n_F = Eigen::Vector3d::Zero();
        n_F[axis] = side ? 1.0 : -1.0;
        std::array<Eigen::Vector3d, 4> c;
        const double uv_a[4][2] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
        for (int k = 0; k < 4; ++k) {
          Eigen::Vector3d p;
          p[axis] = side ? hi[axis] : lo[axis];
          p[a1] = uv_a[k][0] ? hi[a1] : lo[a1];
          p[a2] = uv_a[k][1] ? hi[a2] : lo[a2];
          c[static_cast<size_t>(k)] = X_WF * p;
        }
        flat_quad(c, colour(albedo, shade(X_WF.linear() * n_F)));
      }
    }
  }

  /// Untextured faces (drawn first, with the flat-colour program), then marker faces.
  const std::vector<Vertex>& flat() const { return flat_; }
  const std::vector<Vertex>& textured() const { return textured_; }

 private:
  Lighting lighting_;
  double light_scale_;
  Eigen::Vector3d light_to_W_;
  std::vector<Vertex> flat_, textured_;
};

Eigen::Isometry3d interpolate_pose(const Eigen::Isometry3d& X0, const Eigen::Isometry3d& X1,
                                   double s) {
  const Eigen::Quaterniond q0(X0.linear()), q1(X1.linear());
  Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
  X.linear() = q0.slerp(s, q1).normalized().toRotationMatrix();
  X.translation() = (1.0 - s) * X0.translation() + s * X1.translation();
  return X;
}

}  // namespace

struct Renderer::Impl {
  Warehouse warehouse;
  CameraIntrinsics K;
  RenderOptions options;
  RenderCamera camera;       // 1x undistorted render camera and float map
  int hi_width = 0, hi_height = 0;  // render size x supersample
  Eigen::Matrix4d clip_from_camera = Eigen::Matrix4d::Identity();
  EglContext egl;
  std::string gl_renderer, gl_version;

  GLuint flat_program = 0, textured_program = 0, vao = 0, vbo = 0, fbo = 0, colour_rb = 0, depth_rb = 0, atlas = 0;
  GLint flat_clip_loc = -1, textured_clip_loc = -1;
  GLsizei flat_count = 0, textured_count = 0;

  cv::Mat map1, map2;        // fixed-point remap maps (CV_16SC2 + CV_16UC1)
  std::unique_ptr<SensorNoise> noise;  // when options.noise_stddev > 0
  cv::Mat rgba_hi, rgba, acc, distorted_rgba;  // per-frame RGBA buffers, allocated once

  Impl(const Warehouse& w, const CameraIntrinsics& k, const RenderOptions& o)
      : warehouse(w), K(k), options(o), egl(o.egl_platform) {}

  void build(const SceneLayout& layout);
  void release_gl();  // deletes the GL objects build() made (context current)
  void draw_and_read(const Eigen::Isometry3d& X_WC);  // -> rgba (1x render size)
  void finish(std::uint64_t noise_seed, cv::Mat& bgr);
};

void Renderer::Impl::build(const SceneLayout& layout) {
  const int s = options.supersample;
  hi_width = camera.width_px * s;
  hi_height = camera.height_px * s;
  // Supersampled camera: hi-res pixel u_s = s u + (s - 1)/2 has the same centre as the
  // s x s block average that INTER_AREA assigns to 1x pixel u.
  clip_from_camera =
      gl_clip_from_camera(s * camera.fx_px, s * camera.fy_px, s * camera.cx_px + 0.5 * (s - 1),
                          s * camera.cy_px + 0.5 * (s - 1), hi_width, hi_height, options.near_m,
                          options.far_m);

  // ---- marker atlas: tile 0 white, then one tile per distinct marker ID ----
  const int tile = layout.marker_bits + 2 + 2 * kQuietZoneCells;
  std::map<int, int> tile_of_id;
  for (const MarkerQuad& m : layout.markers) tile_of_id.emplace(m.marker_id, 0);
  int next_tile = 1;
  for (auto& [id, t] : tile_of_id) t = next_tile++;
  const int atlas_w = tile * next_tile;
  cv::Mat atlas_img(tile, atlas_w, CV_8UC1, cv::Scalar(255));
  const cv::Ptr<cv::aruco::Dictionary> dict =
      cv::aruco::getPredefinedDictionary(layout.aruco_dictionary_id);
  for (const auto& [id, t] : tile_of_id) {
    cv::Mat marker;  // one pixel per marker cell, black border one cell wide
    cv::aruco::drawMarker(dict, id, layout.marker_bits + 2, marker, 1);
    cv::Mat dst = atlas_img(cv::Rect(t * tile + kQuietZoneCells, kQuietZoneCells,
                                     layout.marker_bits + 2, layout.marker_bits + 2));
    marker.copyTo(dst);
  }
  atlas_img.setTo(cv::Scalar(kBlackTexel), atlas_img == 0);

  // ---- static world ----
  MeshBuilder mesh(warehouse.lighting, options.light_scale);
  for (const Cuboid& c : layout.cuboids) {
    const Rgb& albedo = c.kind == Cuboid::Kind::kBox ? warehouse.box_colour : warehouse.bar_colour;
    mesh.cuboid(layout.X_WS[static_cast<size_t>(c.shelf)], c.min_S_m, c.max_S_m, albedo);
  }
  for (const TagQuad& t : layout.tags) {
    mesh.flat_quad(t.corners_W_m,
                   mesh.colour(warehouse.tag_colour, kTagFlat + (1.0 - kTagFlat) * mesh.shade(t.normal_W)));
    // Tags are coloured on their outer side only: half-way between the tag and the bar, a
    // backing square in the bar colour is what shows from inside the shelf (a tag of the
    // back face seen through the cells from the front is not a tag blob).
    std::array<Eigen::Vector3d, 4> back = t.corners_W_m;
    for (auto& c : back) c -= 0.5 * kSurfaceOffset_m * t.normal_W;
    mesh.flat_quad(back, mesh.colour(warehouse.bar_colour, mesh.shade(-t.normal_W)));
  }
  // Room: floor, ceiling, four walls, as the inside of the arena box (normals inward); after
  // the shelves, so that the early depth test skips most of their hidden pixels.
  {
    const Eigen::Vector3d lo = warehouse.arena_min_W_m, hi = warehouse.arena_max_W_m;
    const Eigen::Isometry3d I = Eigen::Isometry3d::Identity();
    auto room_face = [&](int axis, bool high, const Rgb& albedo) {
      // One face of the arena box, lit by its inward normal.
      const int a1 = (axis + 1) % 3, a2 = (axis + 2) % 3;
      std::array<Eigen::Vector3d, 4> c;
      const double uv_a[4][2] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
      for (int k = 0; k < 4; ++k) {
        Eigen::Vector3d p;
        p[axis] = high ? hi[axis] : lo[axis];
        p[a1] = uv_a[k][0] ? hi[a1] : lo[a1];
        p[a2] = uv_a[k][1] ? hi[a2] : lo[a2];
        c[static_cast<size_t>(k)] = I * p;
      }
      Eigen::Vector3d n = Eigen::Vector3d::Zero();
      n[axis] = high ? -1.0 : 1.0;
      mesh.flat_quad(c, mesh.colour(albedo, mesh.shade(n)));
    };
    room_face(2, false, warehouse.floor_colour);
    room_face(2, true, warehouse.wall_colour);
    for (int axis : {0, 1})
      for (bool high : {false, true}) room_face(axis, high, warehouse.wall_colour);
  }
  for (const MarkerQuad& m : layout.markers) {
    const float u0 = static_cast<float>(tile_of_id.at(m.marker_id) * tile) / atlas_w;
    const float u1 = static_cast<float>((tile_of_id.at(m.marker_id) + 1) * tile) / atlas_w;
    // Corners TL TR BR BL <- image rows top (v = 0) to bottom (v = 1).
    mesh.textured_quad(m.quiet_corners_W_m,
              mesh.colour({kPaperAlbedo, kPaperAlbedo, kPaperAlbedo}, mesh.shade(m.normal_W)),
              {Eigen::Vector2f(u0, 0.f), Eigen::Vector2f(u1, 0.f), Eigen::Vector2f(u1, 1.f),
               Eigen::Vector2f(u0, 1.f)});
  }
  flat_count = static_cast<GLsizei>(mesh.flat().size());
  textured_count = static_cast<GLsizei>(mesh.textured().size());
  std::vector<Vertex> vertices = mesh.flat();
  vertices.insert(vertices.end(), mesh.textured().begin(), mesh.textured().end());

  // ---- GL objects ----
  egl.make_current();
  const char* r = reinterpret_cast<const char*>(glGetString(GL_RENDERER));
  const char* v = reinterpret_cast<const char*>(glGetString(GL_VERSION));
  gl_renderer = r ? r : "?";
  gl_version = v ? v : "?";

  flat_program = link_program(kVertexShader, kFlatFragmentShader);
  flat_clip_loc = glGetUniformLocation(flat_program, "clip_from_world");
  textured_program = link_program(kVertexShader, kTexturedFragmentShader);
  textured_clip_loc = glGetUniformLocation(textured_program, "clip_from_world");
  glUseProgram(textured_program);
  glUniform1i(glGetUniformLocation(textured_program, "atlas"), 0);

  glGenVertexArrays(1, &vao);
  glBindVertexArray(vao);
  glGenBuffers(1, &vbo);
  glBindBuffer(GL_ARRAY_BUFFER, vbo);
  glBufferData(GL_ARRAY_BUFFER, static_cast<GLsizeiptr>(vertices.size() * sizeof(Vertex)),
               vertices.data(), GL_STATIC_DRAW);
  glVertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, sizeof(Vertex),
                        reinterpret_cast<const void*>(offsetof(Vertex, p_W)));
  glVertexAttribPointer(1, 3, GL_FLOAT, GL_FALSE, sizeof(Vertex),
                        reinterpret_cast<const void*>(offsetof(Vertex, rgb)));
  glVertexAttribPointer(2, 2, GL_FLOAT, GL_FALSE, sizeof(Vertex),
                        reinterpret_cast<const void*>(offsetof(Vertex, uv)));
  for (GLuint a : {0u, 1u, 2u}) glEnableVertexAttribArray(a);

  glGenTextures(1, &atlas);
  glActiveTexture(GL_TEXTURE0);
  glBindTexture(GL_TEXTURE_2D, atlas);
  glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
  glTexImage2D(GL_TEXTURE_2D, 0, GL_R8, atlas_w, tile, 0, GL_RED, GL_UNSIGNED_BYTE, atlas_img.data);
  // Nearest: marker cells stay crisp; cell edges fall exactly where the geometry puts them.
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);

  GLint max_rb = 0;
  glGetIntegerv(GL_MAX_RENDERBUFFER_SIZE, &max_rb);
  if (hi_width > max_rb || hi_height > max_rb) {
    std::ostringstream os;
    os << "OpenGL: render size " << hi_width << " x " << hi_height
       << " exceeds GL_MAX_RENDERBUFFER_SIZE " << max_rb << " (lower supersample)";
    throw RenderError(os.str());
  }
  glGenFramebuffers(1, &fbo);
  glBindFramebuffer(GL_FRAMEBUFFER, fbo);
  glGenRenderbuffers(1, &colour_rb);
  glBindRenderbuffer(GL_RENDERBUFFER, colour_rb);
  glRenderbufferStorage(GL_RENDERBUFFER, GL_RGBA8, hi_width, hi_height);
  glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER, colour_rb);
  glGenRenderbuffers(1, &depth_rb);
  glBindRenderbuffer(GL_RENDERBUFFER, depth_rb);
  glRenderbufferStorage(GL_RENDERBUFFER, GL_DEPTH_COMPONENT24, hi_width, hi_height);
  glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, depth_rb);
  const GLenum status = glCheckFramebufferStatus(GL_FRAMEBUFFER);
  if (status != GL_FRAMEBUFFER_COMPLETE) {
    std::ostringstream os;
    os << "OpenGL: framebuffer incomplete (status 0x" << std::hex << status << ")";
    throw RenderError(os.str());
  }
  glViewport(0, 0, hi_width, hi_height);
  glEnable(GL_DEPTH_TEST);
  glDepthFunc(GL_LESS);
  glDisable(GL_CULL_FACE);
  glDisable(GL_DITHER);
  glDisable(GL_MULTISAMPLE);
  glDisable(GL_BLEND);
  glClearColor(0.f, 0.f, 0.f, 1.f);
  glPixelStorei(GL_PACK_ALIGNMENT, 4);
  check_gl("renderer initialisation");

  // ---- per-frame buffers and the fixed-point distortion map, once ----
  rgba_hi.create(hi_height, hi_width, CV_8UC4);
  rgba.create(camera.height_px, camera.width_px, CV_8UC4);
  distorted_rgba.create(K.height_px, K.width_px, CV_8UC4);
  cv::convertMaps(camera.map_xy, cv::noArray(), map1, map2, CV_16SC2);
}

void Renderer::Impl::draw_and_read(const Eigen::Isometry3d& X_WC) {
  egl.make_current();
  const Eigen::Matrix4f clip_from_world =
      (clip_from_camera * X_WC.inverse(Eigen::Isometry).matrix()).cast<float>();
  glBindFramebuffer(GL_FRAMEBUFFER, fbo);
  glBindVertexArray(vao);
  glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
  // Two draw calls for the whole static world: flat faces, then marker faces.
  glUseProgram(flat_program);
  glUniformMatrix4fv(flat_clip_loc, 1, GL_FALSE, clip_from_world.data());
  glDrawArrays(GL_TRIANGLES, 0, flat_count);
  if (textured_count > 0) {
    glUseProgram(textured_program);
    glUniformMatrix4fv(textured_clip_loc, 1, GL_FALSE, clip_from_world.data());
    glDrawArrays(GL_TRIANGLES, flat_count, textured_count);
  }
  // Rows come back bottom GL row first = image row 0 first (see gl_clip_from_camera).
  // RGBA, the renderbuffer's own layout on Mesa: a plain copy (BGRA costs a swizzle pass,
  // ~6x slower on llvmpipe); the channel order is fixed in the final cvtColor.
  glReadPixels(0, 0, hi_width, hi_height, GL_RGBA, GL_UNSIGNED_BYTE, rgba_hi.data);
  check_gl("draw and readback");
  if (options.supersample > 1) {
    // Exact s x s block means for an integer factor.
    cv::resize(rgba_hi, rgba, rgba.size(), 0, 0, cv::INTER_AREA);
  }
}

void Renderer::Impl::finish(std::uint64_t noise_seed, cv::Mat& bgr) {
  const cv::Mat& undistorted = options.supersample > 1 ? rgba : rgba_hi;
  cv::remap(undistorted, distorted_rgba, map1, map2, cv::INTER_LINEAR, cv::BORDER_CONSTANT,
            cv::Scalar(0, 0, 0, 255));
  bgr.create(K.height_px, K.width_px, CV_8UC3);
  cv::cvtColor(distorted_rgba, bgr, cv::COLOR_RGBA2BGR);
  if (noise) noise->apply(bgr, noise_seed);
}

Renderer::Renderer(const Warehouse& warehouse, const CameraIntrinsics& intrinsics,
                   RenderOptions options) {
  if (!(options.noise_stddev >= 0.0) || options.motion_blur_samples < 1 ||
      options.motion_blur_samples > 64 || !(options.light_scale >= 0.0) ||
      options.supersample < 1 || options.supersample > 4 || !(options.near_m > 0.0) ||
      !(options.far_m > options.near_m)) {
    std::ostringstream os;
    os << "render options invalid: need noise_stddev >= 0 (" << options.noise_stddev
       << "), motion_blur_samples 1..64 (" << options.motion_blur_samples
       << "), light_scale >= 0 (" << options.light_scale << "), supersample 1..4 ("
       << options.supersample << "), 0 < near_m < far_m (" << options.near_m << ", "
       << options.far_m << ")";
    throw RenderError(os.str());
  }
  const SceneLayout layout = build_scene_layout(warehouse);  // validates before EGL
  RenderCamera camera = make_render_camera(intrinsics);
  if (camera.max_roundtrip_error_px > 1e-3) {
    std::ostringstream os;
    os << "lens distortion cannot be inverted accurately over the image (round trip error "
       << camera.max_roundtrip_error_px << " px)";
    throw RenderError(os.str());
  }
  impl_ = std::make_unique<Impl>(warehouse, intrinsics, options);
  impl_->camera = std::move(camera);
  if (options.noise_stddev > 0.0) {
    impl_->noise = std::make_unique<SensorNoise>(intrinsics.height_px, intrinsics.width_px, 3, options.noise_stddev);
  }
  impl_->build(layout);
}

void Renderer::Impl::release_gl() {
  glDeleteFramebuffers(1, &fbo);
  glDeleteRenderbuffers(1, &colour_rb);
  glDeleteRenderbuffers(1, &depth_rb);
  glDeleteTextures(1, &atlas);
  glDeleteBuffers(1, &vbo);
  glDeleteVertexArrays(1, &vao);
  glDeleteProgram(flat_program);
  glDeleteProgram(textured_program);
  fbo = colour_rb = depth_rb = atlas = vbo = vao = flat_program = textured_program = 0;
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
  impl_->draw_and_read(X_WC);
  impl_->finish(noise_seed, bgr);
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
  const int n = impl_->options.motion_blur_samples;
  if (n == 1) {
    render_into(X_WC, noise_seed, bgr);
    return;
  }
  Impl& m = *impl_;
  cv::Mat& undistorted = m.options.supersample > 1 ? m.rgba : m.rgba_hi;
  m.acc.create(undistorted.size(), CV_16UC4);
  m.acc.setTo(cv::Scalar::all(0));
  for (int k = 0; k < n; ++k) {
    const Eigen::Isometry3d X =
        k == n - 1 ? X_WC : interpolate_pose(X_WC_prev, X_WC, static_cast<double>(k + 1) / n);
    m.draw_and_read(X);
    cv::add(m.acc, undistorted, m.acc, cv::noArray(), CV_16U);
  }
  // Integer mean rounded half up: (sum + n/2) / n, exact (sum <= 64 * 255).
  const int half = n / 2;
  for (int r = 0; r < m.acc.rows; ++r) {
    const std::uint16_t* a = m.acc.ptr<std::uint16_t>(r);
    std::uint8_t* o = undistorted.ptr<std::uint8_t>(r);
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
const RenderCamera& Renderer::render_camera() const { return impl_->camera; }

}  // namespace shelfcross::render
