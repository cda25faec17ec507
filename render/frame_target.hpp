#pragma once
// The framebuffer a Renderer draws into: an RGBA8 colour texture and a 24-bit depth texture of
// the rasterised size, and how each frame starts on them.
//
// Why textures and glClearTexImage rather than renderbuffers and glClear. On llvmpipe a glClear
// is binned into every 64 x 64 tile and executed there as 64 short row fills per buffer: the
// colour and depth clears were a quarter of a frame's CPU. ARB_clear_texture (core in GL 4.4,
// offered by llvmpipe in any context) fills the texture straight away in whole rows, and only
// the rows and columns asked for: the colour everywhere (every pixel is either the room face
// the clear paints or drawn over), the depth only inside the box where a depth-tested
// fragment can fall. The bytes are the same: the colour is given as the bytes a clear or a
// fragment writes, and the depth as 1.0, which both paths store as 0xffffff; depth outside
// the box is never read. Where the extension is missing (a driver without it), the frame
// starts with glClear of both buffers whole, as before.

#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "render/lens_mesh.hpp"

namespace shelfcross::render {

/// A box of pixels in GL window coordinates (x right, y = GL row), [x0, x1) x [y0, y1).
struct PixelBox {
  int x0 = 0, y0 = 0, x1 = 0, y1 = 0;
  bool empty() const { return x1 <= x0 || y1 <= y0; }
};

/// The pixels that the triangles indices[first, end) of `vertices` (GL clip coordinates, w > 0:
/// faces are clipped at the near plane before) can cover in a width x height viewport at the
/// origin: the box of their window positions grown by one pixel each way (pixel centres
/// inside a triangle lie inside the box of its vertices; the margin covers the rasteriser's
/// sub-pixel snapping and rounding of x / w), clamped to the viewport. Empty for no triangles.
PixelBox covered_pixels(const std::vector<GpuVertex>& vertices,
                        const std::vector<std::uint32_t>& indices, std::size_t first,
                        std::size_t end, int width_px, int height_px);

class FrameTarget {
 public:
  FrameTarget() = default;
  FrameTarget(const FrameTarget&) = delete;
  FrameTarget& operator=(const FrameTarget&) = delete;

  /// Creates the framebuffer and its textures (the context current); throws RenderError if
  /// the size exceeds the driver's limits or the framebuffer is incomplete.
  void create(int width_px, int height_px);
  /// Deletes them (the context current); a no-op if none.
  void release();
  /// Binds the framebuffer for drawing and reading.
  void bind() const;
  /// Starts a frame (bound): colour := rgba8 at every pixel, depth := 1 (the far plane) at
  /// least inside depth_box (the rest of the depth buffer is left as it was).
  void start_frame(const std::array<std::uint8_t, 4>& rgba8, const PixelBox& depth_box) const;
  /// Whether start_frame fills the textures directly (ARB_clear_texture) or uses glClear.
  bool clears_textures() const { return clear_texture_; }

 private:
  unsigned fbo_ = 0, colour_ = 0, depth_ = 0;  // GL names
  int width_px_ = 0, height_px_ = 0;
  bool clear_texture_ = false;
};

}  // namespace shelfcross::render
