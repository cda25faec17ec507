#include "verification/cosim/cosim_run.hpp"

#include <unistd.h>

#include <csignal>
#include <cstdio>
#include <stdexcept>

#include "shelfcross/rotation.hpp"
#include "verification/cosim/run_metrics_json.hpp"

namespace shelfcross::verification {

namespace {
const Scenario& landed(const RunSetup& setup) {
  if (!setup.scenario->start.landed) {
    throw std::invalid_argument("the co-simulation starts landed runs only (start.landed: true)");
  }
  return *setup.scenario;
}
}  // namespace

RunContext::RunContext(const RunSetup& setup_, render::Renderer& renderer_, const FrameObserver& observer_)
    : setup(setup_),
      sc(landed(setup_)),
      cs(sc.cosim),
      renderer(renderer_),
      observer(observer_),
      flight_config(flight_config_for(sc, setup_.believed_camera)),
      timeout_ns(seconds_to_ns(cs.timeout_s)),
      shelf_count(mission_shelf_count(sc)),
      traj_{sc.warehouse.shelves.at(0), shelf_pose_W(sc.warehouse.shelves.at(0)).inverse(),
            millihertz(cs.trajectory_rate_hz), 0, std::nullopt, {}, {}, {}, {}},
      fsw_log_{std::nullopt, "", std::vector<std::optional<CellIndex>>(static_cast<size_t>(shelf_count))} {
  RunMetrics& m = result.metrics;
  m.link.model = cs.link.model;
  m.shelves = shelf_count;
  m.strategy = cs.strategy;
}

void RunContext::log_event(TimeNs t, const std::string& text, bool hashed) {
  char stamp[32];
  std::snprintf(stamp, sizeof stamp, "%.3f ", ns_to_seconds(t));
  result.events.push_back(stamp + text);
  if (!hashed) return;
  hash.add(t);
  hash.add(std::string_view(text));
}

void RunContext::observe(const TickReport& tick, const TelloWorld& world) {
  if (tick.end == WorldEnd::numerical_failure || (tick.end == WorldEnd::left_arena && !tick.contact)) {
    outcome = tick.end == WorldEnd::numerical_failure ? RunOutcome::numerical_failure : RunOutcome::left_arena;
    result.detail = tick.detail;
    return;
  }
  if (tick.contact) {
    outcome = tick.end == WorldEnd::collision ? RunOutcome::collision : RunOutcome::left_arena;
    result.detail = tick.detail;
    log_event(tick.contact->t_ns, "contact with " + tick.contact->element.name);
    t_end_ns = world.t_last_ns();
    return;
  }
  if (!tick.observed) return;
  for (size_t i = 0; i < tick.faces.size(); ++i) {
    const std::string which = shelf_count > 1 ? "shelf " + std::to_string(i) + " " : "";
    if (tick.faces[i].front) log_event(tick.t_ns, which + "front face crossed");
    if (tick.faces[i].back) log_event(tick.t_ns, which + "back face crossed");
  }
  // The truth log: every step of the plant.
  const plant::RigidBodyState& s = world.tello().state();
  hash.add(tick.t_ns);
  for (int i = 0; i < 3; ++i) hash.add(s.p_WB_m[i]);
  for (int i = 0; i < 4; ++i) hash.add(s.q_WB.coeffs()[i]);
  for (int i = 0; i < 3; ++i) hash.add(s.v_WB_W_mps[i]);
  for (int i = 0; i < 3; ++i) hash.add(s.w_WB_B_radps[i]);
  t_end_ns = world.t_last_ns();
}

void RunContext::sample_trajectory(TimeNs t, const plant::RigidBodyState& s, const flight_sw::FlightSoftware& fsw) {
  RunMetrics& m = result.metrics;
  while (event_time(traj_.k, traj_.mhz) <= t) {
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
    if (traj_.approach_start_ns && m.target && fsw.phase() == flight_sw::Phase::Approach && fsw.shelf_index() == 0) {
      const Eigen::Vector3d c = cell_centre_S_m(traj_.shelf, m.target->level, m.target->column);
      const Eigen::Vector3d p_S = traj_.X_SW * s.p_WB_m;
      traj_.t.push_back(ns_to_seconds(t - *traj_.approach_start_ns));
      traj_.err_z.push_back(p_S.z() - c.z());
      traj_.err_y.push_back(p_S.y() - c.y());
      traj_.err_yaw.push_back(wrap_pi(rpy.z() - traj_.shelf.yaw_rad));
    }
    ++traj_.k;
  }
}

void RunContext::after_fsw_step(const flight_sw::FlightSoftware& fsw, TimeNs t) {
  RunMetrics& m = result.metrics;
  const flight_sw::Telemetry& tm = fsw.telemetry();
  hash.add(static_cast<int>(tm.phase));
  hash.add(tm.control.e_z_m);
  hash.add(tm.control.e_psi_rad);
  if (fsw.phase() != fsw_log_.last_phase) {
    fsw_log_.last_phase = fsw.phase();
    log_event(t, std::string("phase ") + flight_sw::phase_name(*fsw_log_.last_phase) + (tm.event.empty() ? "" : ": " + tm.event));
    if (*fsw_log_.last_phase == flight_sw::Phase::Approach && !traj_.approach_start_ns) {
      traj_.approach_start_ns = t;
      result.approach_start_s = ns_to_seconds(t);
      m.target = tm.tracking.target;
    }
    if (*fsw_log_.last_phase == flight_sw::Phase::Cross && !result.cross_start_s) result.cross_start_s = ns_to_seconds(t);
  } else if (tm.event != fsw_log_.last_event && !tm.event.empty()) {
    log_event(t, "event " + tm.event, false);  // within a phase: refusals, losses, back-offs
  }
  fsw_log_.last_event = tm.event;
  if (tm.tracking.target && fsw.shelf_index() == 0) m.target = tm.tracking.target;
  if (tm.tracking.target && fsw.shelf_index() < shelf_count) fsw_log_.targets[static_cast<size_t>(fsw.shelf_index())] = tm.tracking.target;
}

void RunContext::flight_software_threw(TimeNs t, const std::string& what) {
  outcome = RunOutcome::flight_software_exception;
  result.detail = what;
  log_event(t, "flight software threw: " + what);
}

bool injected_fault_due(const CosimSettings& cs, TimeNs t) {
  return cs.inject_flight_software_exception_s >= 0.0 && t >= seconds_to_ns(cs.inject_flight_software_exception_s);
}

void inject_process_faults(const CosimSettings& cs, TimeNs t) {
  if (cs.inject_crash_s >= 0.0 && t >= seconds_to_ns(cs.inject_crash_s)) {
    // Past any handler (AddressSanitizer's would turn the signal into exit code 1): the
    // process dies by SIGSEGV, as a driver's fault kills a release build.
    std::signal(SIGSEGV, SIG_DFL);
    std::raise(SIGSEGV);
  }
  if (cs.inject_hang_s >= 0.0 && t >= seconds_to_ns(cs.inject_hang_s)) {
    for (;;) pause();
  }
}

namespace {
constexpr double kLandingGrace_s = 30.0;  // RunContext::limit_ns
}  // namespace

TimeNs RunContext::limit_ns(const flight_sw::FlightSoftware& fsw) const {
  const bool landing = fsw.phase() == flight_sw::Phase::Land || fsw.phase() == flight_sw::Phase::Done;
  return landing ? timeout_ns + seconds_to_ns(kLandingGrace_s) : timeout_ns;
}

void RunContext::time_out(TimeNs limit) {
  outcome = RunOutcome::timeout;
  result.detail = "not finished after " + std::to_string(ns_to_seconds(limit)) + " s";
}

void RunContext::started(const flight_sw::FlightSoftware& fsw) {
  log_event(0, std::string("phase ") + flight_sw::phase_name(fsw.phase()));
  fsw_log_.last_phase = fsw.phase();
}

RunResult RunContext::finish(const TelloWorld& world, const flight_sw::FlightSoftware& fsw,
                             const std::string& pilot_failsafe) {
  RunMetrics& m = result.metrics;
  m.truth = world.truth();
  // Metrics and the verdict.
  m.mission_time_s = ns_to_seconds(t_end_ns);
  m.crossed_target = m.truth.crossed && m.target && *m.truth.crossed == *m.target;
  for (size_t i = 0; i < world.crossings().size(); ++i) {
    const auto& crossed = world.crossings()[i].crossed();
    m.shelves_crossed += crossed ? 1 : 0;
    m.shelves_crossed_target += crossed && fsw_log_.targets[i] && *crossed == *fsw_log_.targets[i] ? 1 : 0;
  }
  const bool through_cells = cs.strategy == "through_cells";
  const flight_sw::MissionResult fsw_result = fsw.result();
  m.flight_software_result = std::string(flight_sw::outcome_name(fsw_result.outcome)) +
                             (fsw_result.reason.empty() ? "" : ": " + fsw_result.reason);
  m.sticks = fsw.telemetry().control.sticks;
  std::set<InventoryEntry> reported;
  for (const flight_sw::BoxEntry& b : fsw.all_boxes()) reported.insert({b.id, b.shelf, b.level, b.column});
  m.inventory = score_inventory(reported, true_inventory(sc));
  result.inventory_json = fsw.inventory_json();
  if (!traj_.t.empty()) {
    m.altitude = analyse_step_response(traj_.t, traj_.err_z, {cs.settling_fraction, cs.settling_floor_z_m});
    m.heading = analyse_step_response(traj_.t, traj_.err_yaw, {cs.settling_fraction, cs.settling_floor_yaw_rad});
    m.lateral = analyse_step_response(traj_.t, traj_.err_y, {cs.settling_fraction, cs.settling_floor_y_m});
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
  log_event(t_end_ns, std::string("outcome ") + outcome_name(result.outcome) +
                          (result.detail.empty() ? "" : ": " + result.detail));
  hash.add(std::string_view(run_metrics_json(m)));
  result.run_hash = hash.hex();
  return std::move(result);
}

}  // namespace shelfcross::verification
