#include "verification/scenario/scenario.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <map>
#include <numbers>
#include <set>
#include <type_traits>
#include <utility>
#include <vector>

#include <yaml-cpp/yaml.h>

#include "config/strict_yaml.hpp"
#include "flight_sw/config.hpp"
#include "plant/collision.hpp"
#include "shelfcross/aruco_dictionaries.hpp"
#include "verification/scenario/dispersion_table.hpp"
#include "verification/scenario/scenario_yaml.hpp"
#include "verification/scenario/senses_yaml.hpp"

namespace shelfcross::verification {
namespace {

using config::ConfigError;

// Each visit_* function below lists the keys of one section once: their names, ranges and
// cross-checks, walked by the Reader and the Writer of scenario_yaml.hpp.

using namespace scenario_yaml;

// ---- The sections ----

std::string metres(double x) { return format_double(x) + " m"; }

/// State shared by the sections while reading one scenario.
struct Context {
  Scenario* scenario = nullptr;
  int dictionary_size = 0;
  std::set<int> marker_ids;  // across all shelves
  struct RandomFill {
    size_t shelf;
    double fill_ratio;
    std::uint64_t seed;
    int line;
  };
  std::vector<RandomFill> random_fills;
  size_t shelf_index = 0;
};

template <class V>
void visit_box(V& v, BoxPlacement& b, const ShelfSpec& s, std::set<std::pair<int, int>>& cells,
               Context& ctx) {
  const Warehouse& w = ctx.scenario->warehouse;
  const int nrows = static_cast<int>(s.row_pitch_m.size());
  const int ncols = static_cast<int>(s.column_pitch_m.size());
  v.field("level", b.level, at_least(1), Need::required);
  v.check("level", b.level <= nrows,
          "level " + std::to_string(b.level) + " does not exist: the shelf has " +
              std::to_string(nrows) + " levels");
  v.field("column", b.column, at_least(1), Need::required);
  v.check("column", b.column <= ncols,
          "column " + std::to_string(b.column) + " does not exist: the shelf has " +
              std::to_string(ncols) + " columns");
  v.field("marker_id", b.marker_id, at_least(0), Need::required);
  v.check("marker_id", b.marker_id < ctx.dictionary_size,
          "marker ID " + std::to_string(b.marker_id) + " is beyond " + w.aruco_dictionary +
              " (IDs 0.." + std::to_string(ctx.dictionary_size - 1) + ")");
  v.check("level", cells.insert({b.level, b.column}).second,
          "two boxes in the cell at level " + std::to_string(b.level) + ", column " +
              std::to_string(b.column));
  v.check("marker_id", ctx.marker_ids.insert(b.marker_id).second,
          "marker ID " + std::to_string(b.marker_id) + " is used by another box");
  if (b.level < 1 || b.column < 1 || b.level > nrows || b.column > ncols) return;  // refused above
  const double clear_width = s.column_pitch_m[static_cast<size_t>(b.column - 1)] - s.post_thickness_m;
  const double clear_height = cell_clear_height_m(s, b.level);
  v.check("column", w.box_size_m.y() <= clear_width,
          "a box " + metres(w.box_size_m.y()) + " wide does not fit the clear width " +
              metres(clear_width) + " of column " + std::to_string(b.column));
  v.check("level", w.box_size_m.z() <= clear_height,
          "a box " + metres(w.box_size_m.z()) + " high does not fit the clear height " +
              metres(clear_height) + " of level " + std::to_string(b.level));
}

template <class V>
void visit_shelf(V& v, ShelfSpec& s, Context& ctx) {
  const Warehouse& w = ctx.scenario->warehouse;
  const size_t index = ctx.shelf_index++;
  const Bounds<double> kYaw = between(-std::numbers::pi, std::numbers::pi);
  v.field("name", s.name);
  v.vec3("origin_W_m", s.origin_W_m, kAnyFinite, Need::required);
  v.check("origin_W_m", s.origin_W_m.z() == 0.0, "a shelf stands on the floor: z must be 0");
  v.field("yaw_rad", s.yaw_rad, kYaw);
  v.field("post_thickness_m", s.post_thickness_m, kPositive);
  v.field("beam_thickness_m", s.beam_thickness_m, kPositive);
  v.field("deck_thickness_m", s.deck_thickness_m, between(0.0, 0.1));
  v.list("column_pitch_m", s.column_pitch_m, kPositive, Need::required);
  v.list("row_pitch_m", s.row_pitch_m, kPositive, Need::required);
  for (const char* key : {"column_pitch_m", "row_pitch_m"}) {
    const std::vector<double>& pitches =
        std::string(key) == "column_pitch_m" ? s.column_pitch_m : s.row_pitch_m;
    const double bar = std::string(key) == "column_pitch_m" ? s.post_thickness_m : s.beam_thickness_m + s.deck_thickness_m;
    v.check(key, !pitches.empty() && pitches.size() <= 64, "a shelf has 1 to 64 columns and rows");
    for (double p : pitches) {
      v.check(key, p > bar, "pitch " + metres(p) + " leaves no opening between bars " +
                                metres(bar) + " thick" + (s.deck_thickness_m > 0.0 && std::string(key) == "row_pitch_m"
                                                              ? " (beam and deck)" : ""));
      v.check(key, w.tag_size_m < p,
              "tags of " + metres(w.tag_size_m) + " are larger than the cell pitch " + metres(p) +
                  " (adjacent tags would overlap)");
    }
  }
  v.field("base_height_m", s.base_height_m, kNonNegative);
  v.check("base_height_m", s.base_height_m > 0.5 * s.beam_thickness_m,
          "the lowest beam would reach below the floor");
  v.field("depth_m", s.depth_m, kPositive);
  v.check("depth_m", s.depth_m > std::max(s.post_thickness_m, s.beam_thickness_m),
          "the front and back faces would overlap");
  v.check("depth_m", w.box_size_m.x() <= s.depth_m - s.post_thickness_m,
          "boxes " + metres(w.box_size_m.x()) + " deep do not fit between the front and back "
          "posts of a shelf " + metres(s.depth_m) + " deep");
  // Inside the arena: the four corners of the footprint and the top.
  {
    const Eigen::Isometry3d X_WS = shelf_pose_W(s);
    const double bar = 0.5 * std::max(s.post_thickness_m, s.beam_thickness_m);
    const double y_left = post_y_S_m(s, 0) + bar, y_right = post_y_S_m(s, static_cast<int>(s.column_pitch_m.size())) - bar;
    const double top = beam_z_S_m(s, static_cast<int>(s.row_pitch_m.size())) + 0.5 * s.beam_thickness_m;
    bool inside = top <= w.arena_max_W_m.z();
    for (double x : {-bar, s.depth_m + bar}) {
      for (double y : {y_left, y_right}) {
        const Eigen::Vector3d c = X_WS * Eigen::Vector3d(x, y, 0.0);
        inside = inside && c.x() >= w.arena_min_W_m.x() && c.x() <= w.arena_max_W_m.x() &&
                 c.y() >= w.arena_min_W_m.y() && c.y() <= w.arena_max_W_m.y();
      }
    }
    v.check("origin_W_m", inside, "the shelf does not fit inside the arena");
  }
  std::set<std::pair<int, int>> cells;
  v.items("boxes", s.boxes,
          [&](auto& bv, BoxPlacement& b) { visit_box(bv, b, s, cells, ctx); }, Need::optional,
          true);
  if constexpr (V::kReading) {
    if (v.map().has("random_boxes")) {
      v.check("random_boxes", !v.map().has("boxes"), "give either 'boxes' or 'random_boxes', not both");
      const config::Map r = v.map().map("random_boxes");
      const double fill = r.required<double>("fill_ratio", kUnit);
      const auto seed = r.required<std::uint64_t>("seed");
      r.finish();
      ctx.random_fills.push_back({index, fill, seed, v.map().line_of("random_boxes")});
    } else {
      v.map().optional_map("random_boxes");  // marks it as read (absent)
    }
  }
}

/// Random placements (Reader only, after every explicit box is known): in each shelf with
/// `random_boxes`, round(fill_ratio * cells the box fits) distinct cells and as many marker IDs
/// unused anywhere else, both drawn without replacement (place_random_boxes, seeded stream).
void resolve_random_boxes(Context& ctx, const std::string& file) {
  Warehouse& w = ctx.scenario->warehouse;
  for (const Context::RandomFill& f : ctx.random_fills) {
    ShelfSpec& s = w.shelves[f.shelf];
    std::vector<int> free_ids;
    for (int id = 0; id < ctx.dictionary_size; ++id) {
      if (!ctx.marker_ids.count(id)) free_ids.push_back(id);
    }
    RandomStream stream(f.seed, StreamId::box_placement);
    try {
      s.boxes = place_random_boxes(w, s, f.fill_ratio, free_ids, stream);
    } catch (const std::invalid_argument& e) {
      throw ConfigError(file, f.line, std::string("'random_boxes': ") + e.what() + " (" + w.aruco_dictionary + ")");
    }
    for (const BoxPlacement& b : s.boxes) ctx.marker_ids.insert(b.marker_id);
  }
}

template <class V>
void visit_warehouse(V& v, Warehouse& w, Context& ctx) {
  v.section("arena", [&](auto& a) {
    a.vec3("min_W_m", w.arena_min_W_m);
    a.vec3("max_W_m", w.arena_max_W_m);
    a.check("min_W_m", w.arena_min_W_m.z() == 0.0, "the floor is z = 0: the arena's min z must be 0");
    a.check("max_W_m", (w.arena_max_W_m.array() > w.arena_min_W_m.array()).all(),
            "every coordinate of max_W_m must exceed that of min_W_m");
  });
  v.section("colours", [&](auto& c) {
    c.colour("floor", w.floor_colour);
    c.colour("wall", w.wall_colour);
    c.colour("bar", w.bar_colour);
    c.colour("tag", w.tag_colour);
    c.colour("box", w.box_colour);
  });
  v.section("lighting", [&](auto& l) {
    l.field("ambient", w.lighting.ambient, kUnit);
    l.field("directional", w.lighting.directional, kUnit);
    l.vec3("direction_W", w.lighting.direction_W);
    l.check("direction_W", w.lighting.direction_W.norm() > 0.0, "the light direction must not be zero");
  });
  v.section("tags", [&](auto& t) { t.field("size_m", w.tag_size_m, kPositive); });
  v.section("boxes", [&](auto& b) {
    b.vec3("size_m", w.box_size_m, kPositive);
    b.field("aruco_dictionary", w.aruco_dictionary);
    const auto size = aruco_dictionary_size(w.aruco_dictionary);
    b.check("aruco_dictionary", size.has_value(),
            "unknown ArUco dictionary '" + w.aruco_dictionary + "' (OpenCV names: DICT_4X4_50, ...)");
    ctx.dictionary_size = size.value_or(0);
    b.field("marker_size_m", w.marker_size_m, kPositive);
    b.check("marker_size_m", w.marker_size_m <= std::min(w.box_size_m.y(), w.box_size_m.z()),
            "a marker of " + metres(w.marker_size_m) + " is larger than the box face (" +
                metres(w.box_size_m.y()) + " x " + metres(w.box_size_m.z()) + ")");
  });
  if (!ctx.dictionary_size) ctx.dictionary_size = aruco_dictionary_size(w.aruco_dictionary).value_or(0);
  v.items("shelves", w.shelves, [&](auto& sv, ShelfSpec& s) { visit_shelf(sv, s, ctx); },
          Need::required, false);
  v.check("shelves", !w.shelves.empty(), "a warehouse has at least one shelf");
}

template <class V>
void visit_camera(V& v, Scenario& s) {
  CameraIntrinsics& c = s.camera;
  v.field("width_px", c.width_px, between(1, 16384));
  v.field("height_px", c.height_px, between(1, 16384));
  v.field("fx_px", c.fx_px, kPositive);
  v.field("fy_px", c.fy_px, kPositive);
  v.field("cx_px", c.cx_px, kNonNegative);
  v.check("cx_px", c.cx_px <= c.width_px, "the principal point must lie in the image");
  v.field("cy_px", c.cy_px, kNonNegative);
  v.check("cy_px", c.cy_px <= c.height_px, "the principal point must lie in the image");
  v.field("k1", c.k1);
  v.field("k2", c.k2);
  v.field("p1", c.p1);
  v.field("p2", c.p2);
  v.field("k3", c.k3);
  v.field("frame_rate_hz", s.frame_rate_hz, between(1.0, 240.0));
  v.field("readout_s", s.readout_s, between(0.0, 0.1));
  v.check("readout_s", s.readout_s * s.frame_rate_hz <= 1.0, "a readout must fit in one frame period");
  v.section("mount", [&](auto& m) {
    m.field("pitch_rad", s.camera_mount.pitch_rad,
            between(-0.5 * std::numbers::pi, 0.5 * std::numbers::pi));
    m.vec3("p_BC_B_m", s.camera_mount.p_BC_B_m, between(-1.0, 1.0));
  });
}

template <class V>
void visit_vehicle(V& v, plant::VehicleParams& p) {
  v.field("mass_kg", p.mass_kg, kPositive);
  v.field("gravity_mps2", p.gravity_mps2, kPositive);
  v.vec3("size_m", p.size_m, kPositive);
  v.vec3("inertia_kgm2", p.inertia_kgm2, kNonNegative);
  v.field("arm_x_m", p.arm_x_m, kNonNegative);
  v.field("arm_y_m", p.arm_y_m, kNonNegative);
  v.field("rotor_inertia_kgm2", p.rotor_inertia_kgm2, kNonNegative);
  v.field("thrust_coeff_N_per_radps2", p.thrust_coeff_N_per_radps2, kNonNegative);
  v.field("torque_coeff_Nm_per_radps2", p.torque_coeff_Nm_per_radps2, kNonNegative);
  v.field("rotor_speed_max_radps", p.rotor_speed_max_radps, kNonNegative);
  v.field("rotor_speed_min_radps", p.rotor_speed_min_radps, kNonNegative);
  v.check("rotor_speed_min_radps", p.rotor_speed_min_radps <= p.rotor_speed_max_radps,
          "must not exceed rotor_speed_max_radps");
  v.field("motor_time_constant_s", p.motor_time_constant_s, kPositive);
  v.vec3("linear_drag_Ns_per_m", p.linear_drag_Ns_per_m, kNonNegative);
  v.vec3("quadratic_drag_Ns2_per_m2", p.quadratic_drag_Ns2_per_m2, kNonNegative);
  v.section("switches", [&](auto& w) {
    w.field("motor_dynamics", p.switches.motor_dynamics);
    w.field("gyroscopic", p.switches.gyroscopic);
    w.field("linear_drag", p.switches.linear_drag);
    w.field("quadratic_drag", p.switches.quadratic_drag);
    w.field("wind", p.switches.wind);
  });
  v.section("surface_effects", [&](auto& e) {
    plant::SurfaceEffectParams& f = p.surface_effects;
    e.field("rotor_radius_m", f.rotor_radius_m, above(0.0));
    e.check("rotor_radius_m", f.rotor_radius_m <= 0.2, "a rotor radius above 0.2 m is not a Tello-class rotor");
    e.field("ground_coeff", f.ground_coeff, between(0.0, 2.0));
    e.field("ceiling_coeff", f.ceiling_coeff, between(0.0, 2.0));
    e.field("ceiling_range_radii", f.ceiling_range_radii, between(0.25, 4.0));
  });
}

template <class V>
void visit_wind(V& v, plant::WindParams& p) {
  v.vec3("steady_W_mps", p.steady_W_mps, between(-50.0, 50.0));
  v.field("gust_stddev_mps", p.gust_stddev_mps, between(0.0, 50.0));
  v.field("gust_time_constant_s", p.gust_time_constant_s, kPositive);
}

template <class V>
void visit_autopilot(V& v, plant::AutopilotParams& p) {
  Bounds<double> kTilt = between(0.0, 0.5 * std::numbers::pi);  // exclusive at both ends
  kTilt.min_exclusive = kTilt.max_exclusive = true;
  v.field("rate_hz", p.rate_hz, between(1.0, 100000.0));
  v.field("rc_horizontal_mps_at_100", p.rc_horizontal_mps_at_100, kPositive);
  v.field("rc_vertical_mps_at_100", p.rc_vertical_mps_at_100, kPositive);
  v.field("rc_yaw_radps_at_100", p.rc_yaw_radps_at_100, kPositive);
  v.field("fast_mode_speed_factor", p.fast_mode_speed_factor, at_least(1.0));
  v.field("velocity_time_constant_s", p.velocity_time_constant_s, kPositive);
  v.field("vertical_time_constant_s", p.vertical_time_constant_s, kPositive);
  v.field("yaw_time_constant_s", p.yaw_time_constant_s, kPositive);
  v.field("tilt_limit_slow_rad", p.tilt_limit_slow_rad, kTilt);
  v.field("tilt_limit_fast_rad", p.tilt_limit_fast_rad, kTilt);
  v.check("tilt_limit_fast_rad", p.tilt_limit_fast_rad >= p.tilt_limit_slow_rad,
          "must not be below tilt_limit_slow_rad");
  v.field("takeoff_height_m", p.takeoff_height_m, kPositive);
  v.field("takeoff_reply_delay_s", p.takeoff_reply_delay_s, kNonNegative);
  v.field("land_speed_mps", p.land_speed_mps, kPositive);
  v.field("watchdog_s", p.watchdog_s, kPositive);
}

template <class V>
void visit_start(V& v, Scenario& s) {
  StartState& st = s.start;
  v.vec3("p_WB_m", st.p_WB_m, kAnyFinite, Need::required);
  v.field("yaw_rad", st.yaw_rad, between(-std::numbers::pi, std::numbers::pi));
  v.field("landed", st.landed);
  if constexpr (V::kReading) {
    const double half_height = 0.5 * s.vehicle.size_m.z();
    if (st.landed) {
      v.check("p_WB_m", st.p_WB_m.z() == 0.0, "a landed start is on the floor: z must be 0");
    } else {
      v.check("p_WB_m", st.p_WB_m.z() > half_height,
              "a hovering start must be above the floor: z > " + metres(half_height));
    }
    // The vehicle must start clear of the walls and of every shelf part (the floor it may touch).
    Eigen::Isometry3d X_WB = Eigen::Isometry3d::Identity();
    X_WB.linear() = Eigen::AngleAxisd(st.yaw_rad, Eigen::Vector3d::UnitZ()).toRotationMatrix();
    X_WB.translation() = st.p_WB_m;
    if (st.landed) X_WB.translation().z() = half_height;
    const plant::CollisionWorld world(s.warehouse, s.vehicle.size_m, 0.0);
    const auto hits = world.overlaps(X_WB, 0, plant::FloorContacts::ignore);
    v.check("p_WB_m", hits.empty(),
            hits.empty() ? "" : "the vehicle would start inside the " + hits.front().element.name);
  }
}

template <class V>
void visit_link(V& v, LinkSettings& l) {
  v.field("video_latency_mean_s", l.video_latency_mean_s, between(0.0, 5.0));
  v.field("video_latency_jitter_s", l.video_latency_jitter_s, between(0.0, 1.0));
  v.field("frame_drop_probability", l.frame_drop_probability, between(0.0, 0.9));
  v.field("state_latency_mean_s", l.state_latency_mean_s, between(0.0, 2.0));
  v.field("state_latency_jitter_s", l.state_latency_jitter_s, between(0.0, 1.0));
  v.field("command_latency_mean_s", l.command_latency_mean_s, between(0.0, 2.0));
  v.field("command_latency_jitter_s", l.command_latency_jitter_s, between(0.0, 1.0));
  v.field("command_loss_probability", l.command_loss_probability, between(0.0, 0.9));
  v.field("compute_latency_s", l.compute_latency_s, between(0.0, 1.0));
  v.field("model", l.model);
  v.check("model", l.model == "sdk" || l.model == "ideal", "unknown link model '" + l.model + "' (sdk or ideal)");
  v.field("video_datagram_loss", l.video_datagram_loss, between(0.0, 0.9));
  v.field("state_loss", l.state_loss, between(0.0, 0.9));
  v.field("reply_loss", l.reply_loss, between(0.0, 0.9));
  v.field("duplicate_probability", l.duplicate_probability, between(0.0, 0.9));
  v.field("late_reply_probability", l.late_reply_probability, between(0.0, 1.0));
  v.field("late_reply_s", l.late_reply_s, between(0.0, 600.0));
  v.field("not_joystick_probability", l.not_joystick_probability, between(0.0, 1.0));
  v.field("no_valid_imu_probability", l.no_valid_imu_probability, between(0.0, 1.0));
  v.field("video_stall_start_s", l.spells.video_stall_start_s, between(-1.0, 3600.0));
  v.field("video_stall_duration_s", l.spells.video_stall_duration_s, between(0.0, 3600.0));
  v.field("burst_loss", l.spells.burst_loss, between(0.0, 1.0));
  v.field("burst_mean_s", l.spells.burst_mean_s, between(0.0, 60.0));
  v.field("burst_interval_s", l.spells.burst_interval_s, between(0.1, 3600.0));
  v.field("outage_interval_s", l.spells.outage_interval_s, between(0.0, 3600.0));
  v.check("outage_interval_s", l.spells.outage_interval_s == 0.0 || l.spells.outage_interval_s >= 1.0,
          "0 (no outages at random) or at least 1 s");
  v.field("outage_min_s", l.spells.outage_min_s, between(0.01, 60.0));
  v.field("outage_max_s", l.spells.outage_max_s, between(0.01, 60.0));
  v.check("outage_max_s", l.spells.outage_max_s >= l.spells.outage_min_s, "must not be below outage_min_s");
  v.field("outage_start_s", l.spells.outage_start_s, between(-1.0, 3600.0));
  v.field("outage_duration_s", l.spells.outage_duration_s, between(0.0, 60.0));
  v.field("video_slices", l.video_slices, between(1, 45));
  v.field("key_interval_frames", l.key_interval_frames, between(0, 600));
  v.field("lost_command", l.lost_command);
  v.field("lost_command_count", l.lost_command_count, between(0, 1000));
}

template <class V>
void visit_cosim(V& v, CosimSettings& c) {
  v.field("state_rate_hz", c.state_rate_hz, between(1.0, 100.0));
  v.field("fsw_tick_hz", c.fsw_tick_hz, between(1.0, 1000.0));
  v.field("timeout_s", c.timeout_s, between(1.0, 3600.0));
  v.field("trajectory_rate_hz", c.trajectory_rate_hz, between(1.0, 1000.0));
  v.field("vehicle_margin_m", c.vehicle_margin_m, between(0.0, 0.5));
  v.field("battery_start_pct", c.battery_start_pct, between(1.0, 100.0));
  v.field("endurance_s", c.endurance_s, kPositive);
  v.field("render_noise_stddev", c.render_noise_stddev, between(0.0, 50.0));
  v.field("motion_blur_samples", c.motion_blur_samples, between(1, 16));
  v.field("settling_fraction", c.settling_fraction, between(0.0, 1.0));
  v.field("settling_floor_z_m", c.settling_floor_z_m, kNonNegative);
  v.field("settling_floor_yaw_rad", c.settling_floor_yaw_rad, kNonNegative);
  v.field("settling_floor_y_m", c.settling_floor_y_m, kNonNegative);
  v.field("near_miss_m", c.near_miss_m, between(0.0, 0.5));
  v.section("link", [&](auto& l) { visit_link(l, c.link); });
  v.section("pilot", [&](auto& p) { p.field("stop_rc_repeats", c.pilot.stop_rc_repeats, between(0, 10));
    p.field("level_check", c.pilot.level_check);
  });
  v.field("inject_flight_software_exception_s", c.inject_flight_software_exception_s, between(-1.0, 3600.0));
  v.field("inject_crash_s", c.inject_crash_s, between(-1.0, 3600.0));
  v.field("inject_hang_s", c.inject_hang_s, between(-1.0, 3600.0));
  v.field("strategy", c.strategy);
  v.check("strategy", flight_sw::parse_strategy(c.strategy).has_value(),
          "unknown strategy '" + c.strategy + "' (through_cells, over_tops or around_ends)");
}

bool valid_id(const std::string& name) {
  if (name.empty() || name.size() > 64) return false;
  return std::all_of(name.begin(), name.end(), [](char c) {
    return std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '-' || c == '.';
  });
}

constexpr int kFormatVersion = 1;

template <class V>
void visit_scenario(V& v, Scenario& s, Context& ctx) {
  int version = kFormatVersion;
  v.field("version", version, between(kFormatVersion, kFormatVersion));
  v.field("name", s.name, {}, Need::required);
  v.check("name", valid_id(s.name), "a name is 1 to 64 letters, digits, '_', '-' or '.'");
  v.section("warehouse", [&](auto& w) { visit_warehouse(w, s.warehouse, ctx); }, Need::required);
  if constexpr (V::kReading) resolve_random_boxes(ctx, v.map().file());
  v.section("camera", [&](auto& c) { visit_camera(c, s); });
  v.section("vehicle", [&](auto& p) { visit_vehicle(p, s.vehicle); });
  v.section("wind", [&](auto& p) { visit_wind(p, s.wind); });
  v.section("autopilot", [&](auto& p) { visit_autopilot(p, s.autopilot); });
  v.section("senses", [&](auto& p) { visit_senses(p, s.senses); });
  // The start is checked against the vehicle and the warehouse, so it comes last.
  v.section("start", [&](auto& p) { visit_start(p, s); }, Need::required);
  v.section("cosim", [&](auto& c) { visit_cosim(c, s.cosim); });
  v.distributions("dispersions", s.dispersions);
  v.check("dispersions", s.warehouse.shelves.size() >= 2 || (!s.dispersions.contains("shelf_behind_distance_m") &&
                                                             !s.dispersions.contains("shelf_behind_lateral_m")),
          "shelf_behind_distance_m and shelf_behind_lateral_m move shelf 1: the warehouse needs two shelves");
}

Scenario read(const config::Document& doc) {
  const config::Map root = doc.root();
  Scenario s;
  Context ctx;
  ctx.scenario = &s;
  Reader reader(root);
  visit_scenario(reader, s, ctx);
  root.finish();
  return s;
}

}  // namespace

std::vector<BoxPlacement> place_random_boxes(const Warehouse& w, const ShelfSpec& s, double fill_ratio,
                                             std::vector<int> free_ids, RandomStream& stream) {
  std::vector<std::pair<int, int>> cells;
  for (int level = 1; level <= static_cast<int>(s.row_pitch_m.size()); ++level) {
    for (int column = 1; column <= static_cast<int>(s.column_pitch_m.size()); ++column) {
      const bool fits = w.box_size_m.y() <= s.column_pitch_m[static_cast<size_t>(column - 1)] - s.post_thickness_m &&
                        w.box_size_m.z() <= cell_clear_height_m(s, level);
      if (fits) cells.emplace_back(level, column);
    }
  }
  const auto count = static_cast<size_t>(std::llround(fill_ratio * static_cast<double>(cells.size())));
  if (count > free_ids.size()) {
    throw std::invalid_argument(std::to_string(count) + " boxes need more unused marker IDs than are left (" +
                                std::to_string(free_ids.size()) + ")");
  }
  // The first `count` items of a seeded Fisher-Yates shuffle: cells, then IDs.
  const auto shuffle_prefix = [&](auto& v) {
    for (size_t i = 0; i < count; ++i) std::swap(v[i], v[i + stream.below(v.size() - i)]);
  };
  shuffle_prefix(cells);
  shuffle_prefix(free_ids);
  std::vector<BoxPlacement> boxes;
  for (size_t i = 0; i < count; ++i) boxes.push_back({cells[i].first, cells[i].second, free_ids[i]});
  // Listed bottom to top, left to right (IDs stay with their drawn cells).
  std::sort(boxes.begin(), boxes.end(), [](const BoxPlacement& a, const BoxPlacement& b) {
    return std::pair(a.level, a.column) < std::pair(b.level, b.column);
  });
  return boxes;
}

std::optional<int> aruco_dictionary_size(const std::string& name) {
  const ArucoDictionaryEntry* e = find_aruco_dictionary(name);
  if (!e) return std::nullopt;
  return e->size;
}

Scenario load_scenario(const std::string& path) { return read(config::Document::from_file(path)); }

Scenario parse_scenario(const std::string& yaml_text, const std::string& name_for_errors) {
  return read(config::Document::from_string(yaml_text, name_for_errors));
}

std::string write_scenario(const Scenario& scenario) {
  Scenario s = scenario;  // the visitors take mutable references; the writer only reads them
  Context ctx;
  ctx.scenario = &s;
  std::string out =
      "# shelfcross scenario, fully resolved: every key written out, defaults included.\n"
      "# Format: scenarios/README.md\n";
  Writer writer(out, 0);
  visit_scenario(writer, s, ctx);
  return out;
}

}  // namespace shelfcross::verification
