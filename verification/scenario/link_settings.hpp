#pragma once
// The Wi-Fi link's settings, a scenario's `cosim.link` section: latencies, losses and faults of
// each channel, for the link the co-simulation flies (cosim/link_model.hpp draws the ideal
// link's deliveries from them; cosim/cosim_sdk_link.cpp hands them to the simulated Tello's
// datagram channels).
//
// Defaults follow docs/tello_sdk.md: users report 0.3 to 1 s of video lag, most of it
// receiver-side buffering; a receiver that always decodes the newest frame (as tello_pilot
// does) sees about the encoder + Wi-Fi + decoder delay, taken here as 0.2 s mean.

#include <string>

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

}  // namespace shelfcross::verification
