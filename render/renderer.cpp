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

#include "render/frame_target.hpp"
#include "render/lens_mesh.hpp"
#include "render/noise.hpp"
#include "render/scene.hpp"

namespace shelfcross::render {
namespace {

// Printed black is not black: ~4 % reflectance; in the sRGB-encoded product texel * colour
// this is about 0.2 of white.
constexpr std::uint8_t kBlackTexel = 51;
// Tags are lit only lightly so that their colour survives the lighting range:
// shade_tag = kTagFlat + (1 - kTagFlat) * shade.
constexpr double kTagFlat = 0.7;
// Albedo of the marker paper.
constexpr double kPaperAlbedo = 0.90;
// The texture coordinates of a face without texture: zeros. (Eigen's default constructor leaves
// a vector's coefficients unset, and copying them would read indeterminate values.)
const std::array<Eigen::Vector2f, 4> kNoTexture{Eigen::Vector2f::Zero(), Eigen::Vector2f::Zero(),
                                                Eigen::Vector2f::Zero(), Eigen::Vector2f::Zero()};

double srgb_encode(double linear) {
  const double c = std::clamp(linear, 0.0, 1.0);
  return c <= 0.0031308 ? 12.92 * c : 1.055 * std::pow(c, 1.0 / 2.4) - 0.055;
}

// Vertices arrive in clip coordinates, the lens already applied (lens_mesh.hpp). Flat faces
// pass on only their colour (fewer interpolants: cheaper triangle set-up on llvmpipe).
const char* kFlatVertexShader = R"(#version 330 core
layout(location = 0) in vec4 clip;
layout(location = 1) in vec3 rgb;
flat out vec3 v_rgb;
void main() {
  gl_Position = clip;
  v_rgb = rgb;
}
)";

const char* kTexturedVertexShader = R"(#version 330 core
layout(location = 0) in vec4 clip;
layout(location = 1) in vec3 rgb;
layout(location = 2) in vec2 uv;
flat out vec3 v_rgb;
out vec2 v_uv;
void main() {
  gl_Position = clip;
  v_rgb = rgb;
  v_uv = uv;
}
)";

// Untextured faces: the colour alone. (On llvmpipe a texture fetch per pixel costs more than
// the rest of the pipeline, so only marker faces pay for it.)
const char* kFlatFragmentShader = R"(#version 330 core
flat in vec3 v_rgb;
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

// Builds the faces of the whole static world (lens_mesh.hpp turns them into triangles per frame).
class FaceBuilder {
 public:
  FaceBuilder(const Lighting& lighting, double light_scale)
      : lighting_(lighting), light_scale_(light_scale) {
    light_to_W_ = -lighting.direction_W.normalized();
  }

  // Lambert: ambient + directional * max(0, n . l), l toward the light.
  double shade(const Eigen::Vector3d& n_W) const {
    return lighting_.ambient + lighting_.directional * std::max(0.0, n_W.dot(light_to_W_));
  }
  // The face's 8-bit colour k / 255, k = round(255 srgb): the byte GL writes for it, whether
  // a fragment or a clear (renderer.cpp clears to a room face's colour) writes it.
  Eigen::Vector3f colour(const Rgb& albedo, double shade_factor) const {
    const double k = shade_factor * light_scale_;
    auto byte = [](double linear) {
      return static_cast<float>(std::nearbyint(255.0 * srgb_encode(linear)) / 255.0);
    };
    return {byte(albedo.r * k), byte(albedo.g * k), byte(albedo.b * k)};
  }

  // A quad c0 c1 c2 c3 (in order around its edge), seen from the side n_W points to.
  void face(FaceGroup group, const std::array<Eigen::Vector3d, 4>& c, const Eigen::Vector3d& n_W,
            const Eigen::Vector3f& rgb, const std::array<Eigen::Vector2f, 4>& uv = kNoTexture,
            int solid = -1) {
    MeshFace f;
    f.corners_W_m = c;
    f.normal_W = n_W;
    f.rgb = rgb;
    f.uv = uv;
    f.solid = solid;
    faces_[static_cast<std::size_t>(group)].push_back(f);
  }
  // A new id for the faces of one closed solid (MeshFace::solid).
  int new_solid() { return next_solid_++; }

