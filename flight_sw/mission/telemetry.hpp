#pragma once
// What the flight software is doing, for logs (FlightSoftware::telemetry): written on every
// input, read by tello_pilot's flight log and the co-simulation's run records. Each room
// keeps its own record (perception/view_telemetry.hpp, navigation/tracking_telemetry.hpp,
// guidance/control_telemetry.hpp); this gathers them with the link's.

#include <optional>
#include <string>

#include "flight_sw/guidance/control_telemetry.hpp"
#include "flight_sw/mission/phases.hpp"
#include "flight_sw/navigation/navigation.hpp"
#include "flight_sw/navigation/tracking_telemetry.hpp"
#include "flight_sw/perception/view_telemetry.hpp"
#include "shelfcross/time.hpp"

namespace shelfcross::flight_sw {

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
