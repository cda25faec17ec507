#pragma once
// What the flight software is doing, for logs (FlightSoftware::telemetry): written on every
// input, read by tello_pilot's flight log and the co-simulation's run records.

#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include "flight_sw/cell_identity.hpp"
#include "flight_sw/control.hpp"
#include "flight_sw/line_hold.hpp"
#include "flight_sw/mission_phases.hpp"
#include "flight_sw/navigation.hpp"
#include "flight_sw/stick_response.hpp"
#include "shelfcross/sdk_messages.hpp"

namespace shelfcross::flight_sw {

/// One tag of the last analysed frame.
struct TagTelemetry {
  cv::Point2d centre_px;
  double area_px = 0.0;
  int tag_row = -1;     ///< -1 when not classified
  int tag_column = -1;
};

/// What the shelf survey saw (ShelfSurvey: FindShelf, GoToViewpoint, TakeInventory, and the
/// approach's re-acquisition): the last analysed view.
struct ViewTelemetry {
  std::vector<TagTelemetry> tags;
  bool grid_valid = false;
  int grid_rows = 0;
  int grid_columns = 0;
  bool full_view = false;
  std::string grid_refusal;
  int markers_seen = 0;
  Eigen::Vector3d e1_G_m = Eigen::Vector3d::Zero();  ///< to the optimal viewpoint
};

/// The target as the approach tracks it (TargetTracker and the mission's approach).
struct TrackingTelemetry {
  std::optional<CellIndex> target;
  std::optional<cv::Rect2d> tracked_box_px;
  bool tracker_ok = false;
  CellIdentity target_identity = CellIdentity::Unknown;  ///< cell_identity.hpp
  int identity_checks = 0;     ///< pictures judged while the target was unidentified
  int identity_contradictions = 0;  ///< of which disagreed with the target (re-read from the viewpoint)
  int shelf_rereads = 0;       ///< shelf re-read from the viewpoint because the target was in doubt
  int rejected_poses = 0;      ///< implausible jumps of the target's pose, ignored
  int wrong_level_poses = 0;   ///< of which on another level's tags (state height disagrees)
  int level_unsure_poses = 0;  ///< poses whose level the state records of the video latency could not tell: held
  int behind_tags_dropped = 0; ///< tags in the target's window too small for the front shelf (eq. 1 against the tracked tags)
  int hidden_target_pictures = 0;  ///< damaged pictures whose guessed rows hid the target's corner tags: held
};

/// The approach's control errors and what was flown (the approach's laws, Sticks, the
/// line-hold gate and the in-crossing watch).
struct ControlTelemetry {
  double e_z_m = 0.0;
  double e_psi_rad = 0.0;
  double psi_cell_rad = 0.0;   ///< heading relative to the cell normal (lateral law input)
  double lateral_mps = 0.0;    ///< bang-off-bang output
  double yaw_cell_rad = 0.0;   ///< the vehicle's own heading relative to the cell normal
  bool settled = false;        ///< still and centred long enough to commit to the crossing
  bool holding_short = false;  ///< forward speed held at 0 (off the normal, or settling)
  double forward_gain = 1.0;   ///< measured forward speed per nominal stick speed (crossing timing)
  LineHoldForecast line_hold;  ///< what the blind crossing may add to the line's offsets (line_hold.hpp)
  int crossings_backed_out = 0;  ///< crossings stopped by the in-crossing watch before the cell
  /// The Tello's measured answer to its sticks per StickAxis, once measured, with the scale
  /// each axis's sticks are sent at (stick_response.hpp).
  StickEstimates sticks;
  VelocityCommand velocity;    ///< last commanded
  RcSticks rc;                 ///< last sent
};

/// The vehicle and the link as the inputs show them (state records, pictures, replies).
struct LinkTelemetry {
  bool video_stalled = false;
  int battery_pct = -1;
  double height_m = 0.0;
  int stale_replies = 0;
  int bad_frames = 0;  ///< frames of the wrong size or type, ignored
  int damaged_frames = 0;  ///< error-concealed pictures received (CameraFrame::damaged)
  int band_decided_frames = 0;  ///< damaged pictures that decided on rows clear of their damage (perception.band_margin_px)
  int unflown_frames = 0;  ///< of which too damaged to steer on (perception.steer_max_damage_events): hovered
};

/// What the flight software is doing, for logs, grouped by what writes it. Updated on every
/// input.
struct Telemetry {
  TimeNs t_ns = 0;
  Phase phase = Phase::Idle;
  int shelf = 0;      ///< index of the shelf being worked on (layout order, from 0)
  std::string event;  ///< the last notable event (phase change, failsafe, refusal)
  /// Body pose from vision: in the target cell's frame K during the approach, in the grid
  /// frame G while going to the viewpoint.
  std::optional<PoseEstimate> pose;
  bool pose_in_cell_frame = false;
  ViewTelemetry view;
  TrackingTelemetry tracking;
  ControlTelemetry control;
  LinkTelemetry link;
};

}  // namespace shelfcross::flight_sw
