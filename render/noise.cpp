#include "render/noise.hpp"

#include <algorithm>
#include <cassert>
#include <cmath>

#include <opencv2/core/hal/intrin.hpp>
#include <opencv2/imgproc.hpp>

#include "shelfcross/random.hpp"

namespace shelfcross::render {

SensorNoise::SensorNoise(int rows, int cols, int channels, double stddev, std::uint64_t table_seed)
    : rows_(rows), cols_(cols), channels_(channels), field_cols_(cols + kMargin) {
  // sqrt(4 (2^32 - 1) / 12): the standard deviation of the sum of four uniform 16-bit fields.
  const double scale = stddev / std::sqrt(4.0 * (4294967296.0 - 1.0) / 12.0);
  const size_t bytes = static_cast<size_t>(rows + kMargin) * static_cast<size_t>(field_cols_) * static_cast<size_t>(channels);
  for (int f = 0; f < kFields; ++f) {
    const std::uint64_t key = mix64(table_seed ^ mix64(0x6a09e667f3bcc909ULL + static_cast<std::uint64_t>(f)));
    std::vector<std::int8_t> field(bytes);
    for (size_t k = 0; k < bytes; ++k) {
      const std::uint64_t h = mix64(key + k * 0x9e3779b97f4a7c15ULL);
      const std::int64_t sum =
          static_cast<std::int64_t>((h & 0xffff) + ((h >> 16) & 0xffff) + ((h >> 32) & 0xffff) + (h >> 48));
      const double v = std::nearbyint(scale * static_cast<double>(sum - 131070));
      field[k] = static_cast<std::int8_t>(std::clamp(v, -127.0, 127.0));
    }
    fields_.push_back(std::move(field));
  }
}

void SensorNoise::apply(cv::Mat& image, std::uint64_t frame_seed) const {
  assert(image.depth() == CV_8U && image.rows == rows_ && image.cols == cols_ && image.channels() == channels_);
  const std::uint64_t h = mix64(frame_seed ^ 0xbb67ae8584caa73bULL);
  const std::vector<std::int8_t>& field = fields_[h % kFields];
  const int dx = static_cast<int>((h >> 8) % kMargin), dy = static_cast<int>((h >> 24) % kMargin);
  const int row_bytes = cols_ * channels_;
  for (int r = 0; r < rows_; ++r) {
    std::uint8_t* p = image.ptr<std::uint8_t>(r);
    const std::int8_t* n = field.data() + (static_cast<size_t>(r + dy) * field_cols_ + dx) * channels_;
    for (int c = 0; c < row_bytes; ++c) {
      const int v = p[c] + n[c];
      p[c] = static_cast<std::uint8_t>(v < 0 ? 0 : (v > 255 ? 255 : v));
    }
  }
}

void SensorNoise::apply_rgba_to_bgr(const cv::Mat& rgba, cv::Mat& bgr, std::uint64_t frame_seed) const {
  assert(channels_ == 3 && rgba.type() == CV_8UC4 && rgba.rows == rows_ && rgba.cols == cols_);
  bgr.create(rows_, cols_, CV_8UC3);
  // The same window as apply().
  const std::uint64_t h = mix64(frame_seed ^ 0xbb67ae8584caa73bULL);
  const std::vector<std::int8_t>& field = fields_[h % kFields];
  const int dx = static_cast<int>((h >> 8) % kMargin), dy = static_cast<int>((h >> 24) % kMargin);
  const int row_bytes = cols_ * 3;
  // Blocks of rows small enough to stay in the L2 cache between the conversion (OpenCV's own
  // SIMD) and the noise pass over the same bytes.
  constexpr int kBlockRows = 16;
  for (int r0 = 0; r0 < rows_; r0 += kBlockRows) {
    const int r1 = std::min(rows_, r0 + kBlockRows);
    cv::Mat out = bgr.rowRange(r0, r1);
    cv::cvtColor(rgba.rowRange(r0, r1), out, cv::COLOR_RGBA2BGR);
    for (int r = r0; r < r1; ++r) {
      std::uint8_t* p = bgr.ptr<std::uint8_t>(r);
      const std::int8_t* n = field.data() + (static_cast<size_t>(r + dy) * field_cols_ + dx) * 3;
      int c = 0;
#if CV_SIMD128
      // Saturating u8 + s8: with p' = p - 128 (flip the top bit), the signed saturating sum
      // p' + n flipped back is min(255, max(0, p + n)).
      const cv::v_uint8x16 bias = cv::v_setall_u8(0x80);
      for (; c + 16 <= row_bytes; c += 16) {
        const cv::v_int8x16 sum = cv::v_reinterpret_as_s8(cv::v_load(p + c) ^ bias) + cv::v_load(n + c);
        cv::v_store(p + c, cv::v_reinterpret_as_u8(sum) ^ bias);
      }
#endif
      for (; c < row_bytes; ++c) {
        const int v = p[c] + n[c];
        p[c] = static_cast<std::uint8_t>(v < 0 ? 0 : (v > 255 ? 255 : v));
      }
    }
  }
}

}  // namespace shelfcross::render
