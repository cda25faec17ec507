#pragma once
// The Wi-Fi link between the Tello and the computer running the flight software, as the
// co-simulation models it: every message gets a latency (mean plus seeded jitter), video
// frames and commands can be lost, and the flight software's own compute time delays what it
// sends. Each effect draws from its own stream (shelfcross/random.hpp), so changing one
// setting does not shift the draws of another.
//
// The settings and their defaults: scenario/link_settings.hpp.

#include <cstdint>
#include <optional>
#include <string>

#include "shelfcross/random.hpp"
#include "shelfcross/time.hpp"
#include "verification/scenario/link_settings.hpp"

namespace shelfcross::verification {

/// Draws per-message delivery for one run. Deliveries on one channel keep their order (a UDP
/// stream on one Wi-Fi hop does not reorder in practice): a message never arrives before the
/// one sent before it on the same channel.
class LinkModel {
 public:
  /// Requires settings checked by the scenario reader (latencies and jitters >= 0,
  /// probabilities in [0, 1]); not checked again here. Any seed; does not throw.
  LinkModel(const LinkSettings& settings, std::uint64_t run_seed);

  /// When a frame captured at t_capture_ns reaches the flight software, or nothing if dropped.
  /// On one channel an arrival never precedes the previous call's: order is kept in call order.
  std::optional<TimeNs> video_arrival(TimeNs t_capture_ns);
  /// When a state record or a reply sent at t_send_ns reaches the flight software.
  TimeNs state_arrival(TimeNs t_send_ns);
  /// When a command issued at t_issue_ns (the stamp of the input that caused it) reaches the
  /// vehicle, or nothing if lost. The compute time is added before the link latency.
  std::optional<TimeNs> command_arrival(TimeNs t_issue_ns);

  const LinkSettings& settings() const { return settings_; }

 private:
  static TimeNs jittered(RandomStream& stream, double mean_s, double jitter_s);
  LinkSettings settings_;
  RandomStream video_latency_, frame_drop_, state_latency_, command_latency_, command_loss_;
  TimeNs last_video_ns_ = 0, last_state_ns_ = 0, last_command_ns_ = 0;
};

}  // namespace shelfcross::verification
