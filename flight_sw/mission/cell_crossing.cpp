#include "flight_sw/mission/cell_crossing.hpp"

#include <Eigen/Geometry>

#include "flight_sw/guidance/guidance.hpp"

namespace shelfcross::flight_sw {

void CellCrossing::begin(const CrossingStart& start) {
  end_ = start.end;
  watch_ = start.watch;
  height_m_ = start.height_m;
}

// The crossing holds the cell centre's height by the state height (no picture shows the cell
// in there): a drift or a sink the open-loop command would carry into a beam is turned back.
double CellCrossing::vz_mps(double height_m) const { return crossing_vz_mps(config_.control, *height_m_, height_m); }

// On each state record of the crossing: the watch's verdict (line_hold.hpp); a drift seen while
// the vehicle can still stop short of the front face stops it (the mission backs it out, a
// refusal of the crossing like the gate's: crossing_attempts of them decline it).
std::optional<CrossingStop> CellCrossing::watch(const StateRecord& s, MissionFacts& facts) const {
  const Eigen::Vector2d v_O = Eigen::Rotation2Dd(s.yaw_rad) * Eigen::Vector2d(s.vx_H_mps, s.vy_H_mps);
  const CrossingWatchVerdict v = crossing_watch(end_, watch_, config_.mission, facts.odometry.p_O_m(), v_O,
                                                s.height_m - *height_m_, s.vz_H_mps);
  if (!v.back_out) return std::nullopt;
  ++facts.telemetry.control.crossings_backed_out;
  return CrossingStop{"drift seen before the cell (" + centimetres_text(v.across_m) + " across, " +
                          centimetres_text(v.height_m) + " up)",
                      (facts.odometry.p_O_m().head<2>() - end_.start_O_m).dot(end_.axis_O)};
}

bool CellCrossing::flown(TimeNs elapsed_ns, const MissionFacts& facts) const {
  return crossing_flown(end_, elapsed_ns, facts.state_fresh(), facts.odometry.p_O_m());
}

}  // namespace shelfcross::flight_sw
