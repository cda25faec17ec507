#pragma once
// The link's faults, one model per channel for both links of the co-simulation: the simulated
// Tello draws them datagram by datagram (the sdk link, and tello-sim), the ideal link message
// by message from the same model with the same seed. Each channel's losses, duplicates and
// late replies come from a stream of its own, seeded from the run's seed (so one setting
// never shifts another's draws, and every fate draws the same count whatever it turns out),
// and each channel's delivery times: the delay plus a normal jitter truncated at +-3 sigma,
// never before the channel's previous datagram (one Wi-Fi hop does not reorder). Losses in
// bursts and outages (fault_windows.hpp) come from streams of their own too (StreamId::
// link_bursts): a datagram's loss is still one draw of its channel's stream, compared with the
// bad state's loss probability instead of the channel's own while a burst lasts, and lost
// whatever it drew while an outage lasts; with neither on, every draw is what it was.

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

#include "shelfcross/random.hpp"
#include "shelfcross/time.hpp"
#include "verification/world/fault_windows.hpp"

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
  BurstLoss bursts;      ///< losses in bursts, each channel its own chain; off by default
  LinkOutages outages;   ///< every channel down at once; none by default
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

  /// A command datagram with this text on air at t: lost, twice (two draws, always); lost also
  /// when the text begins with lost_command_prefix, the first lost_command_count of them
  /// (applied after the draws, so it shifts none). Every fate below is lost in an outage and
  /// drawn against the bad state's loss in a burst of its channel, at its t.
  Fate command(std::string_view text, TimeNs t);
  /// A reply on air at t: lost, late, twice (three draws, always).
  Fate reply(TimeNs t);
  /// A state record on air at t: lost, twice (two draws, always).
  Fate state(TimeNs t);
  /// A whole frame: one draw per capture (the outages are the caller's: outage()).
  bool frame_lost();
  /// One datagram of a frame that is sent, on air at t: one draw each.
  bool video_datagram_lost(TimeNs t);
  /// Whether the link is down at t (a random outage or the fixed one): nothing passes.
  bool outage(TimeNs t);
  /// Whether `channel` is in a burst (its chain's bad state) at t.
  bool burst(Channel channel, TimeNs t);
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
  /// One draw of `stream` against the channel's loss now: `loss` in the good state, the
  /// bursts' bad_loss in a burst; lost in an outage whatever it drew.
  bool lost(RandomStream& stream, double loss, Channel channel, TimeNs t);

  EmulatorFaults faults_;
  int prefixed_commands_seen_ = 0;
  RandomStream command_, reply_, state_, video_, error_, frame_;
  RandomStream command_jitter_, reply_jitter_, state_jitter_, video_jitter_;
  TimeNs last_due_[4] = {0, 0, 0, 0};  ///< per channel
  FaultWindows bursts_[4];             ///< per channel: its chain's bad spells
  FaultWindows outages_;               ///< the random outages
};

}  // namespace shelfcross::verification
