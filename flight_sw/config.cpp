#include "flight_sw/config.hpp"

#include <stdexcept>

#include "config/strict_yaml.hpp"
#include "shelfcross/aruco_dictionaries.hpp"

namespace shelfcross::flight_sw {
namespace {

using config::Bounds;
using config::Map;

// Bounds with every field named (designated initializers that skip fields warn).
template <class T>
Bounds<T> at_least(T lo, bool exclusive = false) {
  return {.min = lo, .max = std::nullopt, .min_exclusive = exclusive, .max_exclusive = false};
}
template <class T>
Bounds<T> within(T lo, T hi) {
  return {.min = lo, .max = hi, .min_exclusive = false, .max_exclusive = false};
}
const Bounds<double> kPositive = at_least(0.0, true);
const Bounds<double> kNonNegative = at_least(0.0);
const Bounds<double> kFraction = within(0.0, 1.0);
const Bounds<int> kHue = within(0, 179);
const Bounds<int> kByte = within(0, 255);
const Bounds<int> kPercent = within(0, 100);

template <class T>
void opt(const Map& m, const char* key, T& value, const Bounds<T>& b = {}) {
  value = m.optional<T>(key, value, b);
}

Eigen::Vector3d vector3(const Map& m, const char* key, const Eigen::Vector3d& fallback,
                        const Bounds<double>& b = {}) {
  const std::vector<double> v =
      m.optional_list<double>(key, {fallback.x(), fallback.y(), fallback.z()}, b, 3);
  return {v[0], v[1], v[2]};
}

void read_shelf(const Map& m, KnownShelf& s) {
  s.column_pitch_m = m.required_list<double>("column_pitch_m", kPositive);
  s.row_pitch_m = m.required_list<double>("row_pitch_m", kPositive);
  if (s.column_pitch_m.empty()) m.fail("column_pitch_m", "needs at least one column");
  if (s.row_pitch_m.empty()) m.fail("row_pitch_m", "needs at least one level");
  opt(m, "post_thickness_m", s.post_thickness_m, kNonNegative);
  opt(m, "beam_thickness_m", s.beam_thickness_m, kNonNegative);
  opt(m, "depth_m", s.depth_m, kPositive);
  opt(m, "tag_size_m", s.tag_size_m, kPositive);
  opt(m, "tag_offset_m", s.tag_offset_m, kNonNegative);
  opt(m, "aruco_dictionary", s.aruco_dictionary);
  if (!find_aruco_dictionary(s.aruco_dictionary)) {
    m.fail("aruco_dictionary", "unknown ArUco dictionary '" + s.aruco_dictionary +
                                   "' (an OpenCV predefined name such as DICT_4X4_50)");
  }
  opt(m, "marker_size_m", s.marker_size_m, kPositive);
  for (double p : s.column_pitch_m) {
    if (p <= s.post_thickness_m) m.fail("column_pitch_m", "a column pitch is not wider than a post");
  }
  for (double p : s.row_pitch_m) {
    if (p <= s.beam_thickness_m) m.fail("row_pitch_m", "a row pitch is not taller than a beam");
  }
  m.finish();
}

void read_camera(const Map& m, CameraIntrinsics& c) {
  opt(m, "width_px", c.width_px, at_least(16));
  opt(m, "height_px", c.height_px, at_least(16));
  opt(m, "fx_px", c.fx_px, kPositive);
  opt(m, "fy_px", c.fy_px, kPositive);
  opt(m, "cx_px", c.cx_px);
  opt(m, "cy_px", c.cy_px);
  opt(m, "k1", c.k1);
  opt(m, "k2", c.k2);
  opt(m, "p1", c.p1);
  opt(m, "p2", c.p2);
  opt(m, "k3", c.k3);
  m.finish();
}

void read_mount(const Map& m, CameraMount& c) {
  opt(m, "pitch_rad", c.pitch_rad, within(-1.0, 1.0));
  c.p_BC_B_m = vector3(m, "p_BC_B_m", c.p_BC_B_m);
  m.finish();
}

void read_perception(const Map& m, PerceptionParams& p) {
  if (auto hsv = m.optional_map("tag_hsv")) {
    opt(*hsv, "hue_min", p.tag_hsv.hue_min, kHue);
    opt(*hsv, "hue_max", p.tag_hsv.hue_max, kHue);
    opt(*hsv, "sat_min", p.tag_hsv.sat_min, kByte);
    opt(*hsv, "sat_max", p.tag_hsv.sat_max, kByte);
    opt(*hsv, "val_min", p.tag_hsv.val_min, kByte);
    opt(*hsv, "val_max", p.tag_hsv.val_max, kByte);
    if (p.tag_hsv.sat_min > p.tag_hsv.sat_max) hsv->fail("sat_min", "sat_min > sat_max");
    if (p.tag_hsv.val_min > p.tag_hsv.val_max) hsv->fail("val_min", "val_min > val_max");
    hsv->finish();
  }
  if (m.has("pipeline")) {
    const std::string name = m.required<std::string>("pipeline");
    if (name == "fast") p.pipeline = PerceptionPipeline::fast;
    else if (name == "reference") p.pipeline = PerceptionPipeline::reference;
    else m.fail("pipeline", "unknown pipeline '" + name + "' (fast or reference)");
  }
  opt(m, "tag_seed_stride_px", p.tag_seed_stride_px, within(1, 16));
  opt(m, "min_tag_area_px", p.min_tag_area_px, kNonNegative);
  opt(m, "min_fill_ratio", p.min_fill_ratio, kFraction);
  opt(m, "max_aspect_ratio", p.max_aspect_ratio, at_least(1.0));
  opt(m, "area_ratio_threshold", p.area_ratio_threshold, kFraction);
  opt(m, "grid_orthogonality_tolerance_rad", p.grid_orthogonality_tolerance_rad,
      within(0.0, 0.8));
  opt(m, "marker_area_ratio_threshold", p.marker_area_ratio_threshold, kFraction);
  opt(m, "marker_min_agreeing_frames", p.marker_min_agreeing_frames, at_least(1));
  opt(m, "inventory_frames", p.inventory_frames, at_least(1));
  opt(m, "decide_max_damage_events", p.decide_max_damage_events, within(0, 1000));
  opt(m, "steer_max_damage_events", p.steer_max_damage_events, within(0, 1000));
  if (p.steer_max_damage_events < p.decide_max_damage_events) {
    m.fail("steer_max_damage_events", "must be >= decide_max_damage_events");
  }
  opt(m, "band_margin_px", p.band_margin_px, within(-1.0, 1000.0));
  opt(m, "roi_expand", p.roi_expand, within(0.0, 5.0));
  opt(m, "corner_gate", p.corner_gate, {.min = 0.0, .max = 1.0, .min_exclusive = true, .max_exclusive = false});
  if (p.inventory_frames < p.marker_min_agreeing_frames) {
    m.fail("inventory_frames", "must be >= marker_min_agreeing_frames");
  }
  m.finish();
}

void read_control(const Map& m, ControlGains& c) {
  opt(m, "forward_speed_mps", c.forward_speed_mps, kPositive);
  opt(m, "kp_z", c.kp_z, kNonNegative);
  opt(m, "ki_z", c.ki_z, kNonNegative);
  opt(m, "z_integral_limit_m_s", c.z_integral_limit_m_s, kNonNegative);
  opt(m, "z_speed_max_mps", c.z_speed_max_mps, kPositive);
  opt(m, "kp_psi", c.kp_psi, kNonNegative);
  opt(m, "ki_psi", c.ki_psi, kNonNegative);
  opt(m, "psi_integral_limit_rad_s", c.psi_integral_limit_rad_s, kNonNegative);
  opt(m, "yaw_rate_max_radps", c.yaw_rate_max_radps, kPositive);
  opt(m, "lateral_speed_mps", c.lateral_speed_mps, kNonNegative);
  opt(m, "psi_lateral_threshold_rad", c.psi_lateral_threshold_rad, kNonNegative);
  opt(m, "lateral_threshold_m", c.lateral_threshold_m, kNonNegative);
  opt(m, "viewpoint_kp", c.viewpoint_kp, kPositive);
  opt(m, "viewpoint_speed_max_mps", c.viewpoint_speed_max_mps, kPositive);
  opt(m, "viewpoint_yaw_kp", c.viewpoint_yaw_kp, kNonNegative);
  opt(m, "search_yaw_rate_radps", c.search_yaw_rate_radps, kNonNegative);
  opt(m, "back_off_speed_mps", c.back_off_speed_mps, kPositive);
  opt(m, "crossing_speed_mps", c.crossing_speed_mps, kPositive);
  opt(m, "max_control_dt_s", c.max_control_dt_s, kPositive);
  opt(m, "approach_cone_rad", c.approach_cone_rad, kPositive);
  opt(m, "commit_range_m", c.commit_range_m, kNonNegative);
  opt(m, "crossing_kp_z", c.crossing_kp_z, kNonNegative);
  opt(m, "crossing_z_speed_max_mps", c.crossing_z_speed_max_mps, kPositive);
  opt(m, "unsteered_hold_s", c.unsteered_hold_s, kNonNegative);
  m.finish();
}

void read_rc(const Map& m, RcConversion& r) {
  opt(m, "rc_per_mps_horizontal", r.rc_per_mps_horizontal, kPositive);
  opt(m, "rc_per_mps_vertical", r.rc_per_mps_vertical, kPositive);
  opt(m, "rc_per_radps_yaw", r.rc_per_radps_yaw, kPositive);
  opt(m, "rc_period_s", r.rc_period_s, kNonNegative);
  opt(m, "keepalive_s", r.keepalive_s, within(0.05, 10.0));
  m.finish();
}

void read_timeouts(const Map& m, Timeouts& t) {
  const std::pair<const char*, double*> seconds[] = {{"command_reply_s", &t.command_reply_s},
                            {"takeoff_reply_s", &t.takeoff_reply_s},
                            {"land_reply_s", &t.land_reply_s},
                            {"video_start_s", &t.video_start_s},
                            {"find_shelf_s", &t.find_shelf_s},
                            {"go_to_viewpoint_s", &t.go_to_viewpoint_s},
                            {"take_inventory_s", &t.take_inventory_s},
                            {"approach_s", &t.approach_s},
                            {"target_lost_s", &t.target_lost_s},
                            {"back_off_s", &t.back_off_s},
                            {"video_hover_s", &t.video_hover_s},
                            {"video_land_s", &t.video_land_s},
                            {"mission_s", &t.mission_s}};
  for (const auto& [key, value] : seconds) {
    opt(m, key, *value, kPositive);
  }
  opt(m, "command_retries", t.command_retries, within(0, 20));
  opt(m, "command_gap_s", t.command_gap_s, kNonNegative);
  if (t.video_land_s <= t.video_hover_s) m.fail("video_land_s", "must exceed video_hover_s");
  m.finish();
}

void read_mission(const Map& m, MissionParams& p) {
  opt(m, "low_battery_pct", p.low_battery_pct, kPercent);
  opt(m, "takeoff_min_battery_pct", p.takeoff_min_battery_pct, kPercent);
  opt(m, "airborne_height_m", p.airborne_height_m, kPositive);
  opt(m, "viewpoint_margin", p.viewpoint.viewpoint_margin, within(0.0, 2.0));
  opt(m, "viewpoint_position_tolerance_m", p.viewpoint.viewpoint_position_tolerance_m, kPositive);
  opt(m, "viewpoint_yaw_tolerance_rad", p.viewpoint.viewpoint_yaw_tolerance_rad, kPositive);
  opt(m, "viewpoint_settle_frames", p.viewpoint.viewpoint_settle_frames, at_least(1));
  opt(m, "viewpoint_lost_s", p.viewpoint.viewpoint_lost_s, kPositive);
  p.vehicle_size_m = vector3(m, "vehicle_size_m", p.vehicle_size_m, kPositive);
  opt(m, "crossing_margin_m", p.crossing_margin_m, kNonNegative);
  opt(m, "crossing_yaw_tolerance_rad", p.crossing.crossing_yaw_tolerance_rad, kPositive);
  opt(m, "crossing_attempts", p.crossing.crossing_attempts, at_least(1));
  opt(m, "cross_range_max_m", p.approach.cross_range_max_m, kPositive);
  opt(m, "beyond_distance_m", p.crossing.beyond_distance_m, kNonNegative);
  opt(m, "edge_margin_px", p.approach.edge_margin_px, kNonNegative);
  opt(m, "settle_s", p.approach.settle_s, kNonNegative);
  opt(m, "settle_z_m", p.approach.settle_z_m, kPositive);
  opt(m, "settle_psi_rad", p.approach.settle_psi_rad, kPositive);
  opt(m, "settle_heading_band_rad", p.approach.settle_heading_band_rad, kPositive);
  opt(m, "settle_hold_s", p.approach.settle_hold_s, kNonNegative);
  opt(m, "pose_fresh_s", p.crossing.pose_fresh_s, kPositive);
  opt(m, "pose_jump_m", p.target.pose_jump_m, kPositive);
  opt(m, "pose_jump_rad", p.target.pose_jump_rad, kPositive);
  opt(m, "pose_jump_window_s", p.target.pose_jump_window_s, kNonNegative);
  opt(m, "coast_s", p.approach.coast_s, kNonNegative);
  opt(m, "level_check", p.target.level_check);
  opt(m, "identity_continuity_s", p.target.identity_continuity_s, kNonNegative);
  opt(m, "stop_distance_m", p.crossing.stop_distance_m, kNonNegative);
  opt(m, "min_beyond_distance_m", p.crossing.min_beyond_distance_m, kNonNegative);
  opt(m, "identity_confirm_s", p.target.identity_confirm_s, kPositive);
  opt(m, "identity_rereads", p.target.identity_rereads, within(0, 100));
  opt(m, "vertical_lag_s", p.crossing.vertical_lag_s, kNonNegative);
  opt(m, "height_hold_range_blend", p.crossing.height_hold_range_blend, kFraction);
  opt(m, "height_hold_time_constant_s", p.crossing.height_hold_time_constant_s, within(0.05, 10.0));
  opt(m, "line_hold_window_s", p.line_hold.line_hold_window_s, within(0.1, 10.0));
  opt(m, "line_hold_min_span_s", p.line_hold.line_hold_min_span_s, within(0.05, 10.0));
  opt(m, "calm_wait_s", p.line_hold.calm_wait_s, kNonNegative);
  opt(m, "give_up_clearance_m", p.line_hold.give_up_clearance_m, kNonNegative);
  opt(m, "separation_min_m", p.line_hold.separation_min_m, within(0.0, 0.1));
  opt(m, "trim_drift", p.line_hold.trim_drift);
  if (p.line_hold.line_hold_min_span_s > p.line_hold.line_hold_window_s) m.fail("line_hold_min_span_s", "must not exceed line_hold_window_s");
  m.finish();
}

void read_layout(const Map& m, WarehouseLayout& l) {
  opt(m, "shelf_count", l.shelf_count, within(1, 64));
  opt(m, "shelf_spacing_m", l.shelf_spacing_m, kNonNegative);
  if (l.shelf_count > 1 && l.shelf_spacing_m <= 0.0) {
    m.fail("shelf_count", "more than one shelf needs shelf_spacing_m (front face to front face)");
  }
  m.finish();
}

void read_strategy(const Map& m, StrategyParams& p) {
  std::string mode = strategy_name(p.mode);
  opt(m, "mode", mode);
  if (const auto s = parse_strategy(mode)) {
    p.mode = *s;
  } else {
    m.fail("mode", "unknown strategy '" + mode + "' (through_cells, over_tops or around_ends)");
  }
  opt(m, "top_clearance_m", p.top_clearance_m, kNonNegative);
  opt(m, "end_clearance_m", p.end_clearance_m, kNonNegative);
  opt(m, "transfer_speed_mps", p.transfer_speed_mps, kPositive);
  opt(m, "transfer_kp", p.transfer_kp, kPositive);
  opt(m, "transfer_yaw_kp", p.transfer_yaw_kp, kNonNegative);
  opt(m, "waypoint_tolerance_m", p.waypoint_tolerance_m, kPositive);
  opt(m, "transfer_leg_s", p.transfer_leg_s, kPositive);
  m.finish();
}

FlightConfig read(const config::Document& doc) {
  FlightConfig c;
  const Map root = doc.root();
  read_shelf(root.map("shelf"), c.shelf);
  if (auto m = root.optional_map("camera")) read_camera(*m, c.camera);
  if (auto m = root.optional_map("mount")) read_mount(*m, c.mount);
  if (auto m = root.optional_map("perception")) read_perception(*m, c.perception);
  if (auto m = root.optional_map("control")) read_control(*m, c.control);
  if (auto m = root.optional_map("rc")) read_rc(*m, c.rc);
  if (auto m = root.optional_map("timeouts")) read_timeouts(*m, c.timeouts);
  if (auto m = root.optional_map("mission")) read_mission(*m, c.mission);
  if (auto m = root.optional_map("layout")) read_layout(*m, c.layout);
  if (auto m = root.optional_map("strategy")) read_strategy(*m, c.strategy);
  root.finish();
  try {
    validate_flight_config(c);  // the cross-field checks not tied to one key
  } catch (const std::invalid_argument& e) {
    throw config::ConfigError(root.file(), root.line(), e.what());
  }
  return c;
}

void require(bool ok, const std::string& what) {
  if (!ok) throw std::invalid_argument("flight configuration: " + what);
}

}  // namespace

const char* strategy_name(Strategy s) {
  switch (s) {
    case Strategy::through_cells: return "through_cells";
    case Strategy::over_tops: return "over_tops";
    case Strategy::around_ends: return "around_ends";
  }
  return "?";
}

std::optional<Strategy> parse_strategy(const std::string& name) {
  for (Strategy s : {Strategy::through_cells, Strategy::over_tops, Strategy::around_ends}) {
    if (name == strategy_name(s)) return s;
  }
  return std::nullopt;
}

FlightConfig load_flight_config(const std::string& path) {
  return read(config::Document::from_file(path));
}

FlightConfig parse_flight_config(const std::string& yaml_text, const std::string& name) {
  return read(config::Document::from_string(yaml_text, name));
}

void validate_flight_config(const FlightConfig& c) {
  const KnownShelf& s = c.shelf;
  require(!s.column_pitch_m.empty() && !s.row_pitch_m.empty(),
          "shelf needs at least one column and one level");
  for (double p : s.column_pitch_m) require(p > s.post_thickness_m, "column pitch <= post");
  for (double p : s.row_pitch_m) require(p > s.beam_thickness_m, "row pitch <= beam");
  require(s.tag_size_m > 0.0 && s.marker_size_m > 0.0 && s.depth_m > 0.0,
          "tag, marker sizes and shelf depth must be positive");
  require(find_aruco_dictionary(s.aruco_dictionary) != nullptr,
          "unknown ArUco dictionary '" + s.aruco_dictionary + "'");
  const CameraIntrinsics& k = c.camera;
  require(k.width_px >= 16 && k.height_px >= 16 && k.fx_px > 0.0 && k.fy_px > 0.0,
          "camera size and focal lengths must be positive");
  const HsvRange& h = c.perception.tag_hsv;
  require(h.hue_min >= 0 && h.hue_min <= 179 && h.hue_max >= 0 && h.hue_max <= 179,
          "tag hue outside 0..179");
  require(h.sat_min <= h.sat_max && h.val_min <= h.val_max, "tag HSV range empty");
  require(c.perception.marker_min_agreeing_frames >= 1 &&
              c.perception.inventory_frames >= c.perception.marker_min_agreeing_frames,
          "inventory_frames must be >= marker_min_agreeing_frames >= 1");
  require(c.perception.decide_max_damage_events >= 0 &&
              c.perception.steer_max_damage_events >= c.perception.decide_max_damage_events,
          "steer_max_damage_events must be >= decide_max_damage_events >= 0");
  require(c.perception.tag_seed_stride_px >= 1 && c.perception.tag_seed_stride_px <= 16,
          "tag_seed_stride_px outside 1..16");
  require(c.timeouts.video_land_s > c.timeouts.video_hover_s,
          "video_land_s must exceed video_hover_s");
  require(c.rc.rc_per_mps_horizontal > 0.0 && c.rc.rc_per_mps_vertical > 0.0 &&
              c.rc.rc_per_radps_yaw > 0.0,
          "rc conversion gains must be positive");
  require(c.control.crossing_speed_mps > 0.0 && c.control.forward_speed_mps > 0.0,
          "forward and crossing speeds must be positive");
  require(c.mission.vehicle_size_m.minCoeff() > 0.0, "vehicle size must be positive");
  const MissionParams& mp = c.mission;
  require(mp.line_hold.line_hold_min_span_s >= 0.05 && mp.line_hold.line_hold_min_span_s <= mp.line_hold.line_hold_window_s &&
              mp.line_hold.line_hold_window_s <= 10.0 && mp.line_hold.calm_wait_s >= 0.0 && mp.line_hold.give_up_clearance_m >= 0.0,
          "mission: 0.05 <= line_hold_min_span_s <= line_hold_window_s <= 10, calm_wait_s and "
          "give_up_clearance_m >= 0");
  require(mp.line_hold.separation_min_m >= 0.0 && mp.line_hold.separation_min_m <= 0.1,
          "mission: separation_min_m outside 0..0.1");
  require(mp.crossing.height_hold_range_blend >= 0.0 && mp.crossing.height_hold_range_blend <= 1.0 &&
              mp.crossing.height_hold_time_constant_s >= 0.05 && mp.crossing.height_hold_time_constant_s <= 10.0,
          "mission: height_hold_range_blend outside 0..1 or height_hold_time_constant_s outside 0.05..10");
  require(c.layout.shelf_count >= 1 && c.layout.shelf_count <= 64, "layout.shelf_count must be 1..64");
  require(c.layout.shelf_count == 1 || c.layout.shelf_spacing_m > s.depth_m + c.mission.vehicle_size_m.x(),
          "layout.shelf_spacing_m must exceed the shelf depth plus the vehicle length");
  const StrategyParams& st = c.strategy;
  require(st.transfer_speed_mps > 0.0 && st.transfer_kp > 0.0 && st.waypoint_tolerance_m > 0.0 &&
              st.transfer_leg_s > 0.0 && st.top_clearance_m >= 0.0 && st.end_clearance_m >= 0.0 &&
              st.transfer_yaw_kp >= 0.0,
          "strategy: speeds, gains, tolerance and leg time positive, clearances >= 0");
}

}  // namespace shelfcross::flight_sw
