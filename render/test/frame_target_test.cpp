// The box in which a frame's depth is reset (frame_target.hpp): it must hold every pixel whose
// centre a depth-tested triangle can cover, since depth outside it is left from the last frame.
#include <gtest/gtest.h>

#include <cstdint>
#include <vector>

#include "render/frame_target.hpp"
#include "render/lens_mesh.hpp"

namespace shelfcross::render {
namespace {

// A vertex at window position (x_px, y_px) of a width x height viewport, with clip w = w.
GpuVertex at_window(double x_px, double y_px, int width, int height, float w) {
  GpuVertex v{};
  v.clip[0] = static_cast<float>((2.0 * x_px / width - 1.0) * w);
  v.clip[1] = static_cast<float>((2.0 * y_px / height - 1.0) * w);
  v.clip[2] = 0.5f * w;
  v.clip[3] = w;
  return v;
}

TEST(CoveredPixels, BoxOfTheRangesVerticesGrownByOnePixel) {
  const int width = 960, height = 720;
  std::vector<GpuVertex> vertices = {
      at_window(0.0, 0.0, width, height, 1.f),        // 0..2: a triangle outside the range
      at_window(959.0, 0.0, width, height, 1.f),
      at_window(0.0, 719.0, width, height, 1.f),
      at_window(100.25, 200.5, width, height, 3.f),   // 3..5: the range's first triangle
      at_window(300.75, 210.0, width, height, 0.2f),
      at_window(150.0, 400.5, width, height, 7.f),
      at_window(120.0, 190.4, width, height, 1.5f),   // 6: with 4 and 5, the second
  };
  const std::vector<std::uint32_t> indices = {0, 1, 2, 3, 4, 5, 6, 4, 5};
  const PixelBox box = covered_pixels(vertices, indices, 3, indices.size(), width, height);
  // x from floor(100.25) - 1 to ceil(300.75) + 1, y from floor(190.4) - 1 to ceil(400.5) + 1.
  EXPECT_EQ(box.x0, 99);
  EXPECT_EQ(box.x1, 302);
  EXPECT_EQ(box.y0, 189);
  EXPECT_EQ(box.y1, 402);
  EXPECT_FALSE(box.empty());
}

TEST(CoveredPixels, ClampedToTheViewportAndEmptyWithoutTriangles) {
  const int width = 64, height = 48;
  const std::vector<GpuVertex> vertices = {at_window(-500.0, -20.0, width, height, 2.f),
                                           at_window(900.0, 10.0, width, height, 2.f),
                                           at_window(10.0, 700.0, width, height, 2.f)};
  const std::vector<std::uint32_t> indices = {0, 1, 2};
  const PixelBox box = covered_pixels(vertices, indices, 0, 3, width, height);
  EXPECT_EQ(box.x0, 0);
  EXPECT_EQ(box.y0, 0);
  EXPECT_EQ(box.x1, width);
  EXPECT_EQ(box.y1, height);
  EXPECT_TRUE(covered_pixels(vertices, indices, 3, 3, width, height).empty());
  // A triangle wholly left of the viewport covers nothing there.
  const std::vector<GpuVertex> left = {at_window(-90.0, 5.0, width, height, 1.f),
                                       at_window(-10.0, 5.0, width, height, 1.f),
                                       at_window(-50.0, 30.0, width, height, 1.f)};
  EXPECT_TRUE(covered_pixels(left, indices, 0, 3, width, height).empty());
}

}  // namespace
}  // namespace shelfcross::render
