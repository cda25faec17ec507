#pragma once
// Seeded, bit-reproducible camera sensor noise, cheap enough for every frame of a campaign.
//
// A SensorNoise draws, once, kFields independent fields of zero-mean noise slightly larger than
// the image: byte k of field f is round(stddev * z) with z from h = mix64(key_f + k * golden),
// the standardised sum of h's four 16-bit fields (Irwin-Hall, n = 4: mean 0, variance 1, tails
// cut at +-3.46 sigma; a sensor's noise is bounded anyway). Each frame's seed picks a field and
// a shift of up to kMargin pixels in each direction, and the image gets that window added with
// saturation to 0..255. Frames thus carry independent-looking noise at the cost of one
// saturating add per byte (the per-byte hash of the fields is paid once per renderer). Integer
// arithmetic only: the same seed gives the same image on any platform and any thread.

#include <cstdint>
#include <vector>

#include <opencv2/core/mat.hpp>

namespace shelfcross::render {

class SensorNoise {
 public:
  static constexpr int kFields = 4;
  static constexpr int kMargin = 64;  ///< pixels of shift range per axis

  /// Fields for images of `rows` x `cols` x `channels` bytes, noise of `stddev` grey levels.
  SensorNoise(int rows, int cols, int channels, double stddev, std::uint64_t table_seed = 0);

  /// Adds one frame's noise to an 8-bit image, which must be of the size and channels given at
  /// construction (asserted).
  void apply(cv::Mat& image, std::uint64_t frame_seed) const;

  /// The renderer's last pass: `bgr` = RGBA -> BGR of `rgba` with this frame's noise added,
  /// byte-identical to cv::cvtColor(rgba, bgr, COLOR_RGBA2BGR) followed by apply(bgr,
  /// frame_seed), in one pass over memory (SIMD). Preconditions (asserted): channels = 3 at
  /// construction, `rgba` CV_8UC4 of the constructed size; `bgr` is (re)allocated CV_8UC3.
  void apply_rgba_to_bgr(const cv::Mat& rgba, cv::Mat& bgr, std::uint64_t frame_seed) const;
  /// The same for a band of the frame: `rgba_rows` (CV_8UC4, the constructed width) holds the
  /// frame's rows first_row .. first_row + rgba_rows.rows - 1, which are written to the same
  /// rows of `bgr` (CV_8UC3 of the constructed size, allocated by the caller) with the same
  /// bytes apply_rgba_to_bgr gives them; the other rows of `bgr` are untouched. The sizes and
  /// types named must hold (asserted).
  void apply_rgba_rows_to_bgr(const cv::Mat& rgba_rows, int first_row, cv::Mat& bgr,
                              std::uint64_t frame_seed) const;

 private:
  int rows_, cols_, channels_, field_cols_;
  std::vector<std::vector<std::int8_t>> fields_;  // (rows + kMargin) x (cols + kMargin) x channels
};

}  // namespace shelfcross::render
