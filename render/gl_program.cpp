#include "render/gl_program.hpp"

#include <sstream>
#include <string>

#define GL_GLEXT_PROTOTYPES 1
#include <GL/gl.h>
#include <GL/glext.h>

#include "render/render_error.hpp"

namespace shelfcross::render {
namespace {


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

}  // namespace

void check_gl(const char* where) {
  const GLenum e = glGetError();
  if (e != GL_NO_ERROR) {
    std::ostringstream os;
    os << "OpenGL: error 0x" << std::hex << e << " during " << where;
    throw RenderError(os.str());
  }
}

unsigned int link_flat_program() { return link_program(kFlatVertexShader, kFlatFragmentShader); }
unsigned int link_textured_program() { return link_program(kTexturedVertexShader, kTexturedFragmentShader); }

}  // namespace shelfcross::render
