// The sdk link of the co-simulation: the simulated Tello (TelloEmulator: its firmware, state
// records and H.264 stream, the link's datagram faults) and tello_pilot's loop (driver, video
// receiver, flight software, failsafes), joined by in-memory datagrams in simulated time.

#include <algorithm>
#include <memory>

#include "flight_sw/tello/clock.hpp"
#include "flight_sw/tello/datagram_channel.hpp"
#include "flight_sw/tello/pilot_loop.hpp"
#include "verification/cosim/cosim_run.hpp"
#include "verification/cosim/link_faults.hpp"
#include "verification/world/tello_emulator.hpp"

namespace shelfcross::verification {
namespace {

// The addresses of the in-memory link: the Tello's own (docs/tello_sdk.md) and a computer on its
// Wi-Fi, so that the driver's and the receiver's sender checks run as they do in flight.
const tello::Endpoint kDroneCommand{"192.168.10.1", 8889};
const tello::Endpoint kDroneState{"192.168.10.1", 8890};
const tello::Endpoint kDroneVideo{"192.168.10.1", 11111};
const tello::Endpoint kPilotCommand{"192.168.10.2", 50000};
const tello::Endpoint kPilotState{"192.168.10.2", 8890};
const tello::Endpoint kPilotVideo{"192.168.10.2", 11111};

/// The pilot loop polls its sockets with this timeout (tello_pilot); in simulated time it
/// steps at least this often, and whenever a datagram reaches it.
constexpr TimeNs kPilotPollNs = 5'000'000;

/// The six in-memory channels: the drone's three and the pilot's three.
struct MemoryLink {
  std::unique_ptr<tello::MemoryChannel> drone_command = std::make_unique<tello::MemoryChannel>(kDroneCommand);
  std::unique_ptr<tello::MemoryChannel> drone_state = std::make_unique<tello::MemoryChannel>(kDroneState);
  std::unique_ptr<tello::MemoryChannel> drone_video = std::make_unique<tello::MemoryChannel>(kDroneVideo);
  std::unique_ptr<tello::MemoryChannel> pilot_command = std::make_unique<tello::MemoryChannel>(kPilotCommand);
  std::unique_ptr<tello::MemoryChannel> pilot_state = std::make_unique<tello::MemoryChannel>(kPilotState);
  std::unique_ptr<tello::MemoryChannel> pilot_video = std::make_unique<tello::MemoryChannel>(kPilotVideo);
  tello::MemoryChannel *dc = drone_command.get(), *ds = drone_state.get(), *dv = drone_video.get();
  tello::MemoryChannel *pc = pilot_command.get(), *ps = pilot_state.get(), *pv = pilot_video.get();
};

/// Moves every datagram sent on `from` to `to`; whether there was any.
bool forward(tello::MemoryChannel& from, tello::MemoryChannel& to, const tello::Endpoint& sender) {
  bool any = false;
  for (tello::OutgoingDatagram& d : from.take_sent()) {
    to.deliver({std::move(d.bytes), sender});
    any = true;
  }
  return any;
}

EmulatorConfig drone_config(const CosimSettings& cs) {
  EmulatorConfig ec;
  ec.bind_ip = kDroneCommand.ip;
  ec.client_state_port = kPilotState.port;
  ec.client_video_port = kPilotVideo.port;
  ec.faults = link_faults(cs.link);  // drawn with the run's seed (TelloEmulator: setup.seed)
  ec.slices_per_frame = cs.link.video_slices;
  ec.key_interval_frames = cs.link.key_interval_frames;
  ec.linger_s = 1e9;  // the co-simulation ends the run itself
  return ec;
}

/// The link's evidence, from the drone's counters and the pilot's.
LinkMetrics link_metrics(LinkMetrics l, const EmulatorCounters& c, const tello::PilotLoop& pilot) {
  const tello::VideoStats v = pilot.video_stats();
  const tello::DriverCounters& d = pilot.driver().counters();
  l.video_datagrams = c.video_datagrams_sent + c.video_datagrams_dropped;
  l.video_datagrams_lost = c.video_datagrams_dropped;
  l.frames_captured = c.frames_captured;
  l.frames_lost = c.frames_lost + c.frames_stalled;
  l.frames_decoded = v.pictures;
  l.frames_damaged = v.handed_damaged;
  l.frames_handed = v.handed;
  l.commands_sent = d.commands_sent + d.rc_sent + d.keepalives;
  l.commands_lost = c.commands_dropped;
  l.replies_lost = c.replies_dropped;
  l.state_records_lost = c.state_dropped;
  l.command_retries = d.retries;
  l.stale_replies = d.stale_replies;
  l.injected_errors = c.injected_errors;
  return l;
}

/// What moves between the drone and the pilot loop, and the pilot loop's state.
struct SdkLink {
  MemoryLink wires;
  TelloEmulator drone;
  tello::ManualClock pilot_clock{0};
  tello::PilotLoopConfig pilot_config;  ///< the pilot loop keeps a reference to it
  std::unique_ptr<tello::PilotLoop> pilot;
  /// Datagrams from the pilot reach the drone after the flight software's compute time (the
  /// command channel's own delay is the drone side's, drawn by its fault model).
  TimedQueue<std::string> to_drone;
  std::uint64_t seq = 0;
  std::optional<int> pilot_exit;
  std::int64_t k_poll = 1;
  std::string failsafe;

