#pragma once
// The link's faults, one model per channel for both links of the co-simulation: the simulated
// Tello draws them datagram by datagram (the sdk link, and tello-sim), the ideal link message
// by message from the same model with the same seed. Each channel's losses, duplicates and
// late replies come from a stream of its own, seeded from the run's seed (so one setting
// never shifts another's draws, and every fate draws the same count whatever it turns out),
// and each channel's delivery times: the delay plus a normal jitter truncated at +-3 sigma,
// never before the channel's previous datagram (one Wi-Fi hop does not reorder).

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

#include "shelfcross/random.hpp"
#include "shelfcross/time.hpp"

namespace shelfcross::verification {

/// Loss, delay and duplication of one channel's datagrams.
struct ChannelFaults {
  double loss = 0.0;       ///< probability that a datagram is dropped, 0..1
  double delay_ms = 0.0;   ///< added to every datagram of the channel, >= 0
  /// Standard deviation of a normal jitter added to delay_ms (truncated at +-3 sigma, the
  /// total never below 0). A channel keeps its order: a datagram never leaves before the one
  /// queued before it on the same channel (one Wi-Fi hop does not reorder).
  double jitter_ms = 0.0;
  double duplicate = 0.0;  ///< probability that a datagram arrives twice (commands, replies, state)
  bool operator==(const ChannelFaults&) const = default;
};

struct EmulatorFaults {
  ChannelFaults commands, replies, state, video;
  double video_frame_loss = 0.0;   ///< probability that a whole frame (all its datagrams) is lost
  double late_replies = 0.0;       ///< probability that a reply is held back late_reply_ms more
  double late_reply_ms = 7500.0;   ///< past a client's 7 s reply timeout
  double not_joystick = 0.0;       ///< probability of "error Not joystick" for a manoeuvre (1: forced)
  double no_valid_imu = 0.0;       ///< probability of "error No valid imu" for a manoeuvre (1: forced)
  /// Fault injection: every command datagram whose text begins with this is lost (e.g.
  /// "land"); empty: none. Applied after the random draws, so it shifts none of them.
  std::string lost_command_prefix;
  /// How many of those are lost, the first ones in the order they arrive; 0: every one.
  int lost_command_count = 0;
  std::optional<double> video_stall_start_s;  ///< no frames in [start, start + duration)
  double video_stall_duration_s = 0.0;
  bool operator==(const EmulatorFaults&) const = default;
};

class DatagramFaults {
 public:
  enum class Channel { command, reply, state, video };
  /// What happens to one datagram.
  struct Fate {
    bool lost = false;
    bool twice = false;  ///< arrives a second time, at the same instant
    bool late = false;   ///< replies: held back late_reply_ms more
  };
  struct Refusal {
    bool not_joystick = false;
    bool no_valid_imu = false;
  };

  /// Requires faults checked (validate_emulator_config, or mapped from checked scenario keys:
  /// probabilities in [0, 1], delays and jitters >= 0); not checked again here. Any seed.
  DatagramFaults(const EmulatorFaults& faults, std::uint64_t seed);

  /// A command datagram with this text: lost, twice (two draws, always); lost also when the
  /// text begins with lost_command_prefix, the first lost_command_count of them (applied
  /// after the draws, so it shifts none).
  Fate command(std::string_view text);
  /// A reply: lost, late, twice (three draws, always).
  Fate reply();
  /// A state record: lost, twice (two draws, always).
  Fate state();
  /// A whole frame: one draw per capture.
  bool frame_lost();
  /// One datagram of a frame that is sent: one draw each.
  bool video_datagram_lost();
  /// A refusable manoeuvre: "error Not joystick", "error No valid imu" (two draws, always).
  Refusal refusal();
  /// Whether a frame captured at t falls in the video stall [start, start + duration).
  bool video_stalled(TimeNs t) const;
  /// When a datagram queued at t on `channel` arrives: t + delay + jitter, and never before the
  /// channel's previous one.
  TimeNs due(Channel channel, TimeNs t);
  /// When a reply queued at t with this fate arrives: due(Channel::reply, t), and late_reply_ms
  /// more when late (the hold does not hold back the replies after it: the channel keeps the
  /// order of the on-time arrivals).
  TimeNs reply_due(const Fate& fate, TimeNs t);

 private:
  EmulatorFaults faults_;
  int prefixed_commands_seen_ = 0;
  RandomStream command_, reply_, state_, video_, error_, frame_;
  RandomStream command_jitter_, reply_jitter_, state_jitter_, video_jitter_;
  TimeNs last_due_[4] = {0, 0, 0, 0};  ///< per channel
};

}  // namespace shelfcross::verification