  // An axis-aligned box [lo, hi] in a frame X_WF: six faces, lit by and seen along their
  // outward normals.
  void cuboid(const Eigen::Isometry3d& X_WF, const Eigen::Vector3d& lo, const Eigen::Vector3d& hi,
              const Rgb& albedo) {
    const int solid = new_solid();
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
        const Eigen::Vector3d n_W = X_WF.linear() * n_F;
        face(kFlatFaces, c, n_W, colour(albedo, shade(n_W)), kNoTexture, solid);
      }
    }
  }

  std::vector<MeshFace>& faces(FaceGroup group) { return faces_[static_cast<std::size_t>(group)]; }

 private:
  Lighting lighting_;
  double light_scale_;
  Eigen::Vector3d light_to_W_;
  std::array<std::vector<MeshFace>, kFaceGroups> faces_;
  int next_solid_ = 0;
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
        mesher(k, o.supersample, o.near_m, o.far_m, kLensChordTolerance_px),
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
  void draw(const Eigen::Isometry3d& X_WC);  // the frame into the framebuffer
  void read();                                // framebuffer -> image() (1x image size)
  void finish(std::uint64_t noise_seed, cv::Mat& bgr);  // image() -> bgr
  // RGBA rows first_row.. of the frame -> the same rows of bgr (allocated): BGR, noise added
  void convert_rows(const cv::Mat& rgba_rows, int first_row, std::uint64_t noise_seed, cv::Mat& bgr);
  void read_and_finish(std::uint64_t noise_seed, cv::Mat& bgr);  // framebuffer -> bgr
  cv::Mat& image() { return options.supersample > 1 ? rgba : rgba_hi; }
};

