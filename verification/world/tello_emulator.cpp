#include "verification/world/tello_emulator.hpp"

#include <poll.h>

#include <algorithm>
#include <cassert>
#include <stdexcept>

#include "flight_sw/tello/clock.hpp"
#include "verification/world/mission_setup.hpp"
#include "verification/world/tello_state_format.hpp"

namespace shelfcross::verification {
namespace {

RunSetup make_setup(const Scenario& nominal, const EmulatorConfig& c) {
  if (c.disperse) return disperse(nominal, c.seed);
  RunSetup setup;
  setup.seed = c.seed;
  setup.scenario = std::make_shared<Scenario>(nominal);
  setup.believed_camera = nominal.camera;
  return setup;
}

void check_landed(const Scenario& sc) {
  if (!sc.start.landed) throw std::invalid_argument("the Tello emulator starts landed (start.landed: true)");
}

EmulatorConfig with_seed(EmulatorConfig c, const RunSetup& setup) {
  c.seed = setup.seed;
  c.disperse = !setup.drawn.empty();
  return c;
}

}  // namespace

TelloEmulator::TelloEmulator(const Scenario& scenario, EmulatorConfig config)
    : TelloEmulator(make_setup(scenario, config), std::move(config), {}, nullptr, {}) {}

TelloEmulator::TelloEmulator(const RunSetup& setup, EmulatorConfig config, EmulatorChannels channels,
                             render::Renderer& renderer, TickObserver on_tick)
    : TelloEmulator(setup, with_seed(std::move(config), setup), std::move(channels), &renderer, std::move(on_tick)) {}

TelloEmulator::TelloEmulator(RunSetup setup, EmulatorConfig config, EmulatorChannels channels,
                             render::Renderer* inline_renderer, TickObserver on_tick)
    : setup_(std::move(setup)),
      config_((validate_emulator_config(config), std::move(config))),
      on_tick_(std::move(on_tick)),
      outbox_(std::move(channels), config_),
      world_((check_landed(*setup_.scenario), setup_), mission_shelf_count(*setup_.scenario)),
      commands_(config_.max_datagram_bytes),
      video_(*setup_.scenario, config_, inline_renderer, outbox_),
      clock_{millihertz(setup_.scenario->autopilot.rate_hz)} {}

void TelloEmulator::end(const std::string& reason) {
  if (!ending_.reason) ending_.reason = reason;
}

TimeNs TelloEmulator::next_due_ns() const {
  // Commands that fell due are handed to the firmware at the next tick, so they never make
  // anything due before it.
  const TimeNs t = event_time(clock_.k_tick, clock_.tick_mhz);
  const auto lock = outbox_.lock();
  return outbox_.next_due_locked(t);
}

void TelloEmulator::advance(TimeNs now_ns) {
  assert(now_ns >= clock_.now_ns);
  clock_.now_ns = now_ns;
  commands_.receive(now_ns, outbox_);
  while (!ending_.reason) {
    const TimeNs t = event_time(clock_.k_tick, clock_.tick_mhz);
    if (t > now_ns) break;
    tick(t, now_ns);
    ++clock_.k_tick;
  }
  const auto lock = outbox_.lock();
  if (!video_.error_locked().empty()) {
    ending_.detail = video_.error_locked();
    end("video_error");
  }
  outbox_.flush_locked(now_ns);
}

void TelloEmulator::tick(TimeNs t, TimeNs now_ns) {
  // 1. The world to t: the plant and the firmware, the motion checked for contacts, the arena,
  // the crossings, the clearance.
  const TickReport r = world_.tick(t);
  if (r.end != WorldEnd::none) {
    ending_.detail = r.detail;
    end(world_end_name(r.end));
    if (r.end == WorldEnd::numerical_failure) return;
  }
  if (on_tick_) on_tick_(r, world_);
  if (ending_.reason) return;
  plant::SimulatedTello& tello = world_.tello();

  // 2. Commands due by t, to the firmware; its replies.
  if (const auto failure = commands_.deliver_due(t, tello, outbox_)) {
    ending_.detail = *failure;
    end("numerical_failure");
  }
  const std::optional<tello::Endpoint>& client = commands_.client();

  // 3. The state record, to the `command` sender's state port.
  if (world_.state_due(t)) {
    if (tello.autopilot().sdk_mode() && client) {
      const std::string text = format_state_record(world_.state_record(t));
      const auto lock = outbox_.lock();
      outbox_.send_state_locked(t, text, {client->ip, config_.client_state_port});
    }
  }

  // 4. A frame capture: to the encoder while the stream is on (and a client known).
  if (const auto capture = world_.capture_due(t)) {
    std::optional<tello::Endpoint> to;
    if (tello.autopilot().stream_on() && client) to = tello::Endpoint{client->ip, config_.client_video_port};
    video_.capture(*capture, t, now_ns, to);
  }

  // 5. Landed after flying, and nobody talking any more: the flight is over.
  if (world_.flew() && tello.mode() == plant::FlightMode::landed &&
      t - commands_.last_datagram_ns() >= seconds_to_ns(config_.linger_s)) {
    end("landed");
  }
}

EmulatorReport TelloEmulator::report() const {
  const Scenario& sc = *setup_.scenario;
  EmulatorReport r;
  r.end_reason = ending_.reason.value_or("running");
  r.detail = ending_.detail;
  r.inventory_truth = true_inventory(sc);
  r.start_p_W_m = sc.start.p_WB_m;
  r.start_yaw_rad = sc.start.yaw_rad;
  r.seed = config_.seed;
  r.dispersed = config_.disperse;
  r.drawn = setup_.drawn;
  const plant::SimulatedTello& tello = world_.tello();
  r.elapsed_s = ns_to_seconds(tello.time_ns());
  r.flight_time_s = tello.autopilot().motor_on_time_s();
  r.flew = world_.flew();
  r.landed = tello.mode() == plant::FlightMode::landed;
  r.truth = world_.truth();
  const auto lock = outbox_.lock();
  r.counters = outbox_.counters_locked();
  return r;
}

void run_tello_emulator(TelloEmulator& emulator, const std::atomic<bool>& stop, double max_seconds) {
  // The emulator's one wall clock, the driver's (its origin here): simulated time follows the
  // time elapsed since here.
  const tello::SteadyClock clock;
  const auto elapsed_ns = [&] { return clock.now_ns(); };
  const TimeNs max_ns = max_seconds > 0.0 ? seconds_to_ns(max_seconds) : 0;
  for (;;) {
    const TimeNs now = elapsed_ns();
    emulator.advance(now);
    if (emulator.finished()) break;
    if (stop.load()) {
      emulator.end("signal");
      break;
    }
    if (max_ns > 0 && now >= max_ns) {
      emulator.end("max_seconds");
      break;
    }
    // Sleep in poll until a command arrives or the next thing falls due (at most 2 ms, so a
    // signal is seen promptly).
    const TimeNs wait_ns = std::clamp<TimeNs>(emulator.next_due_ns() - elapsed_ns(), 0, 2'000'000);
    pollfd p{emulator.ports().command_fd, POLLIN, 0};
    const timespec ts{0, static_cast<long>(wait_ns)};
    ppoll(&p, 1, &ts, nullptr);
  }
  // What is already queued (a land reply, say) goes out before the report.
  emulator.advance(elapsed_ns());
}

}  // namespace shelfcross::verification
