#pragma once
// The Tello SDK emulator behind `shelfcross tello-sim`: a simulated Tello on real UDP sockets,
// so that an unmodified Tello client (tello_pilot, any SDK script) flies the co-simulation's
// world in real time. It behaves as docs/tello_sdk.md says a Tello does:
//   - commands arrive on bind_ip:command_port; every reply goes to the address and port the
//     command came from; nothing is answered before `command` (SimulatedTello's firmware
//     decides every reply: ranges, real error strings, deferred manoeuvre replies, no reply to
//     rc, rc ignored while landed, the 15 s no-command watchdog, read commands);
//   - after `command`, one SDK 2.0 state record (format_state_record of the plant's
//     truth, as the co-simulation builds it) every 100 ms to client_state_port of the address
//     that sent `command`, from state_source_port;
//   - after `streamon`, the camera (the scenario's intrinsics and mount, the co-simulation's
//     renderer) at the scenario's frame rate, encoded by H264Encoder (libx264
//     zero-latency, SPS and PPS before every key frame, a key frame per second of captures
//     (dropped captures do not stretch the group) and on the first frame after streamon, one
//     slice per macroblock row by default), cut by sdk::tello_datagrams into 1460-byte
//     datagrams with a short last one, to client_video_port of that address, from
//     video_source_port. Why these settings: flight_sw/tello/README.md, tello-sim.
//
// Time. The emulator holds no clock: advance(now_ns) is told the time elapsed since it
// started, and simulated time follows it. The plant and the autopilot advance tick by tick
// (autopilot.rate_hz) up to the last tick <= now_ns; each tick is TelloWorld::tick (the one
// world tick the co-simulation uses too: plant, contacts, arena, crossings, clearance), then
// commands due by then are handed to the firmware, and replies, state records and frame
// captures due by then go out.
// run_tello_emulator() is the one place that reads the wall clock (steady_clock) and calls
// advance(); tests call advance() with times of their own.
//
// Video (tello-sim) runs on a worker thread that owns the renderer and the encoder; in the
// co-simulation (the constructor with a renderer) every capture is rendered and encoded
// inline instead, so nothing is dropped for lack of time and a run stays deterministic.
// On the worker thread, a frame whose capture
// time comes while the worker still renders or encodes the previous one is dropped (counted:
// frames_dropped_busy), and so is a capture more than one frame period in the past when the
// main loop reaches it (frames_dropped_late): the emulator never falls behind the wall clock,
// it sends fewer frames.
//
// Faults (all draws from seeded streams: RandomStream(mix64(seed ^ channel), link_faults), one
// stream per channel, so a setting on one channel never shifts the draws of another):
//   loss / delay on each channel (commands in, replies out, state out, video datagrams out);
//   whole video frames lost (all datagrams of a frame: what a receiver sees of a frame drop);
//   late replies (held back late_reply_ms more: a client takes it for the next command's
//   answer), duplicated replies (sent twice), "error Not joystick" / "error No valid imu"
//   instead of executing a manoeuvre (takeoff, moves, turns, go, curve, flip; never land or
//   emergency, so a client can always end a flight), video stalls (no frames captured in
//   [T, T + D) since the emulator's start).
//
// The flight ends (finished()) at the first contact with a shelf part or a wall (the vehicle
// has no contact dynamics: the report names the element), when the vehicle leaves the arena,
// at a numerical failure of the plant, or once it has landed after flying and no datagram
// came for linger_s (so a client whose land reply was lost can still retry it).

#include <atomic>
#include <condition_variable>
#include <functional>
#include <cstdint>
#include <memory>
#include <mutex>
#include <optional>
#include <queue>
#include <set>
#include <string>
#include <thread>
#include <vector>

#include <Eigen/Geometry>

