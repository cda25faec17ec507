#pragma once
// What one run of the co-simulation gives: its outcome, its metrics (truth measured by the
// world, what the link did), its hash, trajectory and event lines. Written by the run
// (cosim_run.hpp), stored as JSON (run_metrics_json.hpp), read by campaigns and reports.

#include <array>
#include <cstdint>
#include <functional>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "flight_sw/mission/flight_software.hpp"
#include "shelfcross/camera.hpp"
#include "shelfcross/cell_index.hpp"
#include "verification/world/metrics.hpp"
#include "verification/world/world_truth.hpp"

namespace shelfcross::verification {

enum class RunOutcome {
  success,                    ///< mission done, no contact, exact inventory of every shelf, landed
                              ///< (through_cells: every shelf crossed face to face, shelf 0 at its target)
  collision,                  ///< touched a shelf part
  left_arena,                 ///< touched a wall or the ceiling, or left the arena box
  timeout,
  numerical_failure,          ///< the plant diverged (CVODE error, NaN)
  flight_software_exception,  ///< the flight software threw
  mission_aborted,            ///< the flight software gave up (its reason is the detail)
  no_crossing,                ///< landed without crossing every shelf face to face (through_cells),
                              ///< or without passing the last shelf (over_tops, around_ends)
  inventory_mismatch,         ///< crossed cleanly but the box list was wrong
};
const char* outcome_name(RunOutcome outcome);

/// What the link did in a run (sdk: datagrams through the pilot loop; ideal: whole messages,
/// so the datagram counts stay 0).
struct LinkMetrics {
  std::string model = "sdk";
  std::int64_t video_datagrams = 0;       ///< sent by the drone, lost ones included
  std::int64_t video_datagrams_lost = 0;
  std::int64_t frames_captured = 0;       ///< capture instants while streaming
  std::int64_t frames_lost = 0;           ///< whole frames lost or stalled (never sent)
  std::int64_t frames_decoded = 0;        ///< pictures the receiver decoded (ideal: frames delivered)
  std::int64_t frames_damaged = 0;        ///< of those handed over, error-concealed (sdk only)
  std::int64_t frames_handed = 0;         ///< handed to the flight software
  std::int64_t commands_sent = 0;         ///< command datagrams, rc and keep-alives (sdk) included
  std::int64_t commands_lost = 0;         ///< drawn lost or lost by cosim.link.lost_command
  std::int64_t replies_lost = 0;
  std::int64_t state_records_lost = 0;
  std::int64_t command_retries = 0;       ///< the driver's re-sends after a reply timeout (sdk only)
  std::int64_t stale_replies = 0;         ///< replies dropped as stale (sdk: by the driver; ideal: by the flight software)
  std::int64_t injected_errors = 0;       ///< "error Not joystick" / "error No valid imu" answers (sdk only)
  /// Fraction of video datagrams lost (0 when none was sent).
  double video_datagram_loss() const {
    return video_datagrams > 0 ? static_cast<double>(video_datagrams_lost) / static_cast<double>(video_datagrams) : 0.0;
  }
};

/// Everything a run measured (JSON form, both ways: run_metrics_json.hpp).
struct RunMetrics {
  double mission_time_s = 0.0;     ///< start to the end of the run
  /// The world's truth (TelloWorld::truth): path, floor touches, the first contact, shelf 0's
  /// crossing and entry offsets, the minimum clearance.
  WorldTruth truth;
  // The mission: its shelves (the scenario's row, mission_shelf_count) and strategy
  std::string strategy = "through_cells";
  int shelves = 1;
  int shelves_crossed = 0;                      ///< shelves crossed face to face through a cell
  int shelves_crossed_target = 0;               ///< ... through the cell the flight software chose there
  // Shelf 0's crossing (truth.crossed) against the flight software's choice
  std::optional<CellIndex> target;   ///< the flight software's chosen cell
  bool crossed_target = false;       ///< truth.crossed is the target
  // Approach responses (paper Fig. 26-28): from the start of the approach to the crossing
  std::optional<StepResponse> altitude;  ///< body z - cell centre z, m
  std::optional<StepResponse> heading;   ///< yaw - shelf normal, rad
  std::optional<StepResponse> lateral;   ///< body y_S - cell centre y_S, m
  // Inventory
  InventoryScore inventory;
  std::string flight_software_result;    ///< outcome and reason of the flight software
  /// The sticks' measured answer by the end of the run and the scale they were sent at, per
  /// flight_sw::StickAxis (flight_sw/control/stick_response.hpp); empty where the run gave too little
  /// to measure.
  flight_sw::StickEstimates sticks;
  LinkMetrics link;
};

/// One sample of the run's trajectory (truth and what the flight software was doing).
struct TrajectorySample {
  double t_s = 0.0;
  Eigen::Vector3d p_WB_m = Eigen::Vector3d::Zero();
  Eigen::Vector3d v_WB_W_mps = Eigen::Vector3d::Zero();
  double roll_rad = 0.0, pitch_rad = 0.0, yaw_rad = 0.0;
  std::string phase;
  std::optional<Eigen::Vector3d> p_est_m;  ///< flight software's body position in its frame
};

struct RunResult {
  RunOutcome outcome = RunOutcome::timeout;
  std::string detail;  ///< e.g. the contact's element, the exception's message
  RunMetrics metrics;
  std::string run_hash;
  std::string inventory_json;
  std::vector<TrajectorySample> trajectory;  ///< at cosim.trajectory_rate_hz
  std::optional<double> approach_start_s;    ///< the flight software entered Approach
  std::optional<double> cross_start_s;       ///< ... and Cross
  std::vector<std::string> events;           ///< "t_s text" lines: phases, commands, contacts
};

/// Called with each frame the flight software received, after it handled it (for --video).
using FrameObserver = std::function<void(const CameraFrame&, const flight_sw::FlightSoftware&)>;

}  // namespace shelfcross::verification
