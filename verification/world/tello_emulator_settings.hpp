#pragma once
// What the Tello emulator (tello_emulator.hpp) is set up with and what it tells: its settings
// (ports, seed, faults, the video stream's shape) and their check, the counters of what it
// received, sent and dropped, its report (stdout and --report), the caller's datagram channels
// that replace its UDP sockets, and the ports it serves on.

#include <cstdint>
#include <memory>
#include <set>
#include <string>

#include <Eigen/Core>

#include "flight_sw/tello/udp_socket.hpp"
#include "verification/scenario/dispersion.hpp"
#include "verification/world/datagram_faults.hpp"
#include "verification/world/metrics.hpp"
#include "verification/world/world_truth.hpp"

namespace shelfcross::verification {

struct EmulatorConfig {
  std::string bind_ip = "127.0.0.1";
  std::uint16_t command_port = 8889;        ///< 0: ephemeral (tests; see command_port())
  std::uint16_t client_state_port = 8890;   ///< state goes to this port of the `command` sender
  std::uint16_t client_video_port = 11111;  ///< video goes to this port of the `command` sender
  std::uint16_t state_source_port = 0;      ///< the emulator's state socket; 0: ephemeral
  std::uint16_t video_source_port = 0;      ///< the emulator's video socket; 0: ephemeral
  std::uint64_t seed = 1;                   ///< wind, render noise and fault draws (and dispersions)
  /// Draw the scenario's dispersions for `seed` first (verification::disperse, exactly as
  /// `shelfcross run --seed` does) and fly that world. Of the draws, the world's (start,
  /// light, boxes, autopilot, mass, wind) apply; the co-simulation's modelled link and
  /// computer (video_latency_mean_s, frame_drop_probability, command_latency_mean_s,
  /// command_loss_probability, compute_latency_s) do not (here they are real: use the faults
  /// below), nor does the believed camera's error (the client's calibration; setup() has it).
  bool disperse = false;
  EmulatorFaults faults;
  /// Captures between key frames; 0: one key frame per second (the Tello's stream). Counted
  /// in captures, not in frames encoded, so frames dropped under load do not stretch a group.
  int key_interval_frames = 0;
  /// Slices per picture: bands of whole macroblock rows, 1..45 at 720 rows (more than the
  /// picture has rows: one per row). A lost datagram damages the rest of its slice (and the
  /// start of the next), concealed from the previous picture until the next key frame: one
  /// slice per row (the default, row-band slicing as low-latency hardware encoders do) costs
  /// a band per lost datagram, one slice per picture the rest of the picture.
  int slices_per_frame = 45;
  double linger_s = 8.0;                    ///< after landing: end when no datagram came this long
  std::size_t max_datagram_bytes = 256;     ///< longer command datagrams are malformed
};

/// Throws std::invalid_argument naming the first setting out of range.
void validate_emulator_config(const EmulatorConfig& config);

struct EmulatorCounters {
  // commands in
  std::int64_t commands_received = 0;   ///< datagrams read from the command socket
  std::int64_t commands_dropped = 0;    ///< lost by fault injection
  std::int64_t commands_duplicated = 0; ///< delivered twice by fault injection
  std::int64_t commands_malformed = 0;  ///< empty, too long or not printable ASCII: dropped
  std::int64_t commands_delivered = 0;  ///< handed to the firmware
  std::int64_t injected_errors = 0;     ///< "error Not joystick" / "error No valid imu" answers
  // replies out
  std::int64_t replies_sent = 0;
  std::int64_t replies_dropped = 0;
  std::int64_t replies_late = 0;
  std::int64_t replies_duplicated = 0;
  // state out
  std::int64_t state_sent = 0;
  std::int64_t state_dropped = 0;
  std::int64_t state_duplicated = 0;
  // video out
  std::int64_t frames_captured = 0;       ///< capture instants while streaming
  std::int64_t frames_sent = 0;           ///< rendered, encoded and cut into datagrams
  std::int64_t frames_dropped_busy = 0;   ///< the worker was still busy with the previous frame
  std::int64_t frames_dropped_late = 0;   ///< the main loop reached the capture too late
  std::int64_t frames_stalled = 0;        ///< inside the injected video stall
  std::int64_t frames_lost = 0;           ///< whole frames lost by fault injection (not rendered)
  std::int64_t key_frames = 0;
  std::int64_t video_datagrams_sent = 0;
  std::int64_t video_datagrams_dropped = 0;
  std::int64_t video_bytes_sent = 0;
  std::int64_t send_errors = 0;           ///< datagrams the OS refused
};

/// What happened, for stdout and --report.
struct EmulatorReport {
  std::string end_reason;          ///< landed, collision, left_arena, numerical_failure, signal, max_seconds, running
  std::string detail;
  double elapsed_s = 0.0;          ///< emulated (= wall) time since the start
  double flight_time_s = 0.0;      ///< motors on
  bool flew = false;               ///< the firmware left `landed` at least once (TelloWorld::flew)
  bool landed = true;
  /// The world's truth (TelloWorld::truth); printed but for floor_touches.
  WorldTruth truth;
  std::set<InventoryEntry> inventory_truth;       ///< (marker id, shelf, level, column) of shelf 0
  Eigen::Vector3d start_p_W_m = Eigen::Vector3d::Zero();  ///< the scenario's (dispersed) start
  double start_yaw_rad = 0.0;
  std::uint64_t seed = 0;
  bool dispersed = false;
  DrawnValues drawn;               ///< the seed's dispersion draws (dispersed only)
  EmulatorCounters counters;
};

/// Whether the emulator's world takes a dispersed parameter (see EmulatorConfig::disperse).
bool emulator_applies_dispersion(const std::string& name);

std::string emulator_report_json(const EmulatorReport& report);
std::string emulator_report_text(const EmulatorReport& report);

/// Datagram channels of the caller's (the co-simulation's in-memory ones) instead of UDP
/// sockets; all three or none.
struct EmulatorChannels {
  std::unique_ptr<tello::DatagramChannel> command, state, video;
};

/// The ports the emulator serves on (the ephemeral ones as bound) and the command socket's
/// descriptor (what run_tello_emulator polls).
struct EmulatorPorts {
  int command_fd = -1;
  std::uint16_t command = 0;
  std::uint16_t state_source = 0;
  std::uint16_t video_source = 0;
};

}  // namespace shelfcross::verification