#include "flight_sw/tello/udp_socket.hpp"
#include "plant/collision.hpp"
#include "plant/simulated_tello.hpp"
#include "render/renderer.hpp"
#include "shelfcross/cell_index.hpp"
#include "shelfcross/random.hpp"
#include "verification/scenario/dispersion.hpp"
#include "verification/scenario/scenario.hpp"
#include "verification/world/datagram_faults.hpp"
#include "verification/world/metrics.hpp"
#include "verification/world/tello_world.hpp"
#include "verification/world/vehicle_truth.hpp"

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
  double path_length_m = 0.0;      ///< of the body origin
  bool flew = false;
  bool landed = true;
  std::optional<plant::Contact> contact;          ///< the first contact with a shelf part or a wall
  std::optional<CellIndex> crossed;    ///< shelf 0's cell crossed face to face
  std::optional<double> entry_offset_y_m, entry_offset_z_m;
  std::optional<double> min_clearance_m;          ///< to any shelf part near a mission shelf
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

class TelloEmulator {
 public:
  /// Called after every autopilot tick whose plant state is finite, with what the tick did
  /// and the world (the co-simulation's truth log and trajectory); never from the video worker.
  using TickObserver = std::function<void(const TickReport& tick, const TelloWorld& world)>;

  /// Binds the sockets, builds the world, the renderer and the encoder. Throws
  /// std::invalid_argument (bad settings or address), std::runtime_error (port busy, no EGL,
  /// no libx264), config errors of the scenario.
  TelloEmulator(const Scenario& scenario, EmulatorConfig config);
  /// The simulated Tello of a co-simulation run: the run's (dispersed) setup, in-memory
  /// channels, and no video thread: captures are rendered by `renderer` (the caller's, made
  /// for the run's warehouse and camera, used only from the calling thread) and encoded
  /// inline, so the run is a pure function of (scenario, seed). config.seed and
  /// config.disperse are taken from the setup.
  TelloEmulator(const RunSetup& setup, EmulatorConfig config, EmulatorChannels channels, render::Renderer& renderer,
                TickObserver on_tick = {});
  ~TelloEmulator();  ///< stops and joins the video worker
  TelloEmulator(const TelloEmulator&) = delete;
  TelloEmulator& operator=(const TelloEmulator&) = delete;

  /// Reads every pending command datagram (stamped now_ns), advances the simulation to the
  /// last autopilot tick <= now_ns handling everything due, sends what is due. now_ns never
  /// decreases.
  void advance(TimeNs now_ns);
  /// The earliest time something is due after the last advance: the next tick, or a queued
  /// outgoing datagram (incoming commands are handled at ticks).
  TimeNs next_due_ns() const;

  bool finished() const { return end_reason_.has_value(); }
  /// Ends the emulation from outside (signal, max_seconds); the first reason given stays.
  void end(const std::string& reason);
  EmulatorReport report() const;

  int command_fd() const { return command_socket_->fd(); }
  std::uint16_t command_port() const { return command_socket_->local_port(); }
  std::uint16_t state_source_port() const { return state_socket_->local_port(); }
  std::uint16_t video_source_port() const { return video_socket_->local_port(); }
  const plant::SimulatedTello& tello() const { return world_.tello(); }
  /// The simulated Tello in its world, with the run's truth record.
  const TelloWorld& world() const { return world_; }
  /// The world flown (dispersed or nominal) and the camera its client would believe.
  const RunSetup& setup() const { return setup_; }
  TimeNs time_ns() const { return world_.tello().time_ns(); }
  /// "EGL ... GL_RENDERER ..." of the video renderer.
  std::string renderer_description() const;

 private:
  enum class Channel { reply, state, video };
  struct Outgoing {
    TimeNs due_ns;
    std::uint64_t seq;
    Channel channel;
    tello::Endpoint to;
    std::string bytes;
    bool operator>(const Outgoing& o) const { return due_ns != o.due_ns ? due_ns > o.due_ns : seq > o.seq; }
  };
  struct IncomingCommand {
    TimeNs due_ns;
    std::uint64_t seq;
    std::string text;
    tello::Endpoint from;
    bool operator>(const IncomingCommand& o) const { return due_ns != o.due_ns ? due_ns > o.due_ns : seq > o.seq; }
  };
  struct FrameJob {
    std::int64_t index = 0;
    TimeNs t_ns = 0;
    Eigen::Isometry3d X_WC_prev = Eigen::Isometry3d::Identity();
    Eigen::Isometry3d X_WC = Eigen::Isometry3d::Identity();
    std::uint64_t noise_seed = 0;
    bool force_key = false;
    tello::Endpoint to;
  };
  struct VideoWorker;
  struct EncodedFrame {
    std::vector<std::string> datagrams;
    bool key = false;
  };

