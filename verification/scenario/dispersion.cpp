#include "verification/scenario/dispersion.hpp"

#include <cmath>
#include <numbers>
#include <stdexcept>
#include <utility>

#include "shelfcross/rotation.hpp"
#include "verification/scenario/scenario.hpp"
#include "verification/scenario/senses_dispersion.hpp"

namespace shelfcross::verification {

double* senses_dispersed_field(plant::SensesParams& senses, const std::string& name) {
  const std::pair<const char*, double*> fields[] = {
      {"vps_noise_mps", &senses.vps.noise_mps},
      {"vps_bias_stddev_mps", &senses.vps.bias_stddev_mps},
      {"vps_min_range_m", &senses.vps.min_range_m},
      {"vps_floor_texture", &senses.vps.texture.floor},
      {"vps_box_texture", &senses.vps.texture.box},
      {"vps_bar_texture", &senses.vps.texture.bar},
      {"tof_noise_m", &senses.height.tof_noise_m},
      {"height_noise_m", &senses.height.height_noise_m},
      {"baro_noise_m", &senses.height.baro_noise_m},
      {"baro_drift_m_per_sqrt_s", &senses.height.baro_drift_m_per_sqrt_s},
      {"height_hold_range_blend", &senses.height_hold.range_blend},
      {"height_hold_range_below_m", &senses.height_hold.range_below_m},
      {"height_hold_time_constant_s", &senses.height_hold.time_constant_s}};
  for (const auto& [n, field] : fields) {
    if (name == n) return field;
  }
  return nullptr;
}

bool is_senses_dispersion(const std::string& name) {
  plant::SensesParams senses;
  if (senses_dispersed_field(senses, name) != nullptr) return true;
  return name == "camera_readout_s" || name == "ground_effect_coeff" || name == "ceiling_effect_coeff";
}

Scenario without_senses(Scenario scenario) {
  scenario.senses = {};
  scenario.readout_s = 0.0;
  scenario.vehicle.surface_effects = {};
  std::erase_if(scenario.dispersions, [](const auto& d) { return is_senses_dispersion(d.first); });
  return scenario;
}

namespace {

/// The senses' dispersed keys (dispersion_table.hpp), each replacing its key.
void apply_senses_draws(const DrawnValues& drawn, plant::SensesParams& senses) {
  for (const auto& [name, value] : drawn) {
    if (double* field = senses_dispersed_field(senses, name)) *field = value;
  }
}

}  // namespace

RunSetup disperse(const Scenario& nominal, std::uint64_t run_seed) {
  return disperse(nominal, run_seed, draw_dispersions(nominal.dispersions, run_seed));
}

RunSetup disperse(const Scenario& nominal, std::uint64_t run_seed, const DrawnValues& drawn) {
  if (drawn.size() != nominal.dispersions.size()) {
    throw std::invalid_argument("disperse: " + std::to_string(drawn.size()) + " drawn values for " +
                                std::to_string(nominal.dispersions.size()) + " dispersed parameters");
  }
  for (const auto& [name, value] : drawn) {
    if (!nominal.dispersions.count(name)) throw std::invalid_argument("disperse: '" + name + "' is not dispersed");
    for (const DispersionParameter& p : dispersion_parameters()) {
      if (name == p.name && !(value >= p.lowest && value <= p.highest)) {
        throw std::invalid_argument("disperse: " + name + " = " + std::to_string(value) + " is outside its range");
      }
    }
  }
  RunSetup setup;
  setup.seed = run_seed;
  setup.drawn = drawn;
  auto s = std::make_shared<Scenario>(nominal);
  setup.believed_camera = nominal.camera;
  const auto has = [&](const char* name) { return setup.drawn.count(name) > 0; };
  const auto value = [&](const char* name) { return setup.drawn.at(name); };

  // Start: in shelf 0's frame S (x_S into the shelf, y_S left), the start sits at x_S = -d.
  if (!s->warehouse.shelves.empty() && (has("start_distance_m") || has("start_lateral_m"))) {
    const Eigen::Isometry3d X_WS = shelf_pose_W(s->warehouse.shelves.front());
    Eigen::Vector3d p_S = X_WS.inverse() * s->start.p_WB_m;
    if (has("start_distance_m")) p_S.x() = -value("start_distance_m");
    if (has("start_lateral_m")) p_S.y() += value("start_lateral_m");
    s->start.p_WB_m = X_WS * p_S;
  }
  if (has("start_yaw_rad")) s->start.yaw_rad = wrap_pi(s->start.yaw_rad + value("start_yaw_rad"));
  if (has("light_scale")) {
    s->warehouse.lighting.ambient *= value("light_scale");
    s->warehouse.lighting.directional *= value("light_scale");
  }
  // Uneven light: the ambient part alone scaled (less ambient, harder shading and shadows
  // across the shelf), and the directional light turned about z_W to the drawn azimuth,
  // keeping its elevation: direction (cos a, sin a) |d_xy|, d_z.
  if (has("ambient_scale")) s->warehouse.lighting.ambient = std::min(1.0, s->warehouse.lighting.ambient * value("ambient_scale"));
  if (has("light_azimuth_rad")) {
    Eigen::Vector3d& d = s->warehouse.lighting.direction_W;
    const double horizontal = std::max(d.head<2>().norm(), 0.1 * std::abs(d.z()));
    d = {horizontal * std::cos(value("light_azimuth_rad")), horizontal * std::sin(value("light_azimuth_rad")), d.z()};
  }
  // The shelf behind (shelf 1 of a scenario with two shelves or more): its front face placed
  // this far behind shelf 0's front face along shelf 0's normal x_S, and moved sideways along
  // y_S by the lateral draw (added to where the file puts it). Its heading is shelf 0's.
  if (s->warehouse.shelves.size() >= 2 && (has("shelf_behind_distance_m") || has("shelf_behind_lateral_m"))) {
    const Eigen::Isometry3d X_WS = shelf_pose_W(s->warehouse.shelves.front());
    ShelfSpec& behind = s->warehouse.shelves[1];
    Eigen::Vector3d p_S = X_WS.inverse() * behind.origin_W_m;
    if (has("shelf_behind_distance_m")) p_S.x() = value("shelf_behind_distance_m");
    if (has("shelf_behind_lateral_m")) p_S.y() += value("shelf_behind_lateral_m");
    p_S.z() = 0.0;
    behind.origin_W_m = X_WS * p_S;
    behind.yaw_rad = s->warehouse.shelves.front().yaw_rad;
  }
  if (has("box_fill_ratio")) {
    RandomStream stream(run_seed, StreamId::box_placement);
    const int dictionary = aruco_dictionary_size(s->warehouse.aruco_dictionary).value_or(0);
    std::vector<int> free_ids;
    for (int id = 0; id < dictionary; ++id) free_ids.push_back(id);
    for (ShelfSpec& shelf : s->warehouse.shelves) {
      shelf.boxes = place_random_boxes(s->warehouse, shelf, value("box_fill_ratio"), free_ids, stream);
      for (const BoxPlacement& b : shelf.boxes) std::erase(free_ids, b.marker_id);
    }
  }
  if (has("camera_focal_error_rel")) {
    setup.believed_camera.fx_px *= 1.0 + value("camera_focal_error_rel");
    setup.believed_camera.fy_px *= 1.0 + value("camera_focal_error_rel");
  }
  if (has("camera_cx_error_px")) setup.believed_camera.cx_px += value("camera_cx_error_px");
  if (has("camera_cy_error_px")) setup.believed_camera.cy_px += value("camera_cy_error_px");
  if (has("camera_readout_s")) s->readout_s = std::min(value("camera_readout_s"), 1.0 / s->frame_rate_hz);
  plant::AutopilotParams& ap = s->autopilot;
  if (has("rc_gain_scale")) {
    ap.rc_horizontal_mps_at_100 *= value("rc_gain_scale");
    ap.rc_vertical_mps_at_100 *= value("rc_gain_scale");
    ap.rc_yaw_radps_at_100 *= value("rc_gain_scale");
  }
  if (has("velocity_time_constant_s")) ap.velocity_time_constant_s = value("velocity_time_constant_s");
  if (has("vertical_time_constant_s")) ap.vertical_time_constant_s = value("vertical_time_constant_s");
  if (has("yaw_time_constant_s")) ap.yaw_time_constant_s = value("yaw_time_constant_s");
  if (has("mass_scale")) s->vehicle.mass_kg *= value("mass_scale");
  if (has("ground_effect_coeff")) s->vehicle.surface_effects.ground_coeff = value("ground_effect_coeff");
  if (has("ceiling_effect_coeff")) s->vehicle.surface_effects.ceiling_coeff = value("ceiling_effect_coeff");
  if (has("wind_speed_mps") || has("wind_direction_rad")) {
    const Eigen::Vector3d& w = s->wind.steady_W_mps;
    const double speed = has("wind_speed_mps") ? value("wind_speed_mps") : w.head<2>().norm();
    const double direction = has("wind_direction_rad") ? value("wind_direction_rad") : std::atan2(w.y(), w.x());
    s->wind.steady_W_mps = {speed * std::cos(direction), speed * std::sin(direction), w.z()};
  }
  if (has("gust_stddev_mps")) s->wind.gust_stddev_mps = value("gust_stddev_mps");
  LinkSettings& link = s->cosim.link;
  if (has("video_latency_mean_s")) link.video_latency_mean_s = value("video_latency_mean_s");
  if (has("frame_drop_probability")) link.frame_drop_probability = value("frame_drop_probability");
  if (has("command_latency_mean_s")) link.command_latency_mean_s = value("command_latency_mean_s");
  if (has("command_loss_probability")) link.command_loss_probability = value("command_loss_probability");
  if (has("compute_latency_s")) link.compute_latency_s = value("compute_latency_s");
  if (has("compute_latency_quantile")) link.compute_latency_s = measured_step_latency_s(value("compute_latency_quantile"));
  if (has("video_datagram_loss")) link.video_datagram_loss = value("video_datagram_loss");
  if (has("state_loss")) link.state_loss = value("state_loss");
  if (has("reply_loss")) link.reply_loss = value("reply_loss");
  if (has("not_joystick_probability")) link.not_joystick_probability = value("not_joystick_probability");
  if (has("video_stall_start_s")) link.spells.video_stall_start_s = value("video_stall_start_s");
  if (has("video_stall_duration_s")) link.spells.video_stall_duration_s = value("video_stall_duration_s");
  if (has("burst_loss")) link.spells.burst_loss = value("burst_loss");
  if (has("burst_mean_s")) link.spells.burst_mean_s = value("burst_mean_s");
  if (has("burst_interval_s")) link.spells.burst_interval_s = value("burst_interval_s");
  if (has("outage_interval_s")) link.spells.outage_interval_s = value("outage_interval_s");
  if (has("outage_start_s")) link.spells.outage_start_s = value("outage_start_s");
  if (has("outage_duration_s")) link.spells.outage_duration_s = value("outage_duration_s");
  apply_senses_draws(setup.drawn, s->senses);
  setup.scenario = std::move(s);
  return setup;
}

}  // namespace shelfcross::verification
