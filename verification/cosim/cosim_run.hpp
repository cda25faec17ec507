#pragma once
// One co-simulated run's state (what Drake calls a Context): the result being built, the run
// hash, the truth log and the flight software's bookkeeping, shared by the two links. The
// links (cosim_sdk_link.cpp, cosim_ideal_link.cpp) each advance the world and the flight
// software from event to event and report into this context; run_cosimulation makes one,
// lets the scenario's link fly it, and returns its verdict. Internal to the co-simulation.

#include <cstdint>
#include <functional>
#include <optional>
#include <queue>
#include <string>
#include <vector>

#include "flight_sw/mission/flight_software.hpp"
#include "render/renderer.hpp"
#include "verification/cosim/run_hash.hpp"
#include "verification/cosim/run_result.hpp"
#include "verification/scenario/dispersion.hpp"
#include "verification/world/mission_setup.hpp"
#include "verification/world/tello_world.hpp"

namespace shelfcross::verification {

/// A message in flight, due at t_ns; ties broken by the order of scheduling (seq), so a run
/// is a pure function of (scenario, seed).
template <class Payload>
struct Timed {
  TimeNs t_ns;
  std::uint64_t seq;
  Payload payload;
  bool operator>(const Timed& o) const { return t_ns != o.t_ns ? t_ns > o.t_ns : seq > o.seq; }
};
template <class Payload>
using TimedQueue = std::priority_queue<Timed<Payload>, std::vector<Timed<Payload>>, std::greater<>>;

class RunContext {
 public:
  /// Requires a landed start (std::invalid_argument otherwise) and a renderer made for the
  /// run's warehouse and camera.
  RunContext(const RunSetup& setup, render::Renderer& renderer, const FrameObserver& observer);

  // What the run is.
  const RunSetup& setup;
  const Scenario& sc;
  const CosimSettings& cs;
  render::Renderer& renderer;
  const FrameObserver& observer;
  const flight_sw::FlightConfig flight_config;
  const TimeNs timeout_ns;
  const int shelf_count;  ///< the mission's shelves (mission_shelf_count)

  // What it has become so far.
  RunResult result;
  std::optional<RunOutcome> outcome;  ///< set once: the first thing that ends the run
  RunHasher hash;
  /// Simulated time reached (the last observed truth; the sdk link's loop may end later).
  TimeNs t_end_ns = 0;

  /// An event of the run, logged; `hashed` ones also enter the run hash (the flight
  /// software's notes within a phase do not: they only explain what the hashed telemetry did).
  void log_event(TimeNs t, const std::string& text, bool hashed = true);
  /// What a world tick did, into the run: its end as the run's outcome (a contact logged),
  /// the faces crossed logged, the observed state hashed (the truth log: every plant step).
  void observe(const TickReport& tick, const TelloWorld& world);
  /// The trajectory and the approach responses (truth against the target cell), at
  /// cosim.trajectory_rate_hz, up to t.
  void sample_trajectory(TimeNs t, const plant::RigidBodyState& s, const flight_sw::FlightSoftware& fsw);
  /// The next trajectory sample's instant.
  TimeNs next_sample_ns() const { return event_time(traj_.k, traj_.mhz); }
  /// What the flight software did in its last step: its telemetry hashed, phases logged,
  /// the chosen cells kept.
  void after_fsw_step(const flight_sw::FlightSoftware& fsw, TimeNs t);
  void flight_software_threw(TimeNs t, const std::string& what);
  /// The run's limit now: cosim.timeout_s, or up to kLandingGrace_s more while the flight
  /// software lands (phases Land and Done). A run is not cut in the middle of its landing: the
  /// mission's own time budget ends 10 s before the limit (flight_config_for), but one lost
  /// `land` costs the driver's 7 s reply timeout before it goes again, and a descent from a
  /// cell's height takes seconds more. Runs that end before cosim.timeout_s are unchanged.
  TimeNs limit_ns(const flight_sw::FlightSoftware& fsw) const;
  /// Past the limit (limit_ns): the run's outcome.
  void time_out(TimeNs limit);
  /// The phase the flight software starts in, logged.
  void started(const flight_sw::FlightSoftware& fsw);

  /// The verdict, once the link has flown: the world's truth and the link's counts into the
  /// metrics, the outcome judged, the run hash closed. `pilot_failsafe`: the pilot loop's
  /// failsafe reason (sdk), empty if none.
  RunResult finish(const TelloWorld& world, const flight_sw::FlightSoftware& fsw, const std::string& pilot_failsafe);

 private:
  /// The trajectory's clock and the approach responses (shelf 0's frame, its chosen cell).
  struct Trajectory {
    const ShelfSpec& shelf;          ///< shelf 0
    const Eigen::Isometry3d X_SW;    ///< shelf 0's frame from the world's
    const std::int64_t mhz;          ///< cosim.trajectory_rate_hz
    std::int64_t k = 0;
    std::optional<TimeNs> approach_start_ns;
    std::vector<double> t, err_z, err_yaw, err_y;
  } traj_;
  /// What the flight software said last, and the cell it chose per mission shelf.
  struct FswLog {
    std::optional<flight_sw::Phase> last_phase;
    std::string last_event;  ///< its last notable event, logged when it changes
    std::vector<std::optional<CellIndex>> targets;
  } fsw_log_;
};

/// cosim.inject_flight_software_exception_s has come by t.
bool injected_fault_due(const CosimSettings& cs, TimeNs t);
/// Faults of the run's process itself (cosim.inject_crash_s, cosim.inject_hang_s), for
/// verifying that a campaign survives them: past its time, a real SIGSEGV, and a hang that
/// never returns.
void inject_process_faults(const CosimSettings& cs, TimeNs t);

/// The sdk link: the simulated Tello (TelloEmulator on in-memory datagrams) against
/// tello_pilot's loop, in simulated time. Flies the run and returns its verdict.
RunResult fly_sdk_link(RunContext& run);
/// The ideal link: whole messages with the sdk link's faults (link_faults.hpp), the flight
/// software alone.
RunResult fly_ideal_link(RunContext& run);

}  // namespace shelfcross::verification
