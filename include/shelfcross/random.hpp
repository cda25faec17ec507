#pragma once
// The project's one convention for randomness: every draw comes from a RandomStream, seeded
// explicitly from (run seed, stream id), so that
//   - a run's seed derives from (campaign seed, run index) by a fixed hash: any run can be
//     replayed alone, in any order, on any worker;
//   - each source of randomness (dispersions, sensor noise, latency jitter, frame drops, wind,
//     ...) has its own stream, so adding draws to one does not shift the others.
//
// Generators and draws are written out here rather than taken from <random>: the standard
// fixes mt19937's sequence but not the algorithms of its distributions, so results through
// std::normal_distribution may differ between standard libraries.

#include <cmath>
#include <cstdint>
#include <numbers>

namespace shelfcross {

/// SplitMix64's finaliser (Steele, Lea & Flood 2014): a bijection of 64-bit integers whose
/// outputs are statistically independent for consecutive inputs.
constexpr std::uint64_t mix64(std::uint64_t x) {
  x += 0x9E3779B97F4A7C15ull;
  x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ull;
  x = (x ^ (x >> 27)) * 0x94D049BB133111EBull;
  return x ^ (x >> 31);
}

/// Seed of run `run_index` of a campaign seeded with `campaign_seed`.
constexpr std::uint64_t run_seed(std::uint64_t campaign_seed, std::uint64_t run_index) {
  return mix64(mix64(campaign_seed) ^ mix64(run_index + 0x5EED5EED5EED5EEDull));
}

/// The independent sources of randomness of one run. Values are part of the replay contract:
/// never renumber, only append.
enum class StreamId : std::uint64_t {
  dispersion = 1,      ///< drawn scenario parameters
  box_placement = 2,   ///< random fill of shelves
  wind = 3,            ///< gusts
  sensor_noise = 4,    ///< state-record noise
  render_noise = 5,    ///< camera sensor noise
  video_latency = 6,   ///< per-frame latency jitter
  frame_drop = 7,      ///< dropped frames
  command_latency = 8, ///< per-command latency jitter
  command_loss = 9,    ///< lost commands
  compute_latency = 10,///< the flight software's compute time
  link_faults = 11,    ///< emulator fault injection
  state_latency = 12,  ///< state records and replies
  vps = 13,            ///< the vision positioning system's velocity errors
  height_sensors = 14, ///< barometer, range sensor and height noise and drift
  link_bursts = 15,    ///< the link's loss bursts and outages (their spells' lengths)
};

/// xoshiro256** (Blackman & Vigna 2018), state filled from SplitMix64 of the stream's seed.
class RandomStream {
 public:
  RandomStream(std::uint64_t seed, StreamId stream) {
    std::uint64_t x = mix64(seed ^ mix64(static_cast<std::uint64_t>(stream)));
    for (auto& word : s_) {
      x += 0x9E3779B97F4A7C15ull;
      word = mix64(x);
    }
  }

  std::uint64_t next_u64() {
    const std::uint64_t result = rotl(s_[1] * 5, 7) * 9;
    const std::uint64_t t = s_[1] << 17;
    s_[2] ^= s_[0];
    s_[3] ^= s_[1];
    s_[1] ^= s_[2];
    s_[0] ^= s_[3];
    s_[2] ^= t;
    s_[3] = rotl(s_[3], 45);
    return result;
  }

  /// Uniform in [0, 1) with 53 random bits. uniform01, uniform and bernoulli take exactly one
  /// 64-bit output of the stream and normal two, whatever their arguments (so a draw's place in
  /// its stream never depends on a value); below takes one or more (rejection).
  double uniform01() { return static_cast<double>(next_u64() >> 11) * 0x1.0p-53; }

  double uniform(double lo, double hi) { return lo + (hi - lo) * uniform01(); }

  /// Standard normal by Box-Muller: z = sqrt(-2 ln u1) cos(2 pi u2), u1 in (0, 1].
  /// One value per call (the sine partner is discarded) so a stream has no hidden cache.
  double normal() {
    const double u1 = 1.0 - uniform01();
    const double u2 = uniform01();
    return std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * std::numbers::pi * u2);
  }
  double normal(double mean, double stddev) { return mean + stddev * normal(); }

  /// True with probability p: never for p <= 0, always for p >= 1.
  bool bernoulli(double p) { return uniform01() < p; }

  /// Uniform integer in [0, n), unbiased (rejection of the short last bucket). Requires n > 0
  /// (n = 0 divides by zero).
  std::uint64_t below(std::uint64_t n) {
    const std::uint64_t limit = ~std::uint64_t{0} - (~std::uint64_t{0} % n);
    std::uint64_t x;
    do {
      x = next_u64();
    } while (x >= limit);
    return x % n;
  }

 private:
  static constexpr std::uint64_t rotl(std::uint64_t x, int k) { return (x << k) | (x >> (64 - k)); }
  std::uint64_t s_[4];
};

}  // namespace shelfcross