  SdkLink(RunContext& run, const flight_sw::FlightSoftware** fsw_view)
      : drone(run.setup, drone_config(run.cs), {std::move(wires.drone_command), std::move(wires.drone_state), std::move(wires.drone_video)},
              run.renderer, [&run, fsw_view](const TickReport& tick, const TelloWorld& world) {
                if (run.outcome) return;
                run.observe(tick, world);
                if (*fsw_view) run.sample_trajectory(tick.t_ns, world.tello().state(), **fsw_view);
              }) {
    tello::PilotLoopConfig& pcfg = pilot_config;
    pcfg.driver.drone_ip = kDroneCommand.ip;
    pcfg.driver.stop_rc_repeats = run.cs.pilot.stop_rc_repeats;
    pcfg.video.drone_ip = kDroneVideo.ip;
    pcfg.video.threaded = false;  // decoded inline, deterministic, in the run's own thread
    pcfg.flight = run.flight_config;
    if (run.observer) pcfg.on_frame = run.observer;
    pilot = std::make_unique<tello::PilotLoop>(
        pcfg, pilot_clock,
        tello::PilotChannels{std::move(wires.pilot_command), std::move(wires.pilot_state), std::move(wires.pilot_video)});
  }

  /// One step of the pilot loop at t (when a datagram reached it or its poll is due); false
  /// when the flight software threw.
  bool step_pilot(RunContext& run, TimeNs t, TimeNs compute_ns) {
    pilot_clock.set(t);
    if (injected_fault_due(run.cs, t)) {
      run.flight_software_threw(t, "injected fault (cosim.inject_flight_software_exception_s)");
      return false;
    }
    try {
      pilot_exit = pilot->step(0);
    } catch (const std::exception& e) {
      run.flight_software_threw(t, e.what());
      return false;
    }
    run.after_fsw_step(pilot->flight_software(), t);
    for (tello::OutgoingDatagram& d : wires.pc->take_sent()) {
      run.log_event(t, "send " + d.bytes);
      to_drone.push({t + compute_ns, seq++, std::move(d.bytes)});
    }
    if (pilot_exit) {
      failsafe = pilot->failsafe_reason();
      run.log_event(t, "pilot loop ended (exit " + std::to_string(*pilot_exit) + ")" +
                           (failsafe.empty() ? "" : ": " + failsafe));
    }
    return true;
  }
};

}  // namespace

RunResult fly_sdk_link(RunContext& run) {
  const flight_sw::FlightSoftware* fsw_view = nullptr;
  SdkLink link(run, &fsw_view);
  MemoryLink& w = link.wires;
  fsw_view = &link.pilot->flight_software();
  link.pilot->start();
  run.started(*fsw_view);

  const TimeNs compute_ns = seconds_to_ns(run.cs.link.compute_latency_s);
  TimeNs t = 0;
  while (!run.outcome) {
    t = link.drone.next_due_ns();
    if (!link.pilot_exit) t = std::min(t, link.k_poll * kPilotPollNs);
    if (!link.to_drone.empty()) t = std::min(t, link.to_drone.top().t_ns);
    if (const TimeNs limit = run.limit_ns(*fsw_view); t > limit) {
      run.time_out(limit);
      break;
    }
    inject_process_faults(run.cs, t);
    while (!link.to_drone.empty() && link.to_drone.top().t_ns <= t) {
      w.dc->deliver({link.to_drone.top().payload, kPilotCommand});
      link.to_drone.pop();
    }
    try {
      link.drone.advance(t);
    } catch (const std::exception& e) {
      if (!run.outcome) {
        run.outcome = RunOutcome::numerical_failure;
        run.result.detail = e.what();
      }
      break;
    }
    if (run.outcome) break;
    if (link.drone.finished()) {  // the plant failed (contacts and the arena reach the run at its tick)
      const EmulatorReport r = link.drone.report();
      run.outcome = r.end_reason == "collision"    ? RunOutcome::collision
                    : r.end_reason == "left_arena" ? RunOutcome::left_arena
                                                   : RunOutcome::numerical_failure;
      run.result.detail = r.detail;
      break;
    }
    for (const tello::OutgoingDatagram& d : w.dc->take_sent()) {
      run.log_event(t, "reply " + d.bytes);
      w.pc->deliver({d.bytes, kDroneCommand});
    }
    const bool delivered = forward(*w.ds, *w.ps, kDroneState) | forward(*w.dv, *w.pv, kDroneVideo);
    const bool poll_due = t >= link.k_poll * kPilotPollNs;
    while (link.k_poll * kPilotPollNs <= t) ++link.k_poll;
    if (!link.pilot_exit && (delivered || poll_due) && !link.step_pilot(run, t, compute_ns)) break;
    // Over when the pilot has ended and the vehicle rests (a pilot that ended in the air
    // leaves it to the drone's own 15 s watchdog).
    if (link.pilot_exit && link.drone.world().tello().mode() == plant::FlightMode::landed && link.to_drone.empty()) break;
  }
  run.t_end_ns = std::max(run.t_end_ns, std::min(t, run.limit_ns(*fsw_view)));
  run.result.metrics.link = link_metrics(run.result.metrics.link, link.drone.report().counters, *link.pilot);
  return run.finish(link.drone.world(), link.pilot->flight_software(), link.failsafe);
}

}  // namespace shelfcross::verification
