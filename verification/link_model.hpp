#pragma once
// The Wi-Fi link between the Tello and the computer running the flight software, as the
// co-simulation models it: every message gets a latency (mean plus seeded jitter), video
// frames and commands can be lost, and the flight software's own compute time delays what it
// sends. Each effect draws from its own stream (shelfcross/random.hpp), so changing one
// setting does not shift the draws of another.
//
// Defaults follow docs/tello_sdk.md: users report 0.3 to 1 s of video lag, most of it
// receiver-side buffering; a receiver that always decodes the newest frame (as tello_pilot
// does) sees about the encoder + Wi-Fi + decoder delay, taken here as 0.2 s mean.

#include <cstdint>
#include <optional>
#include <string>

#include "shelfcross/random.hpp"
#include "shelfcross/time.hpp"

namespace shelfcross::verification {

/// The link between the Tello and the flight computer, for both models (scenarios/README.md
/// argues every default):
///   sdk    the Tello's own datagrams: the simulated Tello's firmware answers command
///          datagrams, sends its state record text and its H.264 stream cut into 1460-byte
///          datagrams; the pilot loop of tello_pilot (driver, video receiver, flight software,
///          failsafes) receives them. Latencies and losses below apply per datagram.
///   ideal  whole messages: a frame, a state record, a command delivered or lost whole, no
///          driver and no decoder (fast studies of the flight software alone).
/// The latency keys mean the same in both: the video channel's delay from capture to the
/// receiver, the state and reply channels', the command channel's; command loss is per
/// command datagram. frame_drop_probability drops whole frames (sdk: all their datagrams).
struct LinkSettings {
  std::string model = "sdk";               ///< sdk or ideal
  double video_latency_mean_s = 0.20;
  double video_latency_jitter_s = 0.02;    ///< stddev, truncated at +-3 sigma
  double frame_drop_probability = 0.02;
  double state_latency_mean_s = 0.02;      ///< state records and replies
  double state_latency_jitter_s = 0.005;
  double command_latency_mean_s = 0.02;
  double command_latency_jitter_s = 0.005;
  double command_loss_probability = 0.005; ///< UDP: a lost command is simply never applied
  double compute_latency_s = 0.002;        ///< flight software step time, fixed unless drawn
  // sdk model only.
  double video_datagram_loss = 0.005;      ///< per 1460-byte video datagram
  double state_loss = 0.005;               ///< per state record datagram
  double reply_loss = 0.005;               ///< per reply datagram
  double duplicate_probability = 0.001;    ///< a command, reply or state datagram arrives twice
  double late_reply_probability = 0.0;     ///< a reply held back late_reply_s more
  double late_reply_s = 7.5;               ///< past the driver's 7 s reply timeout
  double not_joystick_probability = 0.0;   ///< a manoeuvre (not land) refused "error Not joystick"
  double no_valid_imu_probability = 0.0;   ///< ... refused "error No valid imu"
  double video_stall_start_s = -1.0;       ///< no frames in [start, start + duration); < 0: none
  double video_stall_duration_s = 0.0;
  int video_slices = 45;                   ///< slices per picture (one per macroblock row)
  int key_interval_frames = 0;             ///< 0: a key frame per second of captures
  /// Fault injection: every command datagram beginning with this text is lost ("land": a
  /// lost land, as in the lossy flights); empty: none.
  std::string lost_command = "";
  bool operator==(const LinkSettings&) const = default;
};

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
