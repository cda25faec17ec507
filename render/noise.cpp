#include "render/noise.hpp"

#include <cassert>
#include <cmath>

namespace shelfcross::render {

void add_sensor_noise(cv::Mat& image, double stddev, std::uint64_t seed) {
  assert(image.depth() == CV_8U);
  if (!(stddev > 0.0)) return;
  // sqrt(4 (2^32 - 1) / 12), correctly rounded by IEEE sqrt.
  const double scale = stddev / std::sqrt(4.0 * (4294967296.0 - 1.0) / 12.0);
  const std::uint64_t key = mix64(seed ^ 0x6a09e667f3bcc909ULL);
  const int row_bytes = image.cols * image.channels();
  std::uint64_t k = 0;
  for (int r = 0; r < image.rows; ++r) {
    std::uint8_t* p = image.ptr<std::uint8_t>(r);
    for (int c = 0; c < row_bytes; ++c, ++k) {
      const std::uint64_t h = mix64(key + k * 0x9e3779b97f4a7c15ULL);
      const std::int64_t sum = static_cast<std::int64_t>((h & 0xffff) + ((h >> 16) & 0xffff) +
                                                         ((h >> 32) & 0xffff) + (h >> 48));
      const double value = p[c] + scale * static_cast<double>(sum - 131070);
      const double rounded = std::floor(value + 0.5);
      p[c] = static_cast<std::uint8_t>(rounded < 0.0 ? 0.0 : (rounded > 255.0 ? 255.0 : rounded));
    }
  }
}

}  // namespace shelfcross::render
