#include "flight_sw/mission/cell_crossing.hpp"

#include <cmath>

#include <Eigen/Geometry>

#include "flight_sw/guidance/guidance.hpp"

namespace shelfcross::flight_sw {

void CellCrossing::begin(const CrossingStart& start, TimeNs now_ns) {
  end_ = start.end;
  watch_ = start.watch;
  height_m_ = start.height_m;
  started_ns_ = now_ns;
  readings_ = CrossingReadings{};
  offset_told_ = vps_told_ = false;
}

// Flying: longer than the autopilot's lag since the crossing began, so a working VPS reads its
// speed (crossing_readings.hpp).
void CellCrossing::on_state(const StateRecord& s, MissionFacts& facts) {
  readings_.on_state(s, ns_to_seconds(s.t_ns - started_ns_) > kVelocityLag_s);
  if (!offset_told_ && readings_.hold_offset_m() != 0.0) {
    offset_told_ = true;
    facts.telemetry.event = "the height hold follows the range: " + centimetres_text(-readings_.hold_offset_m()) +
                            " climbed that h does not show; held by the vertical speed";
  }
  if (!vps_told_ && readings_.vps_lost()) {
    vps_told_ = true;
    facts.telemetry.event = "VPS lost in the crossing (no horizontal speed read): the rest flown at the speed last read";
  }
}

// The crossing holds the cell centre's height by the state height (no picture shows the cell
// in there): a drift or a sink the open-loop command would carry into a beam is turned back.
// Where the height hold follows the range, the vehicle is at h less the hold's offset o
// (crossing_readings.hpp), and it stays at the cell's height only while the Tello's height
// reference moves with o: the offset's rate is sent as a vertical speed of its own, and the
// height error's correction at kp is widened by kp |o|, so that the whole offset is asked back
// rather than crossing_z_speed_max_mps of it.
double CellCrossing::vz_mps(double height_m) const {
  const ControlGains& g = config_.control;
  const double o = readings_.hold_offset_m();
  return readings_.hold_offset_rate_mps() +
         height_hold_vz_mps(*height_m_, height_m - o, g.crossing_kp_z, g.crossing_z_speed_max_mps + g.crossing_kp_z * std::abs(o));
}

// On each state record of the crossing: the watch's verdict (line_hold.hpp); a drift seen while
// the vehicle can still stop short of the front face stops it (the mission backs it out, a
// refusal of the crossing like the gate's: crossing_attempts of them decline it).
std::optional<CrossingStop> CellCrossing::watch(const StateRecord& s, MissionFacts& facts) const {
  if (readings_.vps_lost()) return std::nullopt;
  const Eigen::Vector2d v_O = Eigen::Rotation2Dd(s.yaw_rad) * Eigen::Vector2d(s.vx_H_mps, s.vy_H_mps);
  const CrossingWatchVerdict v = crossing_watch(end_, watch_, config_.mission, facts.odometry.p_O_m(), v_O,
                                                s.height_m - readings_.hold_offset_m() - *height_m_, s.vz_H_mps);
  if (!v.back_out) return std::nullopt;
  ++facts.telemetry.control.crossings_backed_out;
  return CrossingStop{"drift seen before the cell (" + centimetres_text(v.across_m) + " across, " +
                          centimetres_text(v.height_m) + " up)",
                      crossing_progress_m(end_, facts.odometry.p_O_m())};
}

// The line's progress: the odometry's, plus what was flown blind while the VPS read nothing
// (crossing_readings.hpp), plus, while the records are late, the time since the last one at
// the speed last read. Where no speed has been read in this crossing and the VPS is lost or
// the records late, nothing tells the progress: the crossing is timed.
bool CellCrossing::flown(TimeNs elapsed_ns, const MissionFacts& facts) const {
  const std::optional<double> v_mps = readings_.speed_mps();
  std::optional<double> progress_m;
  if (facts.state && (v_mps || (facts.state_fresh() && !readings_.vps_lost()))) {
    progress_m = crossing_progress_m(end_, facts.odometry.p_O_m()) + readings_.blind_m();
    if (!facts.state_fresh()) *progress_m += *v_mps * ns_to_seconds(facts.now_ns - facts.state->t_ns);
  }
  return crossing_flown(end_, elapsed_ns, progress_m);
}

}  // namespace shelfcross::flight_sw
