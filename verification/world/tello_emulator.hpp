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
// run_tello_emulator() is the one place that reads the wall clock (tello::SteadyClock) and calls
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
#include <functional>
#include <optional>
#include <string>

#include "plant/simulated_tello.hpp"
#include "render/renderer.hpp"
#include "shelfcross/time.hpp"
#include "verification/scenario/dispersion.hpp"
#include "verification/scenario/scenario.hpp"
#include "verification/world/emulator_commands.hpp"
#include "verification/world/emulator_outbox.hpp"
#include "verification/world/emulator_video.hpp"
#include "verification/world/tello_emulator_settings.hpp"
#include "verification/world/tello_world.hpp"

namespace shelfcross::verification {

/// The emulator's parts: the datagram channels and what goes out on them
/// (emulator_outbox.hpp), the SDK command interpreter (emulator_commands.hpp), the camera
/// stream (emulator_video.hpp); here the world's ticks, the state records and the end.
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
  TelloEmulator(const TelloEmulator&) = delete;
  TelloEmulator& operator=(const TelloEmulator&) = delete;

  /// Reads every pending command datagram (stamped now_ns), advances the simulation to the
  /// last autopilot tick <= now_ns handling everything due, sends what is due. now_ns must
  /// never decrease (asserted).
  void advance(TimeNs now_ns);
  /// The earliest time something is due after the last advance: the next tick, or a queued
  /// outgoing datagram (incoming commands are handled at ticks).
  TimeNs next_due_ns() const;

  bool finished() const { return ending_.reason.has_value(); }
  /// Ends the emulation from outside (signal, max_seconds); the first reason given stays.
  void end(const std::string& reason);
  EmulatorReport report() const;

  /// The ports served on (ephemeral ones as bound) and the command socket's descriptor.
  EmulatorPorts ports() const { return outbox_.ports(); }
  /// The simulated Tello in its world, with the run's truth record.
  const TelloWorld& world() const { return world_; }
  /// The world flown (dispersed or nominal) and the camera its client would believe.
  const RunSetup& setup() const { return setup_; }
  /// "EGL ... GL_RENDERER ..." of the video renderer.
  const std::string& renderer_description() const { return video_.renderer_description(); }

 private:
  TelloEmulator(RunSetup setup, EmulatorConfig config, EmulatorChannels channels, render::Renderer* inline_renderer,
                TickObserver on_tick);
  /// One autopilot tick at t: the world, the commands due, the state record, a capture, the
  /// end after landing.
  void tick(TimeNs t_ns, TimeNs now_ns);

  RunSetup setup_;
  EmulatorConfig config_;
  TickObserver on_tick_;
  EmulatorOutbox outbox_;
  TelloWorld world_;  ///< the plant, the firmware, contacts, crossings, the camera's clocks
  SdkCommandInterpreter commands_;
  EmulatorVideo video_;  ///< after outbox_: its worker uses the outbox until it is joined
  /// The autopilot's tick clock, and the time the caller has advanced to.
  struct Clock {
    std::int64_t tick_mhz;
    std::int64_t k_tick = 0;
    TimeNs now_ns = 0;
  } clock_;
  /// Why the emulation ended (the first reason given stays) and the detail.
  struct Ending {
    std::optional<std::string> reason;
    std::string detail;
  } ending_;
};

/// Runs the emulator against the wall clock (tello::SteadyClock, the driver's, read here and
/// nowhere else in the emulator): advance(elapsed) whenever a command datagram arrives or something is due, until it
/// finishes, `stop` becomes true (reason "signal") or max_seconds pass (> 0; "max_seconds").
void run_tello_emulator(TelloEmulator& emulator, const std::atomic<bool>& stop, double max_seconds = 0.0);

}  // namespace shelfcross::verification
