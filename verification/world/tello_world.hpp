#pragma once
// The simulated Tello in its world, one tick at a time: the plant and the firmware
// (plant::SimulatedTello on CVODE), the Bullet collision world, the crossing monitors of the
// mission's shelves and the run's truth (WorldTruth, world_truth.hpp). The co-simulation
// (either link) and the Tello emulator both advance the vehicle through this one component;
// what each adds around it is its own: the emulator its datagrams, sockets and wall clock, the
// co-simulation its link, the flight software and simulated time.
//
// A tick to t (the caller picks t: the emulator at autopilot ticks, the ideal link at every
// event time) does, in this order:
//   1. the plant and the autopilot advance to t (a CVODE failure ends the world:
//      numerical_failure, the solver's message);
//   2. the state must be finite (else numerical_failure, "non-finite state");
//   3. if t is past the last observed time t_last: a_W = (v(t) - v(t_last)) / (t - t_last),
//      the path grows by |p(t) - p(t_last)|, the motion X(t_last) -> X(t) is swept for
//      contacts (continuous: nothing tunnels between ticks; the first contact ends the world:
//      collision on a shelf part, left_arena on a wall or the ceiling), the body origin must
//      stay inside the arena box (left_arena), floor touches are counted, each mission shelf's
//      crossing monitor sees the body origin (shelf 0's crossing enters the truth), and near
//      any of them (within half the vehicle's length plus its margin and 5 cm of the faces)
//      the clearance to the shelves is taken.
// A contact or the arena ends the observation at that tick: nothing after it (crossings,
// clearance) enters the truth, since the flight is over.
//
// The frame clock and the state clock are here too, so both callers capture frames and send
// state records at the same instants from the same pose: a capture is due at the first tick
// at or after tick(f, frame_rate_hz); each capture draws one render-noise seed, dropped or not.

#include <cstdint>
#include <deque>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Geometry>

#include "plant/collision.hpp"
#include "plant/simulated_tello.hpp"
#include "shelfcross/random.hpp"
#include "shelfcross/time.hpp"
#include "verification/scenario/dispersion.hpp"
#include "verification/world/vehicle_truth.hpp"
#include "verification/world/world_truth.hpp"

namespace shelfcross::verification {

/// How a tick ended the world, if it did.
enum class WorldEnd { none, numerical_failure, collision, left_arena };
const char* world_end_name(WorldEnd end);  ///< "", "numerical_failure", "collision", "left_arena"

/// What one tick did.
struct TickReport {
  TimeNs t_ns = 0;
  WorldEnd end = WorldEnd::none;
  std::string detail;     ///< why it ended: the solver's message, the contact's element, ...
  std::optional<plant::Contact> contact;  ///< the contact that ended the world at this tick
  bool observed = false;  ///< t was past the last observed time and the tick ended nothing:
                          ///< the state is new truth (crossings below, clearance, t_last = t)
  /// Per mission shelf (0 first), the faces its crossing monitor saw crossed this tick.
  std::vector<ShelfCrossingMonitor::Faces> faces;
};

class TelloWorld {
 public:
  /// The setup's (dispersed) world: the vehicle landed at the scenario's start, the wind's
  /// and the render noise's streams from the setup's seed, the collision world with
  /// cosim.vehicle_margin_m, a crossing monitor for each of the first `monitored_shelves`
  /// shelves (>= 1, <= the warehouse's). Throws std::invalid_argument for a start not landed.
  TelloWorld(const RunSetup& setup, int monitored_shelves);

  /// Advances the world to t (>= time_ns()) and observes it (see the file comment). Once a
  /// tick has ended the world, the caller stops calling it.
  TickReport tick(TimeNs t_ns);

  /// The state record the Tello sends at t, from the latest observed truth (before the SDK's
  /// quantisation: format_state_record).
  StateRecord state_record(TimeNs t_ns) const;

  /// A frame capture at this tick, if one is due: the camera pose now and at the previous
  /// capture, the capture's index and render-noise seed. Call once per tick, after tick();
  /// every due capture consumes one noise seed whether or not it is then sent.
  struct Capture {
    std::int64_t index = 0;
    TimeNs t_ns = 0;  ///< the capture instant (the scheduled one, tick(index, frame_rate))
    Eigen::Isometry3d X_WC_prev = Eigen::Isometry3d::Identity();
    Eigen::Isometry3d X_WC = Eigen::Isometry3d::Identity();
    /// The camera pose at the start of a rolling shutter's readout, camera.readout_s before
    /// this tick (whose pose X_WC ends it), interpolated between the poses of the ticks around
    /// it; X_WC itself for a global shutter (readout_s 0).
    Eigen::Isometry3d X_WC_readout_start = Eigen::Isometry3d::Identity();
    std::uint64_t noise_seed = 0;
    TimeNs period_ns = 0;  ///< to the next capture
  };
  std::optional<Capture> capture_due(TimeNs t_ns);
  /// Whether a state record is due at this tick (the first tick at or after tick(s,
  /// cosim.state_rate_hz)); advances the state clock past t when it is.
  bool state_due(TimeNs t_ns);
  /// The next scheduled capture and state instants (a caller that steps from event to event
  /// stops at them).
  TimeNs next_capture_ns() const { return event_time(clocks_.k_frame, clocks_.frame_mhz); }
  TimeNs next_state_ns() const { return event_time(clocks_.k_state, clocks_.state_mhz); }

  plant::SimulatedTello& tello() { return tello_; }
  const plant::SimulatedTello& tello() const { return tello_; }
  /// The truth measured so far (world_truth.hpp).
  const WorldTruth& truth() const { return truth_; }
  /// Whether the firmware has left `landed` at least once (at any tick, observed or not).
  bool flew() const { return flew_; }
  /// The mission shelves' crossing monitors (shelf 0 first, whose crossing truth() holds).
  const std::vector<ShelfCrossingMonitor>& crossings() const { return monitors_; }
  /// The last observed time (0 before the first observed tick).
  TimeNs t_last_ns() const { return last_.t_ns; }

 private:
  void observe(TimeNs t, TickReport& report);

  std::shared_ptr<const Scenario> scenario_;  ///< kept alive: the monitors hold its shelves
  const Scenario& sc_;
  plant::CollisionWorld world_;
  plant::SimulatedTello tello_;
  double ground_z_m_;
  double half_length_m_;
  std::vector<ShelfCrossingMonitor> monitors_;
  WorldTruth truth_;
  bool flew_ = false;
  /// The last observed state: what the next tick's motion is swept from and differenced
  /// against, and the acceleration the state record reports.
  struct LastObserved {
    TimeNs t_ns = 0;
    Eigen::Isometry3d X_WB;
    Eigen::Vector3d v_WB_W_mps;
    Eigen::Vector3d a_W_mps2 = Eigen::Vector3d::Zero();
    bool touching_floor = true;
  } last_;
  /// The camera's and the state record's clocks, and what each capture carries over.
  struct Clocks {
    std::int64_t frame_mhz, state_mhz;
    std::int64_t k_frame = 0, k_state = 0;
    Eigen::Isometry3d X_WC_prev_frame;
    RandomStream render_noise;
    /// With a rolling shutter: the camera pose at each tick of the last readout_s and the one
    /// before (capture_due records them).
    std::deque<std::pair<TimeNs, Eigen::Isometry3d>> recent_X_WC;
  } clocks_;
};

}  // namespace shelfcross::verification
