#include "flight_sw/guidance/crossing_law.hpp"

#include <algorithm>
#include <cmath>

#include "flight_sw/text.hpp"
#include "shelfcross/rotation.hpp"

namespace shelfcross::flight_sw {

bool heading_turning(const FlightConfig& config, double yaw_rate_radps) {
  return std::abs(yaw_rate_radps) > config.control.kp_psi * config.mission.approach.settle_psi_rad;
}

std::optional<std::string> crossing_refusal(const FlightConfig& config, CellIndex target, const PoseEstimate& pose,
                                            const CrossingGateInput& input) {
  const MissionParams& m = config.mission;
  const double psi = std::abs(pose.yaw_rad);
  const LineRoom room = line_room(config, target, pose);
  const double tol_y = room.tol_y_m, tol_z = room.tol_z_m;
  const Eigen::Vector3d d = crossing_direction_K(config.shelf, pose);
  // Identity first: a well centred crossing of the wrong cell is a collision.
  if (input.identity != CellIdentity::Confirmed) return std::string("target cell not identified (") + cell_identity_name(input.identity) + ")";
  // The pose is honest only if it is recent (frames may drop) and the vehicle was not moving
  // sideways when it was taken: the video latency hides up to V_y (latency + tau) of motion.
  if (input.pose_age_s > m.crossing.pose_fresh_s) return "last pose too old";
  if (input.still_for_s < m.approach.settle_s) return "still moving sideways";
  // The crossing flies on the heading it starts with: a heading that turned since the pose's
  // picture, or that a turn commanded now carries on turning, turns the line with it.
  if (input.heading_still_for_s < m.approach.settle_s || heading_turning(config, input.yaw_rate_cmd_radps)) {
    return "heading still turning";
  }
  if (psi > m.crossing.crossing_yaw_tolerance_rad) return "heading off the cell normal";
  if (d.x() <= 0.0 || room.offset_y_m() > tol_y) return "off-centre laterally";
  if (room.offset_z_m() > tol_z) return "off-centre vertically";
  // The height now, by the state record: the pose shows the vehicle a video latency ago
  // (0.1-0.35 s), and in that time a vehicle still settling vertically moves centimetres. The
  // crossing holds the cell centre's height by the state height from where the vehicle is now;
  // a vertical speed vz carries it about vz * vertical_lag_s further before the hold turns it.
  // Both heights must leave the vehicle crossing_margin_m clear of the beams.
  if (!input.height_above_cell_m) return std::string("cell height not measured against the state height");
  const double z_now = *input.height_above_cell_m, z_carried = z_now + input.vz_mps * m.crossing.vertical_lag_s;
  if (std::abs(z_now) > tol_z || std::abs(z_carried) > tol_z) return "off the cell's height by the state height";
  // The blind crossing: what the hover before it says the vehicle may wander (line_hold.hpp).
  const LineHoldForecast& f = input.line_hold;
  if (!f.measured) return std::string(kLineHoldNotMeasured);
  // Air that has just left the line no room is not trusted on the next quiet window: the
  // window is 2.5 s of a gust process of about 1 s correlation, a noisy estimate of the next
  // blind seconds, and a lull right after a rough window vouches for little. The calm since
  // must outlast the blind crossing (docs/method.md section 7, "A calm after rough air").
  const double blind_s = blind_crossing_s(config, -pose.p_FB_m().x());
  if (input.calm_for_s && *input.calm_for_s < blind_s) {
    return std::string(kLineCannotBeHeld) + " (calm for " + format_m(*input.calm_for_s) +
           " s since the air left no room, less than the blind crossing's " + format_m(blind_s) + " s)";
  }
  // Offset plus wander past the room less what the crossing keeps clear (the separation
  // minimum plus the forecast's own error, never less than crossing_margin_m): the air's doing
  // if even an arrival centred as the approach settles (within lateral_threshold_m across,
  // settle_z_m up) would leave the wander no room, and then the crossing is given up at the
  // last attempt; else the offset's, and the approach may mend it (a re-read at the last
  // attempt, as for any off-centre arrival).
  const double hold_tol_y = room.room_y_m - line_hold_keep_m(m, f.error_y_m);
  const double hold_tol_z = room.room_z_m - line_hold_keep_m(m, f.error_z_m);
  const auto verdict = [&](double offset_m, double wander_m, double tol_m, double settled_offset_m, const char* axis) {
    const char* why = settled_offset_m + wander_m > tol_m ? kLineCannotBeHeld : kOffCentreForTheWander;
    return std::string(why) + " " + axis + " (offset " + centimetres_text(offset_m) + " + wander " +
           centimetres_text(wander_m) + " > " + centimetres_text(tol_m) + ")";
  };
  if (room.offset_y_m() + f.y_m > hold_tol_y) {
    return verdict(room.offset_y_m(), f.y_m, hold_tol_y, config.control.lateral_threshold_m, "across") + air_text(f);
  }
  const double offset_z = std::max(room.offset_z_m(), std::abs(z_now));
  if (offset_z + f.z_m > hold_tol_z) return verdict(offset_z, f.z_m, hold_tol_z, m.approach.settle_z_m, "vertically");
  // A height hold that follows the range climbs over the shelf where nothing shows it in time
  // to back out (docs/method.md section 7, "What the watch can and cannot catch"): its forecast
  // climb must leave the same room above.
  const double climb = input.cell_centre_h_m ? range_hold_climb_m(config, target, *input.cell_centre_h_m) : 0.0;
  if (climb > 0.0 && z_now + climb + f.z_m > hold_tol_z) {
    return std::string(kLineCannotBeHeld) + " vertically (the height hold follows the range: a climb of " +
           centimetres_text(climb) + " from " + centimetres_text(z_now) + " + wander " + centimetres_text(f.z_m) +
           " > " + centimetres_text(hold_tol_z) + ")";
  }
  return std::nullopt;
}

// The records of the last kKeep_s (more than settle_s plus a pose's age) whose yaw lies within
// the band about each other: a record that widens the band past it ends the stretch before it.
void HeadingStretch::on_state(TimeNs t_ns, double yaw_rad) {
  constexpr double kKeep_s = 5.0;
  if (!yaw_.empty() && ns_to_seconds(t_ns - yaw_.back().first) > max_gap_s_) yaw_.clear();
  yaw_.emplace_back(t_ns, yaw_rad);
  const auto span = [&] {
    double lo = 0.0, hi = 0.0;
    for (const auto& r : yaw_) {
      const double d = wrap_pi(r.second - yaw_rad);
      lo = std::min(lo, d);
      hi = std::max(hi, d);
    }
    return hi - lo;
  };
  bool left = false;
  while (span() > band_rad_) {
    yaw_.pop_front();
    left = true;
  }
  if (left || yaw_.size() == 1) since_ns_ = yaw_.front().first;
  while (ns_to_seconds(t_ns - yaw_.front().first) > kKeep_s) yaw_.pop_front();
}

}  // namespace shelfcross::flight_sw
