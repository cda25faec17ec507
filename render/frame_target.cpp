#include "render/frame_target.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <sstream>
#include <string>

#define GL_GLEXT_PROTOTYPES 1
#include <GL/gl.h>
#include <GL/glext.h>

#include "render/render_error.hpp"

namespace shelfcross::render {
namespace {

bool has_extension(const char* name) {
  GLint n = 0;
  glGetIntegerv(GL_NUM_EXTENSIONS, &n);
  for (GLint i = 0; i < n; ++i) {
    const char* e = reinterpret_cast<const char*>(glGetStringi(GL_EXTENSIONS, static_cast<GLuint>(i)));
    if (e && std::strcmp(e, name) == 0) return true;
  }
  return false;
}

// A texture of the given format for a framebuffer attachment (no mipmaps: level 0 only).
GLuint attachment_texture(GLint internal_format, GLenum format, GLenum type, int width_px,
                          int height_px) {
  GLuint t = 0;
  glGenTextures(1, &t);
  glBindTexture(GL_TEXTURE_2D, t);
  glTexImage2D(GL_TEXTURE_2D, 0, internal_format, width_px, height_px, 0, format, type, nullptr);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAX_LEVEL, 0);
  return t;
}

}  // namespace

PixelBox covered_pixels(const std::vector<GpuVertex>& vertices,
                        const std::vector<std::uint32_t>& indices, std::size_t first,
                        std::size_t end, int width_px, int height_px) {
  if (end <= first) return {};
  // Window coordinates of the viewport (0, 0, width, height): x_w = (x / w + 1) width / 2.
  float x_min = INFINITY, x_max = -INFINITY, y_min = INFINITY, y_max = -INFINITY;
  for (std::size_t i = first; i < end; ++i) {
    const float* c = vertices[indices[i]].clip;
    const float x = c[0] / c[3], y = c[1] / c[3];
    x_min = std::min(x_min, x);
    x_max = std::max(x_max, x);
    y_min = std::min(y_min, y);
    y_max = std::max(y_max, y);
  }
  auto window = [](float ndc, int size) { return (0.5 * static_cast<double>(ndc) + 0.5) * size; };
  auto lower = [](double w, int size) {
    return static_cast<int>(std::clamp(std::floor(w) - 1.0, 0.0, static_cast<double>(size)));
  };
  auto upper = [](double w, int size) {
    return static_cast<int>(std::clamp(std::ceil(w) + 1.0, 0.0, static_cast<double>(size)));
  };
  return {lower(window(x_min, width_px), width_px), lower(window(y_min, height_px), height_px),
          upper(window(x_max, width_px), width_px), upper(window(y_max, height_px), height_px)};
}

void FrameTarget::create(int width_px, int height_px) {
  GLint max_size = 0;
  glGetIntegerv(GL_MAX_TEXTURE_SIZE, &max_size);
  if (width_px > max_size || height_px > max_size) {
    std::ostringstream os;
    os << "OpenGL: render size " << width_px << " x " << height_px
       << " exceeds GL_MAX_TEXTURE_SIZE " << max_size << " (lower supersample)";
    throw RenderError(os.str());
  }
  width_px_ = width_px;
  height_px_ = height_px;
  GLint bound_texture = 0;  // the caller's binding of GL_TEXTURE_2D, restored below
  glGetIntegerv(GL_TEXTURE_BINDING_2D, &bound_texture);
  colour_ = attachment_texture(GL_RGBA8, GL_RGBA, GL_UNSIGNED_BYTE, width_px, height_px);
  depth_ = attachment_texture(GL_DEPTH_COMPONENT24, GL_DEPTH_COMPONENT, GL_UNSIGNED_INT, width_px,
                              height_px);
  glBindTexture(GL_TEXTURE_2D, static_cast<GLuint>(bound_texture));
  glGenFramebuffers(1, &fbo_);
  glBindFramebuffer(GL_FRAMEBUFFER, fbo_);
  glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_TEXTURE_2D, colour_, 0);
  glFramebufferTexture2D(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_TEXTURE_2D, depth_, 0);
  const GLenum status = glCheckFramebufferStatus(GL_FRAMEBUFFER);
  if (status != GL_FRAMEBUFFER_COMPLETE) {
    std::ostringstream os;
    os << "OpenGL: framebuffer incomplete (status 0x" << std::hex << status << ")";
    throw RenderError(os.str());
  }
  GLint major = 0, minor = 0;
  glGetIntegerv(GL_MAJOR_VERSION, &major);
  glGetIntegerv(GL_MINOR_VERSION, &minor);
  clear_texture_ = major > 4 || (major == 4 && minor >= 4) || has_extension("GL_ARB_clear_texture");
}

void FrameTarget::release() {
  glDeleteFramebuffers(1, &fbo_);
  glDeleteTextures(1, &colour_);
  glDeleteTextures(1, &depth_);
  fbo_ = colour_ = depth_ = 0;
}

void FrameTarget::bind() const { glBindFramebuffer(GL_FRAMEBUFFER, fbo_); }

void FrameTarget::start_frame(const std::array<std::uint8_t, 4>& rgba8, const PixelBox& depth_box) const {
  if (!clear_texture_) {
    glClearColor(rgba8[0] / 255.f, rgba8[1] / 255.f, rgba8[2] / 255.f, rgba8[3] / 255.f);
    glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
    return;
  }
  glClearTexImage(colour_, 0, GL_RGBA, GL_UNSIGNED_BYTE, rgba8.data());
  if (depth_box.empty()) return;
  const float far = 1.f;
  glClearTexSubImage(depth_, 0, depth_box.x0, depth_box.y0, 0, depth_box.x1 - depth_box.x0,
                     depth_box.y1 - depth_box.y0, 1, GL_DEPTH_COMPONENT, GL_FLOAT, &far);
}

}  // namespace shelfcross::render
