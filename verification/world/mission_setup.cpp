#include "verification/world/mission_setup.hpp"

#include <algorithm>
#include <cmath>
#include <optional>

#include "plant/collision.hpp"
#include "shelfcross/rotation.hpp"

namespace shelfcross::verification {

namespace {

constexpr double kGiveUpReserve_s = 10.0;  // flight_config_for: the mission's time budget

/// The row's spacing when every shelf has shelf 0's geometry and heading and stands the same
/// distance behind the previous one along shelf 0's normal (1 mm tolerance); nullopt otherwise.
std::optional<double> row_spacing_m(const Scenario& sc) {
  const auto& shelves = sc.warehouse.shelves;
  if (shelves.size() < 2) return std::nullopt;
  const ShelfSpec& s0 = shelves[0];
  const Eigen::Isometry3d X_SW = shelf_pose_W(s0).inverse();
  const double spacing = (X_SW * shelves[1].origin_W_m).x();
  if (!(spacing > s0.depth_m)) return std::nullopt;
  for (size_t i = 1; i < shelves.size(); ++i) {
    const ShelfSpec& s = shelves[i];
    const Eigen::Vector3d p_S = X_SW * s.origin_W_m;
    if (s.column_pitch_m != s0.column_pitch_m || s.row_pitch_m != s0.row_pitch_m ||
        s.post_thickness_m != s0.post_thickness_m || s.beam_thickness_m != s0.beam_thickness_m ||
        s.depth_m != s0.depth_m || s.base_height_m != s0.base_height_m ||
        std::abs(wrap_pi(s.yaw_rad - s0.yaw_rad)) > 1e-9 || std::abs(p_S.x() - spacing * static_cast<double>(i)) > 1e-3 ||
        std::abs(p_S.y()) > 1e-3) {
      return std::nullopt;
    }
  }
  return spacing;
}
}  // namespace

int mission_shelf_count(const Scenario& sc) {
  return row_spacing_m(sc) ? static_cast<int>(sc.warehouse.shelves.size()) : 1;
}

double mission_shelf_spacing_m(const Scenario& sc) { return row_spacing_m(sc).value_or(0.0); }

flight_sw::FlightConfig flight_config_for(const Scenario& sc, const CameraIntrinsics& believed_camera) {
  const ShelfSpec& shelf = sc.warehouse.shelves.at(0);
  flight_sw::FlightConfig c;
  c.shelf.column_pitch_m = shelf.column_pitch_m;
  c.shelf.row_pitch_m = shelf.row_pitch_m;
  c.shelf.post_thickness_m = shelf.post_thickness_m;
  c.shelf.beam_thickness_m = shelf.beam_thickness_m;
  c.shelf.depth_m = shelf.depth_m;
  c.shelf.tag_size_m = sc.warehouse.tag_size_m;
  // Tags are cards on the outer face of the bars (warehouse.hpp).
  c.shelf.tag_offset_m = 0.5 * std::max(shelf.post_thickness_m, shelf.beam_thickness_m) +
                         plant::CollisionWorld::kTagThickness_m;
  c.shelf.aruco_dictionary = sc.warehouse.aruco_dictionary;
  c.shelf.marker_size_m = sc.warehouse.marker_size_m;
  c.camera = believed_camera;
  c.mount = sc.camera_mount;
  c.mission.target.level_check = sc.cosim.pilot.level_check;
  c.mission.vehicle_size_m = sc.vehicle.size_m;
  // The run's time limit is the mission's budget: the operator gives the flight software that
  // less what a give-up takes to finish safely (backing out from the closest hold to
  // give_up_clearance_m, 2.5 s, and landing, about 4 s; or finishing a crossing, 4 s, then
  // landing beyond the shelf), so that a mission out of time ends as a named safe abort rather
  // than still flying at the limit (a lost `land` on top of that is what the co-simulation's
  // landing grace covers: RunContext::limit_ns). Runs of 20 s or less (tests and studies of a
  // mission's first seconds: take-off alone takes 4 s) keep the default budget; the limit cuts
  // them.
  if (sc.cosim.timeout_s > 2.0 * kGiveUpReserve_s) c.timeouts.mission_s = sc.cosim.timeout_s - kGiveUpReserve_s;
  c.layout.shelf_count = mission_shelf_count(sc);
  c.layout.shelf_spacing_m = mission_shelf_spacing_m(sc);
  if (const auto strategy = flight_sw::parse_strategy(sc.cosim.strategy)) {
    c.strategy.mode = *strategy;
  } else {
    throw std::invalid_argument("unknown strategy '" + sc.cosim.strategy + "'");
  }
  // The operator sets the tag hue window around the tags' colour (OpenCV hue: 0..180).
  const Rgb& tag = sc.warehouse.tag_colour;
  const double mx = std::max({tag.r, tag.g, tag.b}), mn = std::min({tag.r, tag.g, tag.b});
  if (mx - mn > 1e-6) {
    double hue_deg = mx == tag.r ? 60.0 * std::fmod((tag.g - tag.b) / (mx - mn) + 6.0, 6.0)
                     : mx == tag.g ? 60.0 * ((tag.b - tag.r) / (mx - mn) + 2.0)
                                   : 60.0 * ((tag.r - tag.g) / (mx - mn) + 4.0);
    const int h = static_cast<int>(std::lround(hue_deg / 2.0)) % 180;
    const int half_width = (c.perception.tag_hsv.hue_max - c.perception.tag_hsv.hue_min) / 2;
    c.perception.tag_hsv.hue_min = (h - half_width + 180) % 180;
    c.perception.tag_hsv.hue_max = (h + half_width) % 180;
  }
  flight_sw::validate_flight_config(c);
  return c;
}

std::set<InventoryEntry> true_inventory(const Scenario& sc) {
  std::set<InventoryEntry> truth;
  for (int i = 0; i < mission_shelf_count(sc); ++i) {
    for (const BoxPlacement& b : sc.warehouse.shelves.at(static_cast<size_t>(i)).boxes) {
      truth.insert({b.marker_id, i, b.level, b.column});
    }
  }
  return truth;
}

render::RenderOptions render_options_for(const Scenario& s) {
  render::RenderOptions o;
  o.noise_stddev = s.cosim.render_noise_stddev;
  o.motion_blur_samples = s.cosim.motion_blur_samples;
  // A rolling shutter shifts the picture's rows against the readout's middle pose by up to
  // f * omega * readout / 2 for a turn at omega: the margin allows a turn at the autopilot's
  // largest yaw rate, for the longest readout the scenario can draw (one renderer serves every
  // run of a campaign).
  double readout_s = s.readout_s;
  if (const auto d = s.dispersions.find("camera_readout_s"); d != s.dispersions.end())
    readout_s = std::max(readout_s, std::min(d->second.highest(), 1.0 / s.frame_rate_hz));
  o.rolling_shutter_margin_px =
      std::ceil(0.5 * std::max(s.camera.fx_px, s.camera.fy_px) * s.autopilot.loops.max_yaw_rate_radps * readout_s);
  return o;
}

}  // namespace shelfcross::verification