  TelloEmulator(RunSetup setup, EmulatorConfig config, EmulatorChannels channels, render::Renderer* inline_renderer,
                TickObserver on_tick);
  void receive_commands(TimeNs now_ns);
  void tick(TimeNs t_ns, TimeNs now_ns);
  void deliver(TimeNs t_ns, const IncomingCommand& command);
  void send_reply(TimeNs t_ns, const std::string& text, const tello::Endpoint& to);
  /// Queues a datagram due at due_ns and sends everything due by now_ns (under the mutex).
  void enqueue(Channel channel, TimeNs due_ns, const tello::Endpoint& to, std::string bytes, TimeNs now_ns);
  void flush_locked(TimeNs now_ns);
  void video_loop();
  /// Renders, encodes and frames one capture (the worker's job, or inline).
  static EncodedFrame encode_frame(VideoWorker& video, render::Renderer& renderer, const FrameJob& job);
  /// Queues a frame's datagrams (loss and delay drawn) and sends what is due by t_send (under the mutex).
  void queue_frame_locked(const FrameJob& job, EncodedFrame frame, TimeNs t_send);
  void start_video();

  RunSetup setup_;
  std::shared_ptr<const Scenario> scenario_;
  EmulatorConfig config_;
  std::unique_ptr<tello::DatagramChannel> command_socket_, state_socket_, video_socket_;
  render::Renderer* inline_renderer_ = nullptr;  ///< co-simulation: render and encode inline
  TickObserver on_tick_;
  TelloWorld world_;  ///< the plant, the firmware, contacts, crossings, the camera's clocks
  DatagramFaults faults_;  ///< every fault draw and each channel's delivery order

  // Main-loop state (the thread that calls advance()).
  std::priority_queue<IncomingCommand, std::vector<IncomingCommand>, std::greater<>> incoming_;
  std::uint64_t seq_ = 0;
  std::int64_t tick_mhz_;
  std::int64_t k_tick_ = 0;
  TimeNs now_ns_ = 0;
  TimeNs last_datagram_ns_ = 0;
  std::optional<tello::Endpoint> client_;      ///< the sender of `command`
  tello::Endpoint manoeuvre_reply_to_;         ///< the sender of the latest non-rc command
  bool video_was_on_ = false;
  std::int64_t next_key_capture_ = 0;          ///< the capture index due for the next key frame
  std::int64_t key_interval_captures() const;
  std::optional<std::string> end_reason_;
  std::string end_detail_;
  EmulatorReport report_;  ///< what is known at the start (the truth is world_'s, counters counters_)

  // Shared with the video worker (under mutex_).
  mutable std::mutex mutex_;
  std::condition_variable job_ready_;
  std::priority_queue<Outgoing, std::vector<Outgoing>, std::greater<>> outgoing_;
  std::uint64_t out_seq_ = 0;
  EmulatorCounters counters_;
  std::optional<FrameJob> job_;
  bool worker_busy_ = false;
  bool stop_ = false;
  bool worker_ready_ = false;     ///< the worker has built its renderer and encoder (or failed)
  std::string worker_error_;
  std::string renderer_description_;
  std::unique_ptr<VideoWorker> video_;
  std::thread worker_;
};

/// Runs the emulator against the wall clock (std::chrono::steady_clock, read here and nowhere
/// else): advance(elapsed) whenever a command datagram arrives or something is due, until it
/// finishes, `stop` becomes true (reason "signal") or max_seconds pass (> 0; "max_seconds").
void run_tello_emulator(TelloEmulator& emulator, const std::atomic<bool>& stop, double max_seconds = 0.0);

}  // namespace shelfcross::verification
