#pragma once
// The one exception type of render/: thrown for an unusable warehouse or camera (bad
// dictionary name, marker ID out of range, a lens model that cannot be inverted over the
// image) and for EGL/OpenGL initialisation failures. The message says what and why.

#include <stdexcept>

namespace shelfcross::render {

struct RenderError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

}  // namespace shelfcross::render