void Renderer::Impl::build(const SceneLayout& layout) {
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
  FaceBuilder mesh(warehouse.lighting, options.light_scale);
  for (const Cuboid& c : layout.cuboids) {
    const Rgb& albedo = c.kind == Cuboid::Kind::kBox ? warehouse.box_colour : warehouse.bar_colour;
    mesh.cuboid(layout.X_WS[static_cast<size_t>(c.shelf)], c.min_S_m, c.max_S_m, albedo);
  }
  for (const TagQuad& t : layout.tags) {
    mesh.face(kDecalFaces, t.corners_W_m, t.normal_W,
              mesh.colour(warehouse.tag_colour, kTagFlat + (1.0 - kTagFlat) * mesh.shade(t.normal_W)));
    // Tags are coloured on their outer side only: half-way between the tag and the bar, a
    // backing square in the bar colour, facing inward, is what shows from inside the shelf (a
    // tag of the back face seen through the cells from the front is not a tag blob).
    std::array<Eigen::Vector3d, 4> back = t.corners_W_m;
    for (auto& c : back) c -= 0.5 * kSurfaceOffset_m * t.normal_W;
    mesh.face(kFlatFaces, back, -t.normal_W, mesh.colour(warehouse.bar_colour, mesh.shade(-t.normal_W)));
  }
  // Room: floor, ceiling, four walls, as the inside of the arena box (normals inward).
  const Eigen::Vector3d lo = warehouse.arena_min_W_m, hi = warehouse.arena_max_W_m;
  arena = Eigen::AlignedBox3d(lo, hi);
  const int room_solid = mesh.new_solid();
  auto room_face = [&](int axis, bool high, const Rgb& albedo) {
    // One face of the arena box, lit by and seen along its inward normal.
    const int a1 = (axis + 1) % 3, a2 = (axis + 2) % 3;
    std::array<Eigen::Vector3d, 4> c;
    const double uv_a[4][2] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
    for (int k = 0; k < 4; ++k) {
      Eigen::Vector3d p;
      p[axis] = high ? hi[axis] : lo[axis];
      p[a1] = uv_a[k][0] ? hi[a1] : lo[a1];
      p[a2] = uv_a[k][1] ? hi[a2] : lo[a2];
      c[static_cast<size_t>(k)] = p;
    }
    Eigen::Vector3d n = Eigen::Vector3d::Zero();
    n[axis] = high ? -1.0 : 1.0;
    mesh.face(kRoomFaces, c, n, mesh.colour(albedo, mesh.shade(n)), kNoTexture, room_solid);
  };
  room_face(2, false, warehouse.floor_colour);
  room_face(2, true, warehouse.wall_colour);
  for (int axis : {0, 1})
    for (bool high : {false, true}) room_face(axis, high, warehouse.wall_colour);
  for (const MarkerQuad& m : layout.markers) {
    const float u0 = static_cast<float>(tile_of_id.at(m.marker_id) * tile) / atlas_w;
    const float u1 = static_cast<float>((tile_of_id.at(m.marker_id) + 1) * tile) / atlas_w;
    // Corners TL TR BR BL <- image rows top (v = 0) to bottom (v = 1).
    mesh.face(kTexturedFaces, m.quiet_corners_W_m, m.normal_W,
              mesh.colour({kPaperAlbedo, kPaperAlbedo, kPaperAlbedo}, mesh.shade(m.normal_W)),
              {Eigen::Vector2f(u0, 0.f), Eigen::Vector2f(u1, 0.f), Eigen::Vector2f(u1, 1.f),
               Eigen::Vector2f(u0, 1.f)});
  }
  room_first = true;
  for (FaceGroup g : {kFlatFaces, kDecalFaces, kTexturedFaces})
    for (const MeshFace& f : mesh.faces(g))
      for (const Eigen::Vector3d& c : f.corners_W_m) room_first = room_first && arena.contains(c);
  for (FaceGroup g : {kRoomFaces, kFlatFaces, kDecalFaces, kTexturedFaces})
    mesher.set_faces(g, std::move(mesh.faces(g)));
  // Drawn first, without the depth test (draw): the room's faces need no depth inside.
  mesher.set_depth_tested(kRoomFaces, !room_first);

  // ---- GL objects ----
  egl.make_current();
  const char* r = reinterpret_cast<const char*>(glGetString(GL_RENDERER));
  const char* v = reinterpret_cast<const char*>(glGetString(GL_VERSION));
  gl_renderer = r ? r : "?";
  gl_version = v ? v : "?";

  flat_program = link_program(kFlatVertexShader, kFlatFragmentShader);
  textured_program = link_program(kTexturedVertexShader, kTexturedFragmentShader);
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
  glTexImage2D(GL_TEXTURE_2D, 0, GL_R8, atlas_w, tile, 0, GL_RED, GL_UNSIGNED_BYTE, atlas_img.data);
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

void Renderer::Impl::draw(const Eigen::Isometry3d& X_WC) {
  egl.make_current();
  mesher.build(X_WC);
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
  const Eigen::Vector3d p = X_WC.translation();
  const double wall_distance = std::min((p - arena.min()).minCoeff(), (arena.max() - p).minCoeff());
  double farthest = 0.0;
  for (int c = 0; c < 8; ++c)
    farthest = std::max(farthest, (arena.corner(static_cast<Eigen::AlignedBox3d::CornerType>(c)) - p).norm());
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
  impl_->draw(X_WC);
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
  const int n = impl_->options.motion_blur_samples;
  if (n == 1) {
    render_into(X_WC, noise_seed, bgr);
    return;
  }
  Impl& m = *impl_;
  cv::Mat& image = m.image();
  m.acc.create(image.size(), CV_16UC4);
  m.acc.setTo(cv::Scalar::all(0));
  for (int k = 0; k < n; ++k) {
    const Eigen::Isometry3d X =
        k == n - 1 ? X_WC : interpolate_pose(X_WC_prev, X_WC, static_cast<double>(k + 1) / n);
    m.draw(X);
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
