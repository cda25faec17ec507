#include "render/noise.hpp"

#include <algorithm>
#include <cassert>
#include <cmath>

#if defined(__x86_64__)
#include <immintrin.h>
#endif

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

namespace {

// One row of the fused pass, pixels [from, cols): bgr[3i + k] = sat(rgba[4i + 2 - k] + n[3i + k])
// for k = 0, 1, 2 (B, G, R), sat clamping to 0..255.
void rgba_to_bgr_noise_tail(const std::uint8_t* rgba, const std::int8_t* n, std::uint8_t* bgr,
                            int from, int cols) {
  for (int i = from; i < cols; ++i) {
    for (int k = 0; k < 3; ++k) {
      const int v = rgba[4 * i + 2 - k] + n[3 * i + k];
      bgr[3 * i + k] = static_cast<std::uint8_t>(v < 0 ? 0 : (v > 255 ? 255 : v));
    }
  }
}

#if defined(__x86_64__)
// The same, 16 pixels per step with SSSE3 (every x86-64 CPU since 2006; checked at run time):
// returns the number of pixels done (a multiple of 16), the rest is left to the scalar tail.
// Per 4 pixels, PSHUFB picks bytes 2 1 0, 6 5 4, 10 9 8, 14 13 12 of the RGBA quad (B G R of
// each pixel; the alpha bytes dropped) into the low 12 bytes; the four 12-byte pieces are
// joined into three 16-byte vectors by byte shifts. Saturating u8 + s8: with p' = p - 128 (the
// top bit flipped), the signed saturating sum p' + n, flipped back, is min(255, max(0, p + n)).
__attribute__((target("ssse3"))) int rgba_to_bgr_noise_ssse3(const std::uint8_t* rgba,
                                                             const std::int8_t* n,
                                                             std::uint8_t* bgr, int cols) {
  const __m128i pick = _mm_setr_epi8(2, 1, 0, 6, 5, 4, 10, 9, 8, 14, 13, 12, -1, -1, -1, -1);
  const __m128i bias = _mm_set1_epi8(static_cast<char>(0x80));
  auto load = [](const void* p) { return _mm_loadu_si128(static_cast<const __m128i*>(p)); };
  auto add_store = [&](std::uint8_t* out, __m128i p, const std::int8_t* noise) {
    const __m128i sum = _mm_adds_epi8(_mm_xor_si128(p, bias), load(noise));
    _mm_storeu_si128(reinterpret_cast<__m128i*>(out), _mm_xor_si128(sum, bias));
  };
  int i = 0;
  for (; i + 16 <= cols; i += 16) {
    const std::uint8_t* s = rgba + 4 * i;
    const __m128i q0 = _mm_shuffle_epi8(load(s), pick), q1 = _mm_shuffle_epi8(load(s + 16), pick),
                  q2 = _mm_shuffle_epi8(load(s + 32), pick), q3 = _mm_shuffle_epi8(load(s + 48), pick);
    // Bytes 0..47 of the BGR row piece: q0[0..11] q1[0..11] q2[0..11] q3[0..11].
    const __m128i b0 = _mm_or_si128(q0, _mm_slli_si128(q1, 12));
    const __m128i b1 = _mm_or_si128(_mm_srli_si128(q1, 4), _mm_slli_si128(q2, 8));
    const __m128i b2 = _mm_or_si128(_mm_srli_si128(q2, 8), _mm_slli_si128(q3, 4));
    add_store(bgr + 3 * i, b0, n + 3 * i);
    add_store(bgr + 3 * i + 16, b1, n + 3 * i + 16);
    add_store(bgr + 3 * i + 32, b2, n + 3 * i + 32);
  }
  return i;
}
#endif

void rgba_to_bgr_noise_row(const std::uint8_t* rgba, const std::int8_t* n, std::uint8_t* bgr,
                           int cols) {
  int done = 0;
#if defined(__x86_64__)
  static const bool ssse3 = __builtin_cpu_supports("ssse3");
  if (ssse3) done = rgba_to_bgr_noise_ssse3(rgba, n, bgr, cols);
#endif
  rgba_to_bgr_noise_tail(rgba, n, bgr, done, cols);
}

}  // namespace

void SensorNoise::apply_rgba_to_bgr(const cv::Mat& rgba, cv::Mat& bgr, std::uint64_t frame_seed) const {
  assert(rgba.rows == rows_);
  bgr.create(rows_, cols_, CV_8UC3);
  apply_rgba_rows_to_bgr(rgba, 0, bgr, frame_seed);
}

void SensorNoise::apply_rgba_rows_to_bgr(const cv::Mat& rgba_rows, int first_row, cv::Mat& bgr,
                                         std::uint64_t frame_seed) const {
  assert(channels_ == 3 && rgba_rows.type() == CV_8UC4 && rgba_rows.cols == cols_ &&
         first_row >= 0 && first_row + rgba_rows.rows <= rows_ && bgr.type() == CV_8UC3 &&
         bgr.rows == rows_ && bgr.cols == cols_);
  // The same window as apply().
  const std::uint64_t h = mix64(frame_seed ^ 0xbb67ae8584caa73bULL);
  const std::vector<std::int8_t>& field = fields_[h % kFields];
  const int dx = static_cast<int>((h >> 8) % kMargin), dy = static_cast<int>((h >> 24) % kMargin);
  for (int k = 0; k < rgba_rows.rows; ++k) {
    const int r = first_row + k;
    const std::int8_t* n = field.data() + (static_cast<size_t>(r + dy) * field_cols_ + dx) * 3;
    rgba_to_bgr_noise_row(rgba_rows.ptr<std::uint8_t>(k), n, bgr.ptr<std::uint8_t>(r), cols_);
  }
}

}  // namespace shelfcross::render
