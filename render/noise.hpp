#pragma once
// Seeded, bit-reproducible sensor noise. No std::normal_distribution (not portable across
// standard libraries) and no libm: every draw is integer arithmetic on a counter-based hash,
// so the same seed gives the same image on any platform and any thread.

#include <cstdint>

#include <opencv2/core/mat.hpp>

namespace shelfcross::render {

/// SplitMix64 finaliser: a bijective 64-bit mix (Steele, Lea, Flood 2014).
constexpr std::uint64_t mix64(std::uint64_t z) {
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
  return z ^ (z >> 31);
}

/// The noise seed of one frame from a stream seed and the frame index.
constexpr std::uint64_t frame_seed(std::uint64_t stream_seed, std::int64_t frame_index) {
  return mix64(mix64(stream_seed + 0x9e3779b97f4a7c15ULL) ^
               (static_cast<std::uint64_t>(frame_index) * 0xd1b54a32d192ed03ULL));
}

/// Adds zero-mean noise of standard deviation `stddev` grey levels to every byte of an 8-bit
/// image (each channel independently), rounding to nearest and clamping to 0..255.
/// Draw for byte k: h = mix64(seed' + k * golden); the sum of its four 16-bit fields
/// (Irwin-Hall, n = 4) standardised: z = (sum - 2 * 65535) / sqrt(4 (65536^2 - 1) / 12),
/// mean 0, variance 1, tails cut at +-3.46 sigma (a sensor's noise is bounded anyway).
void add_sensor_noise(cv::Mat& image, double stddev, std::uint64_t seed);

}  // namespace shelfcross::render
