#include "flight_sw/tello/pilot_log.hpp"

#include <cstdio>
#include <ostream>

namespace shelfcross::tello {
namespace {

const char* origin_name(int tag) {
  switch (tag) {
    case kTagFlightSoftware: return "fsw";
    case kTagPilot: return "pilot";
    default: return "driver";
  }
}

// Picture rows a frame's damage may cover (the log's measure of how much is guesswork).
int damaged_row_count(const VideoFrame& f) {
  int rows = 0;
  for (const RowSpan& r : f.damaged_rows) rows += r.v_end_px - r.v_begin_px;
  return rows;
}

}  // namespace

void PilotLog::driver_event(const DriverEvent& e) {
  nlohmann::json j = nlohmann::json::object();
  if (!e.command.empty()) j["command"] = e.command;
  if (e.kind == DriverEvent::Kind::State) {
    j["raw"] = e.reply;
    j["battery_pct"] = e.state->battery_pct;
    j["height_m"] = e.state->height_m;
  } else if (!e.reply.empty()) {
    j["reply"] = e.reply;
  }
  if (e.attempt) j["attempt"] = e.attempt;
  if (e.tag) j["origin"] = origin_name(e.tag);
  if (e.synthetic) j["synthetic"] = true;
  log_.write(e.t_ns, event_kind_name(e.kind), std::move(j));
}

void PilotLog::frame(TimeNs taken_ns, const VideoFrame& f) {
  log_.write(taken_ns, "frame", {{"index", f.index}, {"rx_ns", f.t_ns}, {"handed_ns", f.handed_ns},
                                 {"damaged", f.damaged}, {"key_group", f.key_group},
                                 {"damage_events", f.damage_events}, {"damaged_rows", damaged_row_count(f)},
                                 {"rows", f.bgr.rows}, {"cols", f.bgr.cols}});
}

void PilotLog::telemetry(const flight_sw::Telemetry& tm, const Clock& clock) {
  if (tm.phase == logged_phase_ && tm.event == logged_event_) return;
  logged_phase_ = tm.phase;
  logged_event_ = tm.event;
  log_.write(clock.now_ns(), "fsw", {{"phase", flight_sw::phase_name(tm.phase)}, {"event", tm.event},
                                     {"battery_pct", tm.link.battery_pct}, {"height_m", tm.link.height_m}});
  if (console_) {
    *console_ << "[" << ns_to_seconds(clock.now_ns()) << " s] " << flight_sw::phase_name(tm.phase) << ": "
              << tm.event << std::endl;
  }
}

// Where the flight software believes it is relative to the target cell (frame K: x toward
// the shelf, y left, z up; origin at the cell's centre on the front face), so that a flight
// can be understood afterwards.
void PilotLog::approach_view(const flight_sw::Telemetry& tm, const Clock& clock) {
  if (tm.phase != flight_sw::Phase::Approach) return;
  nlohmann::json j = {{"tracker_ok", tm.tracking.tracker_ok}, {"e_z_m", tm.control.e_z_m}, {"e_psi_rad", tm.control.e_psi_rad},
                      {"settled", tm.control.settled}, {"holding_short", tm.control.holding_short},
                      {"rejected_poses", tm.tracking.counts.rejected_poses}, {"wrong_level_poses", tm.tracking.counts.wrong_level_poses},
                      {"level_unsure_poses", tm.tracking.counts.level_unsure_poses},
                      {"damaged_frames", tm.link.damaged_frames}, {"band_decided_frames", tm.link.band_decided_frames},
                      {"unflown_frames", tm.link.unflown_frames}};
  if (tm.pose && tm.pose_in_cell_frame) {
    const Eigen::Vector3d p = tm.pose->p_FB_m();
    j["p_KB_m"] = {p.x(), p.y(), p.z()};
    j["yaw_K_rad"] = tm.pose->yaw_rad;
  }
  if (tm.tracking.tracked_box_px) {
    const cv::Rect2d& b = *tm.tracking.tracked_box_px;
    j["box_px"] = {b.x, b.y, b.width, b.height};
  }
  log_.write(clock.now_ns(), "fsw_view", std::move(j));
}

void PilotLog::record(const VideoFrame& f, const FrameWriter& write, const Clock& clock) {
  char name[64];
  std::snprintf(name, sizeof name, "frame_%06lld%s.png", static_cast<long long>(f.index), f.damaged ? "_damaged" : "");
  if (!write(name, f.bgr)) {
    log_.write(clock.now_ns(), "failsafe", {{"event", "cannot record frame " + std::string(name)}});
  }
}

}  // namespace shelfcross::tello
