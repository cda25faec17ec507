#include "verification/world/tello_world.hpp"

#include <algorithm>
#include <iterator>
#include <stdexcept>

#include "render/ground_truth.hpp"
#include "render/rolling_shutter.hpp"

namespace shelfcross::verification {

const char* world_end_name(WorldEnd end) {
  switch (end) {
    case WorldEnd::none: return "";
    case WorldEnd::numerical_failure: return "numerical_failure";
    case WorldEnd::collision: return "collision";
    case WorldEnd::left_arena: return "left_arena";
  }
  return "";
}

namespace {
const Scenario& landed_scenario(const RunSetup& setup) {
  if (!setup.scenario) throw std::invalid_argument("a run setup without a scenario");
  if (!setup.scenario->start.landed) {
    throw std::invalid_argument("the simulated Tello starts landed runs only (start.landed: true)");
  }
  return *setup.scenario;
}
}  // namespace

TelloWorld::TelloWorld(const RunSetup& setup, int monitored_shelves)
    : scenario_(setup.scenario),
      sc_(landed_scenario(setup)),
      world_(sc_.warehouse, sc_.vehicle.size_m, sc_.cosim.vehicle_margin_m),
      tello_(sc_.vehicle, autopilot_params_for(sc_), sc_.wind, RandomStream(setup.seed, StreamId::wind).next_u64(), {},
             sc_.start.p_WB_m.x(), sc_.start.p_WB_m.y(), sc_.start.yaw_rad,
             plant::SensesSetup{sc_.senses, &world_, light_level(sc_.warehouse.lighting), setup.seed}),
      ground_z_m_(tello_.state().p_WB_m.z()),
      half_length_m_(0.5 * sc_.vehicle.size_m.x() + sc_.cosim.vehicle_margin_m),
      last_{0, body_pose(tello_.state()), tello_.state().v_WB_W_mps},
      clocks_{millihertz(sc_.frame_rate_hz), millihertz(sc_.cosim.state_rate_hz), 0, 0,
              render::camera_pose_W(last_.X_WB, sc_.camera_mount), RandomStream(setup.seed, StreamId::render_noise), {}} {
  if (monitored_shelves < 1 || monitored_shelves > static_cast<int>(sc_.warehouse.shelves.size())) {
    throw std::invalid_argument("monitored shelves must be 1.." + std::to_string(sc_.warehouse.shelves.size()));
  }
  monitors_.reserve(static_cast<size_t>(monitored_shelves));
  for (int i = 0; i < monitored_shelves; ++i) {
    monitors_.emplace_back(sc_.warehouse.shelves[static_cast<size_t>(i)], last_.X_WB.translation());
  }
  if (sc_.readout_s > 0.0) clocks_.recent_X_WC.emplace_back(0, clocks_.X_WC_prev_frame);
}

TickReport TelloWorld::tick(TimeNs t) {
  TickReport r;
  r.t_ns = t;
  try {
    tello_.step_to(t);
  } catch (const std::exception& e) {
    r.end = WorldEnd::numerical_failure;
    r.detail = e.what();
    return r;
  }
  const plant::RigidBodyState& s = tello_.state();
  if (!s.p_WB_m.allFinite() || !s.v_WB_W_mps.allFinite() || !s.q_WB.coeffs().allFinite()) {
    r.end = WorldEnd::numerical_failure;
    r.detail = "non-finite state";
    return r;
  }
  if (tello_.mode() != plant::FlightMode::landed) flew_ = true;
  if (t > last_.t_ns) observe(t, r);
  return r;
}

void TelloWorld::observe(TimeNs t, TickReport& r) {
  const plant::RigidBodyState& s = tello_.state();
  const Eigen::Isometry3d X = body_pose(s);
  last_.a_W_mps2 = (s.v_WB_W_mps - last_.v_WB_W_mps) / ns_to_seconds(t - last_.t_ns);
  truth_.path_length_m += (X.translation() - last_.X_WB.translation()).norm();
  if (const auto contact = world_.sweep(last_.X_WB, last_.t_ns, X, t, plant::FloorContacts::ignore)) {
    truth_.contact = *contact;
    r.contact = *contact;
    r.end = plant::is_shelf_part(contact->element.kind) ? WorldEnd::collision : WorldEnd::left_arena;
    r.detail = contact->element.name;
    last_.t_ns = t;  // the contact's tick is the flight's last instant
    return;
  }
  const Eigen::Vector3d& p = s.p_WB_m;
  if ((p.array() < sc_.warehouse.arena_min_W_m.array()).any() || (p.array() > sc_.warehouse.arena_max_W_m.array()).any()) {
    r.end = WorldEnd::left_arena;
    r.detail = "outside the arena";
    return;
  }
  const bool on_floor = p.z() - ground_z_m_ < 1e-4;
  if (on_floor && !last_.touching_floor) ++truth_.floor_touches;
  last_.touching_floor = on_floor;
  // Each mission shelf's crossing, judged on the body origin in that shelf's frame; the
  // clearance near any of them (a row's shelves share shelf 0's depth).
  const double depth_m = sc_.warehouse.shelves.front().depth_m;
  bool near_a_shelf = false;
  r.faces.reserve(monitors_.size());
  for (ShelfCrossingMonitor& monitor : monitors_) {
    r.faces.push_back(monitor.update(p));
    const double x_S = monitor.p_S_m().x();
    near_a_shelf = near_a_shelf || (x_S > -half_length_m_ - 0.05 && x_S < depth_m + half_length_m_ + 0.05);
  }
  const ShelfCrossingMonitor& shelf0 = monitors_.front();
  truth_.crossed = shelf0.crossed();
  truth_.entry_offset_y_m = shelf0.entry_offset_y_m();
  truth_.entry_offset_z_m = shelf0.entry_offset_z_m();
  if (near_a_shelf) {
    const double clearance = world_.clearance_to_shelves(X).distance_m;
    truth_.min_clearance_m = std::min(truth_.min_clearance_m.value_or(clearance), clearance);
  }
  r.observed = true;
  last_.X_WB = X;
  last_.v_WB_W_mps = s.v_WB_W_mps;
  last_.t_ns = t;
}

StateRecord TelloWorld::state_record(TimeNs t) const {
  const plant::Autopilot& firmware = tello_.autopilot();
  return state_from_senses(tello_.state(), firmware.senses().readings(tello_.state()), last_.a_W_mps2, ground_z_m_,
                           firmware.battery_pct(), firmware.motor_on_time_s(), t);
}

namespace {
// The camera pose at t from the poses h of recent ticks (ascending times), interpolated
// between the ticks around t.
Eigen::Isometry3d pose_at(const std::deque<std::pair<TimeNs, Eigen::Isometry3d>>& h, TimeNs t) {
  // The first tick at or after t (the vehicle sat at its first recorded pose before it).
  auto b = std::lower_bound(h.begin(), h.end(), t, [](const auto& e, TimeNs x) { return e.first < x; });
  if (b == h.begin()) return h.front().second;
  if (b == h.end()) return h.back().second;
  const auto a = std::prev(b);
  const double s = static_cast<double>(t - a->first) / static_cast<double>(b->first - a->first);
  return render::interpolate_pose(a->second, b->second, s);
}
}  // namespace

std::optional<TelloWorld::Capture> TelloWorld::capture_due(TimeNs t) {
  Clocks& k = clocks_;
  const Eigen::Isometry3d X_WC = render::camera_pose_W(body_pose(tello_.state()), sc_.camera_mount);
  const TimeNs readout_ns = seconds_to_ns(sc_.readout_s);
  if (readout_ns > 0) {
    // Keep the ticks of the last readout and the one before it (to interpolate at its start).
    if (k.recent_X_WC.back().first < t) k.recent_X_WC.emplace_back(t, X_WC);
    while (k.recent_X_WC.size() > 2 && k.recent_X_WC[1].first <= t - readout_ns) k.recent_X_WC.pop_front();
  }
  if (t < event_time(k.k_frame, k.frame_mhz)) return std::nullopt;
  Capture c;
  c.index = k.k_frame;
  c.t_ns = event_time(k.k_frame, k.frame_mhz);
  c.period_ns = event_time(k.k_frame + 1, k.frame_mhz) - c.t_ns;
  c.X_WC_prev = k.X_WC_prev_frame;
  c.X_WC = X_WC;
  c.X_WC_readout_start = readout_ns > 0 ? pose_at(k.recent_X_WC, t - readout_ns) : X_WC;
  c.noise_seed = k.render_noise.next_u64();  // one per capture, sent or not
  k.X_WC_prev_frame = c.X_WC;
  while (event_time(k.k_frame, k.frame_mhz) <= t) ++k.k_frame;
  return c;
}

bool TelloWorld::state_due(TimeNs t) {
  Clocks& k = clocks_;
  if (t < event_time(k.k_state, k.state_mhz)) return false;
  while (event_time(k.k_state, k.state_mhz) <= t) ++k.k_state;
  return true;
}

}  // namespace shelfcross::verification
