#include "verification/cosim.hpp"

#include <unistd.h>

#include <csignal>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <queue>
#include <variant>

#include "flight_sw/tello/datagram_channel.hpp"
#include "flight_sw/tello/pilot_loop.hpp"
#include "plant/collision.hpp"
#include "plant/simulated_tello.hpp"
#include "render/ground_truth.hpp"
#include "sdk/state_record.hpp"
#include "shelfcross/random.hpp"
#include "shelfcross/rotation.hpp"
#include "verification/link_model.hpp"
#include "verification/run_hash.hpp"
#include "verification/run_metrics_json.hpp"
#include "verification/tello_emulator.hpp"
#include "verification/tello_state_format.hpp"
#include "verification/vehicle_truth.hpp"

namespace shelfcross::verification {
namespace {


/// A message on its way to the flight software: a frame, a state datagram's text (parsed on
/// arrival by the driver's parser, as tello_pilot does), or a reply.
struct StateText {
  std::string text;
};
using ToFlightSoftware = std::variant<CameraFrame, StateText, SdkReply>;

template <class Payload>
struct Timed {
  TimeNs t_ns;
  std::uint64_t seq;  // scheduling order: breaks ties deterministically
  Payload payload;
  bool operator>(const Timed& o) const { return t_ns != o.t_ns ? t_ns > o.t_ns : seq > o.seq; }
};
template <class Payload>
using TimedQueue = std::priority_queue<Timed<Payload>, std::vector<Timed<Payload>>, std::greater<>>;

}  // namespace

const char* outcome_name(RunOutcome outcome) {
  switch (outcome) {
    case RunOutcome::success: return "success";
    case RunOutcome::collision: return "collision";
    case RunOutcome::left_arena: return "left_arena";
    case RunOutcome::timeout: return "timeout";
    case RunOutcome::numerical_failure: return "numerical_failure";
    case RunOutcome::flight_software_exception: return "flight_software_exception";
    case RunOutcome::mission_aborted: return "mission_aborted";
    case RunOutcome::no_crossing: return "no_crossing";
    case RunOutcome::inventory_mismatch: return "inventory_mismatch";
  }
  return "unknown";
}

namespace {
/// The row's spacing when every shelf has shelf 0's geometry and heading and stands the same
/// distance behind the previous one along shelf 0's normal (1 mm tolerance); nullopt otherwise.
std::optional<double> row_spacing_m(const Scenario& sc) {
  const auto& shelves = sc.warehouse.shelves;
  if (shelves.size() < 2) return std::nullopt;
  const ShelfSpec& s0 = shelves[0];
  const Eigen::Isometry3d X_SW = shelf_pose_W(s0).inverse();
  const double spacing = (X_SW * shelves[1].origin_W_m).x();
  if (!(spacing > s0.depth_m)) return std::nullopt;
  for (size_t i = 1; i < shelves.size(); ++i) {
    const ShelfSpec& s = shelves[i];
    const Eigen::Vector3d p_S = X_SW * s.origin_W_m;
    if (s.column_pitch_m != s0.column_pitch_m || s.row_pitch_m != s0.row_pitch_m ||
        s.post_thickness_m != s0.post_thickness_m || s.beam_thickness_m != s0.beam_thickness_m ||
        s.depth_m != s0.depth_m || s.base_height_m != s0.base_height_m ||
        std::abs(wrap_pi(s.yaw_rad - s0.yaw_rad)) > 1e-9 || std::abs(p_S.x() - spacing * static_cast<double>(i)) > 1e-3 ||
        std::abs(p_S.y()) > 1e-3) {
      return std::nullopt;
    }
  }
  return spacing;
}
}  // namespace

int mission_shelf_count(const Scenario& sc) {
  return row_spacing_m(sc) ? static_cast<int>(sc.warehouse.shelves.size()) : 1;
}

double mission_shelf_spacing_m(const Scenario& sc) { return row_spacing_m(sc).value_or(0.0); }

flight_sw::FlightConfig flight_config_for(const Scenario& sc, const CameraIntrinsics& believed_camera) {
  const ShelfSpec& shelf = sc.warehouse.shelves.at(0);
  flight_sw::FlightConfig c;
  c.shelf.column_pitch_m = shelf.column_pitch_m;
  c.shelf.row_pitch_m = shelf.row_pitch_m;
  c.shelf.post_thickness_m = shelf.post_thickness_m;
  c.shelf.beam_thickness_m = shelf.beam_thickness_m;
  c.shelf.depth_m = shelf.depth_m;
  c.shelf.tag_size_m = sc.warehouse.tag_size_m;
  // Tags are cards on the outer face of the bars (warehouse.hpp).
  c.shelf.tag_offset_m = 0.5 * std::max(shelf.post_thickness_m, shelf.beam_thickness_m) +
                         plant::CollisionWorld::kTagThickness_m;
  c.shelf.aruco_dictionary = sc.warehouse.aruco_dictionary;
  c.shelf.marker_size_m = sc.warehouse.marker_size_m;
  c.camera = believed_camera;
  c.mount = sc.camera_mount;
  c.mission.level_check = sc.cosim.pilot.level_check;
  c.mission.vehicle_size_m = sc.vehicle.size_m;
  c.layout.shelf_count = mission_shelf_count(sc);
  c.layout.shelf_spacing_m = mission_shelf_spacing_m(sc);
  if (const auto strategy = flight_sw::parse_strategy(sc.cosim.strategy)) {
    c.strategy.mode = *strategy;
  } else {
    throw std::invalid_argument("unknown strategy '" + sc.cosim.strategy + "'");
  }
  // The operator sets the tag hue window around the tags' colour (OpenCV hue: 0..180).
  const Rgb& tag = sc.warehouse.tag_colour;
  const double mx = std::max({tag.r, tag.g, tag.b}), mn = std::min({tag.r, tag.g, tag.b});
  if (mx - mn > 1e-6) {
    double hue_deg = mx == tag.r ? 60.0 * std::fmod((tag.g - tag.b) / (mx - mn) + 6.0, 6.0)
                     : mx == tag.g ? 60.0 * ((tag.b - tag.r) / (mx - mn) + 2.0)
                                   : 60.0 * ((tag.r - tag.g) / (mx - mn) + 4.0);
    const int h = static_cast<int>(std::lround(hue_deg / 2.0)) % 180;
    const int half_width = (c.perception.tag_hsv.hue_max - c.perception.tag_hsv.hue_min) / 2;
    c.perception.tag_hsv.hue_min = (h - half_width + 180) % 180;
    c.perception.tag_hsv.hue_max = (h + half_width) % 180;
  }
  flight_sw::validate_flight_config(c);
  return c;
}

std::set<InventoryEntry> true_inventory(const Scenario& sc) {
  std::set<InventoryEntry> truth;
  for (int i = 0; i < mission_shelf_count(sc); ++i) {
    for (const BoxPlacement& b : sc.warehouse.shelves.at(static_cast<size_t>(i)).boxes) {
      truth.insert({b.marker_id, i, b.level, b.column});
    }
  }
  return truth;
}

namespace {

/// The sdk link's datagram faults, from the scenario's link settings (LinkSettings explains
/// how each key maps): the emulator's fault model is the co-simulation's link.
EmulatorFaults sdk_faults(const LinkSettings& l) {
  EmulatorFaults f;
  f.commands = {l.command_loss_probability, 1e3 * l.command_latency_mean_s, 1e3 * l.command_latency_jitter_s,
                l.duplicate_probability};
  f.replies = {l.reply_loss, 1e3 * l.state_latency_mean_s, 1e3 * l.state_latency_jitter_s, l.duplicate_probability};
  f.state = {l.state_loss, 1e3 * l.state_latency_mean_s, 1e3 * l.state_latency_jitter_s, l.duplicate_probability};
  f.video = {l.video_datagram_loss, 1e3 * l.video_latency_mean_s, 1e3 * l.video_latency_jitter_s, 0.0};
  f.video_frame_loss = l.frame_drop_probability;
  f.late_replies = l.late_reply_probability;
  f.late_reply_ms = 1e3 * l.late_reply_s;
  f.not_joystick = l.not_joystick_probability;
  f.no_valid_imu = l.no_valid_imu_probability;
  f.lost_command_prefix = l.lost_command;
  if (l.video_stall_start_s >= 0.0 && l.video_stall_duration_s > 0.0) {
    f.video_stall_start_s = l.video_stall_start_s;
    f.video_stall_duration_s = l.video_stall_duration_s;
  }
  return f;
}

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

}  // namespace

RunResult run_cosimulation(const RunSetup& setup, render::Renderer& renderer, const FrameObserver& observer) {
  const Scenario& sc = *setup.scenario;
  const CosimSettings& cs = sc.cosim;
  const ShelfSpec& shelf = sc.warehouse.shelves.at(0);
  const Eigen::Isometry3d X_SW = shelf_pose_W(shelf).inverse();
  if (!sc.start.landed) throw std::invalid_argument("the co-simulation starts landed runs only (start.landed: true)");
  const bool sdk_link = cs.link.model == "sdk";

  RunResult result;
  RunMetrics& m = result.metrics;
  m.link.model = cs.link.model;
  RunHasher hash;
  const plant::CollisionWorld world(sc.warehouse, sc.vehicle.size_m, cs.vehicle_margin_m);

  // An event of the run, logged; `hashed` ones also enter the run hash (the flight
  // software's notes within a phase do not: they only explain what the hashed telemetry did).
  const auto log_event = [&](TimeNs t, const std::string& text, bool hashed = true) {
    char stamp[32];
    std::snprintf(stamp, sizeof stamp, "%.3f ", ns_to_seconds(t));
    result.events.push_back(stamp + text);
    if (!hashed) return;
    hash.add(t);
    hash.add(std::string_view(text));
  };

  // Truth bookkeeping, the same for both links: the vehicle's state after the plant reached t.
  double ground_z_m = 0.0;
  TimeNs t_now = 0;
  Eigen::Isometry3d X_prev = Eigen::Isometry3d::Identity();
  Eigen::Vector3d v_prev = Eigen::Vector3d::Zero();
  Eigen::Vector3d a_W = Eigen::Vector3d::Zero();
  bool touching_floor = true;
  const int shelf_count = mission_shelf_count(sc);
  m.shelves = shelf_count;
  m.strategy = sc.cosim.strategy;
  std::vector<ShelfCrossingMonitor> monitors;  // one per mission shelf; [0] is shelf 0's
  // The truth's starting point: the vehicle as built, at rest on the floor.
  const auto init_truth = [&](const plant::SimulatedTello& tello) {
    ground_z_m = tello.state().p_WB_m.z();
    X_prev = body_pose(tello.state());
    v_prev = tello.state().v_WB_W_mps;
    monitors.reserve(static_cast<size_t>(shelf_count));
    for (int i = 0; i < shelf_count; ++i) monitors.emplace_back(sc.warehouse.shelves[static_cast<size_t>(i)], X_prev.translation());
  };
  std::vector<std::optional<CellIndex>> targets(static_cast<size_t>(shelf_count));  // the chosen cell per shelf
  std::optional<flight_sw::Phase> last_phase;
  std::string last_event;  // the flight software's last notable event, logged when it changes
  std::optional<TimeNs> approach_start_ns;
  std::vector<double> approach_t, err_z, err_yaw, err_y;
  const double half_length_m = 0.5 * sc.vehicle.size_m.x() + cs.vehicle_margin_m;
  const std::int64_t traj_mhz = millihertz(cs.trajectory_rate_hz);
  std::int64_t k_traj = 0;
  std::optional<RunOutcome> outcome;

  // Contacts, the arena, the crossing monitors, the clearance and the truth hash at t.
  const auto observe_truth = [&](TimeNs t, const plant::SimulatedTello& tello) {
    const plant::RigidBodyState& s = tello.state();
    if (!s.p_WB_m.allFinite() || !s.v_WB_W_mps.allFinite() || !s.q_WB.coeffs().allFinite()) {
      outcome = RunOutcome::numerical_failure;
      result.detail = "non-finite state";
      return;
    }
    if (t <= t_now) return;
    const Eigen::Isometry3d X = body_pose(s);
    const double dt_s = ns_to_seconds(t - t_now);
    a_W = (s.v_WB_W_mps - v_prev) / dt_s;
    m.path_length_m += (X.translation() - X_prev.translation()).norm();
    if (const auto contact = world.sweep(X_prev, t_now, X, t, plant::FloorContacts::ignore)) {
      m.contact = *contact;
      const bool shelf_hit = plant::is_shelf_part(contact->element.kind);
      outcome = shelf_hit ? RunOutcome::collision : RunOutcome::left_arena;
      result.detail = contact->element.name;
      log_event(contact->t_ns, "contact with " + contact->element.name);
      t_now = t;
      return;
    }
    const Eigen::Vector3d& p = s.p_WB_m;
    if ((p.array() < sc.warehouse.arena_min_W_m.array()).any() || (p.array() > sc.warehouse.arena_max_W_m.array()).any()) {
      outcome = RunOutcome::left_arena;
      result.detail = "outside the arena";
      return;
    }
    const bool on_floor = p.z() - ground_z_m < 1e-4;
    if (on_floor && !touching_floor) ++m.floor_touches;
    touching_floor = on_floor;
    // Crossing each shelf, judged on the body origin in the shelf's frame.
    bool near_a_shelf = false;
    for (size_t i = 0; i < monitors.size(); ++i) {
      const ShelfCrossingMonitor::Faces faces = monitors[i].update(p);
      const std::string which = shelf_count > 1 ? "shelf " + std::to_string(i) + " " : "";
      if (faces.front) log_event(t, which + "front face crossed");
      if (faces.back) log_event(t, which + "back face crossed");
      const Eigen::Vector3d& p_S = monitors[i].p_S_m();
      near_a_shelf = near_a_shelf ||
                     (p_S.x() > -half_length_m - 0.05 && p_S.x() < shelf.depth_m + half_length_m + 0.05);
    }
    const ShelfCrossingMonitor& crossing = monitors.front();
    m.entry_offset_y_m = crossing.entry_offset_y_m();
    m.entry_offset_z_m = crossing.entry_offset_z_m();
    m.crossed = crossing.crossed();
    if (near_a_shelf) {
      const double clearance = world.clearance_to_shelves(X).distance_m;
      m.min_clearance_m = std::min(m.min_clearance_m.value_or(clearance), clearance);
    }
    // The truth log: every step of the plant.
    hash.add(t);
    for (int i = 0; i < 3; ++i) hash.add(s.p_WB_m[i]);
    for (int i = 0; i < 4; ++i) hash.add(s.q_WB.coeffs()[i]);
    for (int i = 0; i < 3; ++i) hash.add(s.v_WB_W_mps[i]);
    for (int i = 0; i < 3; ++i) hash.add(s.w_WB_B_radps[i]);
    X_prev = X;
    v_prev = s.v_WB_W_mps;
    t_now = t;
  };

  // The trajectory and the approach responses (truth against the target cell), at their rate.
  const auto sample_trajectory = [&](TimeNs t, const plant::RigidBodyState& s, const flight_sw::FlightSoftware& fsw) {
    while (event_time(k_traj, traj_mhz) <= t) {
      TrajectorySample sample;
      sample.t_s = ns_to_seconds(t);
      sample.p_WB_m = s.p_WB_m;
      sample.v_WB_W_mps = s.v_WB_W_mps;
      const Eigen::Vector3d rpy = euler_zyx(body_pose(s).linear());
      sample.roll_rad = rpy.x();
      sample.pitch_rad = rpy.y();
      sample.yaw_rad = rpy.z();
      sample.phase = flight_sw::phase_name(fsw.phase());
      if (fsw.telemetry().pose) sample.p_est_m = fsw.telemetry().pose->p_FB_m();
      result.trajectory.push_back(sample);
      if (approach_start_ns && m.target && fsw.phase() == flight_sw::Phase::Approach && fsw.shelf_index() == 0) {
        const Eigen::Vector3d c = cell_centre_S_m(shelf, m.target->level, m.target->column);
        const Eigen::Vector3d p_S = X_SW * s.p_WB_m;
        approach_t.push_back(ns_to_seconds(t - *approach_start_ns));
        err_z.push_back(p_S.z() - c.z());
        err_y.push_back(p_S.y() - c.y());
        err_yaw.push_back(wrap_pi(rpy.z() - shelf.yaw_rad));
      }
      ++k_traj;
    }
  };

  // What the flight software did in its last step: its telemetry hashed, phases logged, targets.
  const auto after_fsw_step = [&](const flight_sw::FlightSoftware& fsw, TimeNs t) {
    const flight_sw::Telemetry& tm = fsw.telemetry();
    hash.add(static_cast<int>(tm.phase));
    hash.add(tm.e_z_m);
    hash.add(tm.e_psi_rad);
    if (fsw.phase() != last_phase) {
      last_phase = fsw.phase();
      log_event(t, std::string("phase ") + flight_sw::phase_name(*last_phase) + (tm.event.empty() ? "" : ": " + tm.event));
      if (*last_phase == flight_sw::Phase::Approach && !approach_start_ns) {
        approach_start_ns = t;
        result.approach_start_s = ns_to_seconds(t);
        m.target = tm.target;
      }
      if (*last_phase == flight_sw::Phase::Cross && !result.cross_start_s) result.cross_start_s = ns_to_seconds(t);
    } else if (tm.event != last_event && !tm.event.empty()) {
      log_event(t, "event " + tm.event, false);  // within a phase: refusals, losses, back-offs
    }
    last_event = tm.event;
    if (tm.target && fsw.shelf_index() == 0) m.target = tm.target;
    if (tm.target && fsw.shelf_index() < shelf_count) targets[static_cast<size_t>(fsw.shelf_index())] = tm.target;
  };
  const auto injected_fault_due = [&](TimeNs t) {
    return cs.inject_flight_software_exception_s >= 0.0 && t >= seconds_to_ns(cs.inject_flight_software_exception_s);
  };
  // Faults of the run's process itself (cosim.inject_crash_s, cosim.inject_hang_s), for
  // verifying that a campaign survives them: a real SIGSEGV, and a hang that never returns.
  const auto inject_process_faults = [&](TimeNs t) {
    if (cs.inject_crash_s >= 0.0 && t >= seconds_to_ns(cs.inject_crash_s)) {
      // Past any handler (AddressSanitizer's would turn the signal into exit code 1): the
      // process dies by SIGSEGV, as a driver's fault kills a release build.
      std::signal(SIGSEGV, SIG_DFL);
      std::raise(SIGSEGV);
    }
    if (cs.inject_hang_s >= 0.0 && t >= seconds_to_ns(cs.inject_hang_s)) {
      for (;;) pause();
    }
  };
  const auto flight_software_threw = [&](TimeNs t, const std::string& what) {
    outcome = RunOutcome::flight_software_exception;
    result.detail = what;
    log_event(t, "flight software threw: " + what);
  };
  const TimeNs timeout_ns = seconds_to_ns(cs.timeout_s);
  const flight_sw::FlightConfig flight_config = flight_config_for(sc, setup.believed_camera);

  // The two links. Each leaves the flight software it ran, for the verdict.
  std::unique_ptr<flight_sw::FlightSoftware> ideal_fsw;
  std::unique_ptr<tello::PilotLoop> pilot;
  tello::ManualClock pilot_clock(0);
  std::string pilot_failsafe;
  if (sdk_link) {
    // The simulated Tello (its firmware, state records and H.264 stream, the link's faults)
    // and tello_pilot's loop, joined by in-memory datagrams in simulated time.
    auto drone_command = std::make_unique<tello::MemoryChannel>(kDroneCommand);
    auto drone_state = std::make_unique<tello::MemoryChannel>(kDroneState);
    auto drone_video = std::make_unique<tello::MemoryChannel>(kDroneVideo);
    auto pilot_command = std::make_unique<tello::MemoryChannel>(kPilotCommand);
    auto pilot_state = std::make_unique<tello::MemoryChannel>(kPilotState);
    auto pilot_video = std::make_unique<tello::MemoryChannel>(kPilotVideo);
    tello::MemoryChannel *dc = drone_command.get(), *ds = drone_state.get(), *dv = drone_video.get();
    tello::MemoryChannel *pc = pilot_command.get(), *ps = pilot_state.get(), *pv = pilot_video.get();

    EmulatorConfig ec;
    ec.bind_ip = kDroneCommand.ip;
    ec.client_state_port = kPilotState.port;
    ec.client_video_port = kPilotVideo.port;
    ec.faults = sdk_faults(cs.link);
    ec.slices_per_frame = cs.link.video_slices;
    ec.key_interval_frames = cs.link.key_interval_frames;
    ec.linger_s = 1e9;  // the co-simulation ends the run itself
    const flight_sw::FlightSoftware* fsw_view = nullptr;
    TelloEmulator drone(setup, ec, {std::move(drone_command), std::move(drone_state), std::move(drone_video)}, renderer,
                        [&](TimeNs t, const plant::SimulatedTello& tello) {
                          if (outcome) return;
                          observe_truth(t, tello);
                          if (fsw_view) sample_trajectory(t, tello.state(), *fsw_view);
                        });
    init_truth(drone.tello());

    tello::PilotLoopConfig pcfg;
    pcfg.driver.drone_ip = kDroneCommand.ip;
    pcfg.driver.stop_rc_repeats = cs.pilot.stop_rc_repeats;
    pcfg.video.drone_ip = kDroneVideo.ip;
    pcfg.video.threaded = false;  // decoded inline, deterministic, in the run's own thread
    pcfg.flight = flight_config;
    if (observer) pcfg.on_frame = observer;
    pilot = std::make_unique<tello::PilotLoop>(
        pcfg, pilot_clock, tello::PilotChannels{std::move(pilot_command), std::move(pilot_state), std::move(pilot_video)});
    fsw_view = &pilot->flight_software();
    pilot->start();
    log_event(0, std::string("phase ") + flight_sw::phase_name(fsw_view->phase()));
    last_phase = fsw_view->phase();

    // Datagrams from the pilot reach the drone after the flight software's compute time (the
    // command channel's own delay is the drone side's, drawn by its fault model).
    TimedQueue<std::string> to_drone;
    std::uint64_t seq = 0;
    std::optional<int> pilot_exit;
    std::int64_t k_poll = 1;
    const TimeNs compute_ns = seconds_to_ns(cs.link.compute_latency_s);
    const auto forward = [&](tello::MemoryChannel& from, tello::MemoryChannel& to, const tello::Endpoint& sender) {
      bool any = false;
      for (tello::OutgoingDatagram& d : from.take_sent()) {
        to.deliver({std::move(d.bytes), sender});
        any = true;
      }
      return any;
    };
    TimeNs t = 0;
    while (!outcome) {
      t = drone.next_due_ns();
      if (!pilot_exit) t = std::min(t, k_poll * kPilotPollNs);
      if (!to_drone.empty()) t = std::min(t, to_drone.top().t_ns);
      if (t > timeout_ns) {
        outcome = RunOutcome::timeout;
        result.detail = "not finished after " + std::to_string(cs.timeout_s) + " s";
        break;
      }
      inject_process_faults(t);
      while (!to_drone.empty() && to_drone.top().t_ns <= t) {
        dc->deliver({to_drone.top().payload, kPilotCommand});
        to_drone.pop();
      }
      try {
        drone.advance(t);
      } catch (const std::exception& e) {
        if (!outcome) {
          outcome = RunOutcome::numerical_failure;
          result.detail = e.what();
        }
        break;
      }
      if (outcome) break;
      if (drone.finished()) {  // a contact the truth monitor did not see first, or the plant failed
        const EmulatorReport r = drone.report();
        outcome = r.end_reason == "collision" ? RunOutcome::collision
                  : r.end_reason == "left_arena" ? RunOutcome::left_arena
                                                 : RunOutcome::numerical_failure;
        result.detail = r.detail;
        break;
      }
      for (const tello::OutgoingDatagram& d : dc->take_sent()) {
        log_event(t, "reply " + d.bytes);
        pc->deliver({d.bytes, kDroneCommand});
      }
      const bool delivered = forward(*ds, *ps, kDroneState) | forward(*dv, *pv, kDroneVideo);
      const bool poll_due = t >= k_poll * kPilotPollNs;
      while (k_poll * kPilotPollNs <= t) ++k_poll;
      if (!pilot_exit && (delivered || poll_due)) {
        pilot_clock.set(t);
        if (injected_fault_due(t)) {
          flight_software_threw(t, "injected fault (cosim.inject_flight_software_exception_s)");
          break;
        }
        try {
          pilot_exit = pilot->step(0);
        } catch (const std::exception& e) {
          flight_software_threw(t, e.what());
          break;
        }
        after_fsw_step(*fsw_view, t);
        for (tello::OutgoingDatagram& d : pc->take_sent()) {
          log_event(t, "send " + d.bytes);
          to_drone.push({t + compute_ns, seq++, std::move(d.bytes)});
        }
        if (pilot_exit) {
          pilot_failsafe = pilot->failsafe_reason();
          log_event(t, "pilot loop ended (exit " + std::to_string(*pilot_exit) + ")" +
                           (pilot_failsafe.empty() ? "" : ": " + pilot_failsafe));
        }
      }
      // Over when the pilot has ended and the vehicle rests (a pilot that ended in the air
      // leaves it to the drone's own 15 s watchdog).
      if (pilot_exit && drone.tello().mode() == plant::FlightMode::landed && to_drone.empty()) break;
    }
    t_now = std::max(t_now, std::min(t, timeout_ns));
    // The link's evidence.
    const EmulatorCounters c = drone.report().counters;
    const tello::VideoStats v = pilot->video_stats();
    const tello::DriverCounters& d = pilot->driver().counters();
    m.link.video_datagrams = c.video_datagrams_sent + c.video_datagrams_dropped;
    m.link.video_datagrams_lost = c.video_datagrams_dropped;
    m.link.frames_captured = c.frames_captured;
    m.link.frames_lost = c.frames_lost + c.frames_stalled;
    m.link.frames_decoded = v.pictures;
    m.link.frames_damaged = v.handed_damaged;
    m.link.frames_handed = v.handed;
    m.link.commands_sent = d.commands_sent + d.rc_sent + d.keepalives;
    m.link.commands_lost = c.commands_dropped;
    m.link.replies_lost = c.replies_dropped;
    m.link.state_records_lost = c.state_dropped;
    m.link.command_retries = d.retries;
    m.link.stale_replies = d.stale_replies;
    m.link.injected_errors = c.injected_errors;
  } else {
    LinkModel link(cs.link, setup.seed);
    RandomStream render_noise(setup.seed, StreamId::render_noise);
    plant::SimulatedTello tello(sc.vehicle, autopilot_params_for(sc), sc.wind, RandomStream(setup.seed, StreamId::wind).next_u64(),
                                {}, sc.start.p_WB_m.x(), sc.start.p_WB_m.y(), sc.start.yaw_rad);
    init_truth(tello);
    ideal_fsw = std::make_unique<flight_sw::FlightSoftware>(flight_config);
    flight_sw::FlightSoftware& fsw = *ideal_fsw;
    const std::int64_t tick_mhz = millihertz(sc.autopilot.rate_hz), frame_mhz = millihertz(sc.frame_rate_hz),
                       state_mhz = millihertz(cs.state_rate_hz), fsw_tick_mhz = millihertz(cs.fsw_tick_hz);
    std::int64_t k_tick = 1, k_frame = 0, k_state = 0, k_fsw_tick = 1;
    TimedQueue<std::string> to_vehicle;
    TimedQueue<ToFlightSoftware> to_fsw;
    std::uint64_t seq = 0;
    const auto send_commands = [&](const std::vector<SdkCommand>& commands) {
      for (const SdkCommand& c : commands) {
        const std::optional<TimeNs> arrival = link.command_arrival(c.t_ns);
        log_event(c.t_ns, "send " + c.text + (arrival ? "" : " (lost)"));
        ++m.link.commands_sent;
        if (arrival) {
          to_vehicle.push({*arrival, seq++, c.text});
        } else {
          ++m.link.commands_lost;
        }
      }
    };
    const auto reply_to_fsw = [&](TimeNs t_sent, const std::string& text) {
      to_fsw.emplace(link.state_arrival(t_sent), seq++, SdkReply{0, text});
    };
    Eigen::Isometry3d X_WC_prev_frame = render::camera_pose_W(X_prev, sc.camera_mount);
    bool sdk_on = false, video_on = false;
    // Pictures in flight to the flight software share their pixels with the queue (and with
    // whatever the flight software keeps); each capture is drawn into a buffer that nothing
    // else holds any more, so no picture is copied (a 960 x 720 copy was 6 % of a run).
    std::vector<cv::Mat> frame_buffers;
    const auto free_frame_buffer = [&frame_buffers]() -> cv::Mat& {
      for (cv::Mat& b : frame_buffers) {
        if (!b.u || b.u->refcount == 1) return b;  // not drawn into yet, or held by the pool alone
      }
      return frame_buffers.emplace_back();
    };

    send_commands(fsw.start(0));
    log_event(0, std::string("phase ") + flight_sw::phase_name(fsw.phase()));
    last_phase = fsw.phase();

    const auto step_fsw = [&](const flight_sw::Input& input, TimeNs t) {
      std::vector<SdkCommand> commands;
      try {
        if (injected_fault_due(t)) throw std::runtime_error("injected fault (cosim.inject_flight_software_exception_s)");
        commands = fsw.step(input);
      } catch (const std::exception& e) {
        flight_software_threw(t, e.what());
        return;
      }
      send_commands(commands);
      after_fsw_step(fsw, t);
    };

    while (!outcome) {
      TimeNs t = std::min({event_time(k_tick, tick_mhz), event_time(k_frame, frame_mhz),
                           event_time(k_state, state_mhz), event_time(k_traj, traj_mhz),
                           event_time(k_fsw_tick, fsw_tick_mhz)});
      if (!to_vehicle.empty()) t = std::min(t, to_vehicle.top().t_ns);
      if (!to_fsw.empty()) t = std::min(t, to_fsw.top().t_ns);
      if (t > timeout_ns) {
        outcome = RunOutcome::timeout;
        result.detail = "not finished after " + std::to_string(cs.timeout_s) + " s";
        break;
      }
      inject_process_faults(t);

      // 1. Advance the plant and the autopilot; check the motion for contacts.
      try {
        tello.step_to(t);
      } catch (const std::exception& e) {
        outcome = RunOutcome::numerical_failure;
        result.detail = e.what();
        break;
      }
      observe_truth(t, tello);
      if (outcome) break;
      const plant::RigidBodyState& s = tello.state();

      // 2. Events at t, in a fixed order.
      if (t == event_time(k_tick, tick_mhz)) ++k_tick;
      for (const SdkReply& r : tello.take_replies()) {
        log_event(r.t_ns, "reply " + r.text);
        reply_to_fsw(r.t_ns, r.text);
      }
      while (!to_vehicle.empty() && to_vehicle.top().t_ns == t) {
        const std::string text = to_vehicle.top().payload;
        to_vehicle.pop();
        std::optional<std::string> reply;
        try {
          reply = tello.submit(t, text);
        } catch (const std::exception& e) {
          outcome = RunOutcome::numerical_failure;
          result.detail = e.what();
          break;
        }
        if (reply) {
          if (text == "command" && *reply == "ok") sdk_on = true;
          if (text == "streamon" && *reply == "ok") video_on = true;
          if (text == "streamoff" && *reply == "ok") video_on = false;
          log_event(t, "reply " + *reply);
          reply_to_fsw(t, *reply);
        }
      }
      if (outcome) break;
      if (t == event_time(k_frame, frame_mhz)) {
        const std::uint64_t noise_seed = render_noise.next_u64();  // one per capture, dropped or not
        const Eigen::Isometry3d X_WC = render::camera_pose_W(body_pose(s), sc.camera_mount);
        if (video_on) {
          ++m.link.frames_captured;
          if (const auto arrival = link.video_arrival(t)) {
            cv::Mat& frame_bgr = free_frame_buffer();
            if (cs.motion_blur_samples > 1) {
              renderer.render_blurred_into(X_WC_prev_frame, X_WC, noise_seed, frame_bgr);
            } else {
              renderer.render_into(X_WC, noise_seed, frame_bgr);
            }
            to_fsw.push({*arrival, seq++, CameraFrame{*arrival, k_frame, frame_bgr}});
          } else {
            ++m.link.frames_lost;
          }
        }
        X_WC_prev_frame = X_WC;
        ++k_frame;
      }
      if (t == event_time(k_state, state_mhz)) {
        if (sdk_on) {
          const plant::Autopilot& firmware = tello.autopilot();
          const StateRecord truth =
              state_from_truth(s, a_W, ground_z_m, firmware.battery_pct(), firmware.motor_on_time_s(), t);
          to_fsw.push({link.state_arrival(t), seq++, StateText{format_state_record(truth)}});
        }
        ++k_state;
      }
      while (!outcome && !to_fsw.empty() && to_fsw.top().t_ns == t) {
        ToFlightSoftware msg = to_fsw.top().payload;  // cv::Mat copies share the pixels
        to_fsw.pop();
        if (auto* frame = std::get_if<CameraFrame>(&msg)) {
          ++m.link.frames_decoded;
          ++m.link.frames_handed;
          step_fsw(*frame, t);
          if (observer && !outcome) observer(*frame, fsw);
        } else if (auto* state = std::get_if<StateText>(&msg)) {
          if (auto record = sdk::parse_state_record(state->text, t)) step_fsw(*record, t);
        } else {
          SdkReply reply = std::get<SdkReply>(msg);
          reply.t_ns = t;
          step_fsw(reply, t);
        }
      }
      if (outcome) break;
      if (t == event_time(k_fsw_tick, fsw_tick_mhz)) {  // the flight computer's own timer
        step_fsw(flight_sw::ClockTick{t}, t);
        ++k_fsw_tick;
        if (outcome) break;
      }
      sample_trajectory(t, s, fsw);
      if (fsw.finished() && tello.mode() == plant::FlightMode::landed) break;
    }
  }
  const flight_sw::FlightSoftware& fsw = sdk_link ? pilot->flight_software() : *ideal_fsw;

  // Metrics and the verdict.
  m.mission_time_s = ns_to_seconds(t_now);
  m.crossed_target = m.crossed && m.target && *m.crossed == *m.target;
  for (size_t i = 0; i < monitors.size(); ++i) {
    const auto& crossed = monitors[i].crossed();
    m.shelves_crossed += crossed ? 1 : 0;
    m.shelves_crossed_target += crossed && targets[i] && *crossed == *targets[i] ? 1 : 0;
  }
  const bool through_cells = sc.cosim.strategy == "through_cells";
  const flight_sw::MissionResult fsw_result = fsw.result();
  m.flight_software_result = std::string(flight_sw::outcome_name(fsw_result.outcome)) +
                             (fsw_result.reason.empty() ? "" : ": " + fsw_result.reason);
  std::set<InventoryEntry> reported;
  for (const flight_sw::BoxEntry& b : fsw.all_boxes()) reported.insert({b.id, b.shelf, b.level, b.column});
  m.inventory = score_inventory(reported, true_inventory(sc));
  result.inventory_json = fsw.inventory_json();
  if (!approach_t.empty()) {
    m.altitude = analyse_step_response(approach_t, err_z, {cs.settling_fraction, cs.settling_floor_z_m});
    m.heading = analyse_step_response(approach_t, err_yaw, {cs.settling_fraction, cs.settling_floor_yaw_rad});
    m.lateral = analyse_step_response(approach_t, err_y, {cs.settling_fraction, cs.settling_floor_y_m});
  }
  if (!outcome) {
    if (!pilot_failsafe.empty() && fsw_result.outcome != flight_sw::Outcome::Completed) {
      outcome = RunOutcome::mission_aborted;
      result.detail = "tello_pilot failsafe: " + pilot_failsafe;
    } else if (fsw_result.outcome == flight_sw::Outcome::Aborted) {
      outcome = RunOutcome::mission_aborted;
      result.detail = fsw_result.reason;
    } else if (through_cells ? !m.crossed_target || m.shelves_crossed_target < shelf_count
                             : fsw_result.outcome != flight_sw::Outcome::Completed) {
      outcome = RunOutcome::no_crossing;
      result.detail = m.flight_software_result;
      if (through_cells && shelf_count > 1) {
        result.detail += " (" + std::to_string(m.shelves_crossed) + " of " + std::to_string(shelf_count) + " shelves crossed)";
      }
    } else if (!m.inventory.exact()) {
      outcome = RunOutcome::inventory_mismatch;
      result.detail = std::to_string(m.inventory.correct) + " of " + std::to_string(m.inventory.truth) +
                      " boxes right, " + std::to_string(m.inventory.reported) + " reported";
    } else {
      outcome = RunOutcome::success;
    }
  }
  result.outcome = *outcome;
  log_event(t_now, std::string("outcome ") + outcome_name(result.outcome) +
                       (result.detail.empty() ? "" : ": " + result.detail));
  hash.add(std::string_view(run_metrics_json(m)));
  result.run_hash = hash.hex();
  return result;
}

}  // namespace shelfcross::verification
