#pragma once
// The Wi-Fi link's settings, a scenario's `cosim.link` section: latencies, losses and faults of
// each channel, for the link the co-simulation flies. Both links draw them from one fault model
// (cosim/link_faults.hpp maps the keys to the DatagramFaults of world/datagram_faults.hpp,
// seeded with the run's seed): the sdk link's simulated Tello datagram by datagram, the ideal
// link message by message.
//
// Defaults follow docs/tello_sdk.md: users report 0.3 to 1 s of video lag, most of it
// receiver-side buffering; a receiver that always decodes the newest frame (as tello_pilot
// does) sees about the encoder + Wi-Fi + decoder delay, taken here as 0.2 s mean.

#include <string>

namespace shelfcross::verification {

/// The link's faults that last (the keys stay flat in `cosim.link`): the video stall, losses
/// in bursts, outages.
struct LinkSpells {
  double video_stall_start_s = -1.0;       ///< no frames in [start, start + duration); < 0: none
  double video_stall_duration_s = 0.0;
  /// Losses in bursts (verification/world/fault_windows.hpp): each channel's two-state chain,
  /// a bad spell of Exp(burst_mean_s) after a good one of Exp(burst_interval_s), a datagram
  /// (ideal: a command, reply or state record; not a frame) lost with burst_loss in the bad
  /// state and with the channel's own loss in the good one. burst_mean_s 0: no bursts.
  double burst_loss = 0.5;
  double burst_mean_s = 0.0;
  double burst_interval_s = 10.0;
  /// Outages: nothing passes on any channel, either way (ideal: a frame lost whole). At random,
  /// a quiet spell of Exp(outage_interval_s) then an outage of uniform [outage_min_s,
  /// outage_max_s] in turn (outage_interval_s 0: none at random); and one at outage_start_s
  /// (< 0: none) lasting outage_duration_s.
  double outage_interval_s = 0.0;
  double outage_min_s = 1.0;
  double outage_max_s = 5.0;
  double outage_start_s = -1.0;
  double outage_duration_s = 0.0;
  bool operator==(const LinkSpells&) const = default;
};

/// The link between the Tello and the flight computer, for both models (scenarios/README.md
/// argues every default):
///   sdk    the Tello's own datagrams: the simulated Tello's firmware answers command
///          datagrams, sends its state record text and its H.264 stream cut into 1460-byte
///          datagrams; the pilot loop of tello_pilot (driver, video receiver, flight software,
///          failsafes) receives them. Latencies and losses below apply per datagram.
///   ideal  whole messages: a frame, a state record, a reply, a command delivered or lost
///          whole, no driver and no decoder (fast studies of the flight software alone). Each
///          message is drawn as its datagram is on the sdk link (a frame as a whole frame).
/// Every key does the same on both links unless its comment says otherwise: the channels'
/// delays (with a normal jitter truncated at +-3 sigma, each channel kept in order), losses
/// and duplicates (a duplicate is delivered twice at the same instant), late replies, the
/// lost-command injection, the video stall.
struct LinkSettings {
  std::string model = "sdk";               ///< sdk or ideal
  double video_latency_mean_s = 0.20;      ///< capture to the receiver having the frame
  double video_latency_jitter_s = 0.02;    ///< stddev, truncated at +-3 sigma
  double frame_drop_probability = 0.02;    ///< whole frames lost (sdk: all their datagrams)
  double state_latency_mean_s = 0.02;      ///< state records and replies
  double state_latency_jitter_s = 0.005;
  double command_latency_mean_s = 0.02;
  double command_latency_jitter_s = 0.005;
  double command_loss_probability = 0.005; ///< UDP: a lost command is simply never applied
  /// Flight software step time, fixed unless drawn: added to every command before the command
  /// channel's delay (not a fault of the link).
  double compute_latency_s = 0.002;
  /// Per 1460-byte video datagram (sdk only: the picture reaches the flight software
  /// error-concealed and marked damaged; the ideal link has no datagrams and no decoder, its
  /// pictures are always whole, and it ignores this key rather than turn a damaged picture
  /// into a lost one).
  double video_datagram_loss = 0.005;
  double state_loss = 0.005;               ///< per state record
  double reply_loss = 0.005;               ///< per reply
  double duplicate_probability = 0.001;    ///< a command, reply or state record arrives twice
  double late_reply_probability = 0.0;     ///< a reply held back late_reply_s more
  double late_reply_s = 7.5;               ///< past the driver's 7 s reply timeout
  /// A manoeuvre (not land) refused "error Not joystick" (sdk only: the simulated Tello's
  /// command interpreter answers it; on the ideal link the plant's firmware answers every
  /// command, and this key is ignored).
  double not_joystick_probability = 0.0;
  double no_valid_imu_probability = 0.0;   ///< ... refused "error No valid imu" (sdk only, as above)
  LinkSpells spells;                       ///< the video stall, losses in bursts, outages
  int video_slices = 45;                   ///< slices per picture (one per macroblock row; sdk only)
  int key_interval_frames = 0;             ///< 0: a key frame per second of captures (sdk only)
  /// Fault injection: every command beginning with this text is lost ("land": a lost land, as
  /// in the lossy flights); empty: none.
  std::string lost_command = "";
  int lost_command_count = 0;  ///< how many of those are lost, the first ones; 0: every one
  bool operator==(const LinkSettings&) const = default;
};

}  // namespace shelfcross::verification
