// The emulator's settings checked, and its report written: what `shelfcross tello-sim`
// reads and prints, apart from the simulation itself (tello_emulator.cpp).

#include "verification/world/tello_emulator_settings.hpp"

#include <cmath>
#include <set>
#include <sstream>
#include <stdexcept>

#include <nlohmann/json.hpp>

namespace shelfcross::verification {

namespace {

void check_probability(double p, const char* name) {
  if (!(p >= 0.0 && p <= 1.0)) throw std::invalid_argument(std::string(name) + " must be a probability in 0..1");
}
void check_delay(double ms, const char* name) {
  if (!(ms >= 0.0 && ms <= 600'000.0)) throw std::invalid_argument(std::string(name) + " must be 0..600000 ms");
}

}  // namespace

bool emulator_applies_dispersion(const std::string& name) {
  static const std::set<std::string> not_applied{
      "camera_focal_error_rel", "camera_cx_error_px",       "camera_cy_error_px",
      "video_latency_mean_s",   "frame_drop_probability",   "command_latency_mean_s",
      "command_loss_probability", "compute_latency_s",      "compute_latency_quantile",
      "video_datagram_loss",    "state_loss",               "reply_loss",
      "not_joystick_probability", "video_stall_start_s",    "video_stall_duration_s",
      "burst_loss",             "burst_mean_s",             "burst_interval_s",
      "outage_interval_s",      "outage_start_s",           "outage_duration_s"};
  return not_applied.count(name) == 0;
}

void validate_emulator_config(const EmulatorConfig& c) {
  const EmulatorFaults& f = c.faults;
  check_probability(f.commands.loss, "loss on commands");
  check_probability(f.replies.loss, "loss on replies");
  check_probability(f.state.loss, "loss on state");
  check_probability(f.video.loss, "loss on video");
  check_delay(f.commands.delay_ms, "delay on commands");
  check_delay(f.replies.delay_ms, "delay on replies");
  check_delay(f.state.delay_ms, "delay on state");
  check_delay(f.video.delay_ms, "delay on video");
  check_delay(f.late_reply_ms, "late reply delay");
  check_probability(f.late_replies, "late replies");
  check_probability(f.video_frame_loss, "loss of video frames");
  check_probability(f.commands.duplicate, "duplicate commands");
  check_probability(f.replies.duplicate, "duplicate replies");
  check_probability(f.state.duplicate, "duplicate state records");
  check_delay(f.commands.jitter_ms, "jitter on commands");
  check_delay(f.replies.jitter_ms, "jitter on replies");
  check_delay(f.state.jitter_ms, "jitter on state");
  check_delay(f.video.jitter_ms, "jitter on video");
  check_probability(f.not_joystick, "not-joystick");
  check_probability(f.no_valid_imu, "no-valid-imu");
  if (f.video_stall_start_s && !(*f.video_stall_start_s >= 0.0 && f.video_stall_duration_s > 0.0 &&
                                 std::isfinite(*f.video_stall_start_s) && std::isfinite(f.video_stall_duration_s))) {
    throw std::invalid_argument("video stall needs a start T >= 0 and a duration D > 0 (s)");
  }
  check_probability(f.bursts.bad_loss, "loss in a burst");
  if (!(f.bursts.bad_mean_s >= 0.0 && f.bursts.bad_mean_s <= 60.0)) throw std::invalid_argument("burst length must be 0..60 s");
  if (!(f.bursts.good_mean_s >= 0.1 && f.bursts.good_mean_s <= 3600.0)) {
    throw std::invalid_argument("time between bursts must be 0.1..3600 s");
  }
  const LinkOutages& o = f.outages;
  if (!(o.interval_mean_s == 0.0 || (o.interval_mean_s >= 1.0 && o.interval_mean_s <= 3600.0))) {
    throw std::invalid_argument("time between outages must be 0 (none) or 1..3600 s");
  }
  if (!(o.min_s >= 0.01 && o.max_s >= o.min_s && o.max_s <= 60.0)) {
    throw std::invalid_argument("outage lengths need 0.01 <= MIN <= MAX <= 60 s");
  }
  if (o.start_s && !(*o.start_s >= 0.0 && *o.start_s <= 3600.0 && o.duration_s > 0.0 && o.duration_s <= 60.0)) {
    throw std::invalid_argument("an outage needs a start T in 0..3600 and a duration D in (0, 60] (s)");
  }
  if (!(c.linger_s >= 0.0 && std::isfinite(c.linger_s))) throw std::invalid_argument("linger must be >= 0 s");
  if (c.client_state_port == 0 || c.client_video_port == 0) throw std::invalid_argument("client ports must be 1..65535");
  if (c.key_interval_frames < 0 || c.key_interval_frames > 600) throw std::invalid_argument("key interval must be 0..600 frames");
  if (c.slices_per_frame < 1 || c.slices_per_frame > 45) throw std::invalid_argument("slices per frame must be 1..45");
  if (c.max_datagram_bytes < 16) throw std::invalid_argument("max datagram size must be >= 16 bytes");
  tello::parse_ipv4(c.bind_ip);  // throws std::invalid_argument naming the text
}
std::string emulator_report_json(const EmulatorReport& r) {
  using nlohmann::json;
  json inventory = json::array();
  for (const auto& [id, shelf, level, column] : r.inventory_truth) {
    inventory.push_back({{"id", id}, {"shelf", shelf}, {"level", level}, {"column", column}});
  }
  const EmulatorCounters& c = r.counters;
  json j{{"end_reason", r.end_reason},
         {"detail", r.detail},
         {"elapsed_s", r.elapsed_s},
         {"flight_time_s", r.flight_time_s},
         {"flew", r.flew},
         {"landed", r.landed},
         {"inventory_truth", inventory},
         {"start", {{"p_W_m", {r.start_p_W_m.x(), r.start_p_W_m.y(), r.start_p_W_m.z()}}, {"yaw_rad", r.start_yaw_rad}}},
         {"seed", r.seed},
         {"dispersed", r.dispersed},
         {"counters",
          {{"commands_received", c.commands_received}, {"commands_dropped", c.commands_dropped}, {"commands_duplicated", c.commands_duplicated},
           {"commands_malformed", c.commands_malformed}, {"commands_delivered", c.commands_delivered},
           {"injected_errors", c.injected_errors}, {"replies_sent", c.replies_sent},
           {"replies_dropped", c.replies_dropped}, {"replies_late", c.replies_late},
           {"replies_duplicated", c.replies_duplicated}, {"state_sent", c.state_sent},
           {"state_dropped", c.state_dropped}, {"state_duplicated", c.state_duplicated}, {"frames_captured", c.frames_captured},
           {"frames_sent", c.frames_sent}, {"frames_dropped_busy", c.frames_dropped_busy},
           {"frames_dropped_late", c.frames_dropped_late}, {"frames_stalled", c.frames_stalled}, {"frames_lost", c.frames_lost},
           {"key_frames", c.key_frames}, {"video_datagrams_sent", c.video_datagrams_sent},
           {"video_datagrams_dropped", c.video_datagrams_dropped}, {"video_bytes_sent", c.video_bytes_sent},
           {"send_errors", c.send_errors}}}};
  json drawn = json::object();
  for (const auto& [name, value] : r.drawn) drawn[name] = {{"value", value}, {"applied", emulator_applies_dispersion(name)}};
  j["dispersions"] = drawn;
  write_world_truth(j, r.truth);
  return j.dump(2);
}

std::string emulator_report_text(const EmulatorReport& r) {
  std::ostringstream o;
  const EmulatorCounters& c = r.counters;
  const WorldTruth& t = r.truth;
  o << "tello-sim: " << r.end_reason << (r.detail.empty() ? "" : " (" + r.detail + ")") << " after " << r.elapsed_s
    << " s; flight time " << r.flight_time_s << " s, path " << t.path_length_m << " m, "
    << (r.landed ? "landed" : "airborne") << "\n";
  o << "contact: " << (t.contact ? t.contact->element.name : std::string("none")) << "\n";
  o << "crossed: ";
  if (t.crossed) {
    o << "shelf 0 level " << t.crossed->level << " column " << t.crossed->column << ", entry offset y "
      << t.entry_offset_y_m.value_or(NAN) << " m z " << t.entry_offset_z_m.value_or(NAN) << " m";
  } else {
    o << "no cell";
  }
  if (t.min_clearance_m) o << "; min clearance " << *t.min_clearance_m << " m";
  o << "\ninventory truth (id level column):";
  for (const auto& [id, shelf, level, column] : r.inventory_truth) o << " " << id << "@" << level << "," << column;
  o << "\ncommands received " << c.commands_received << " dropped " << c.commands_dropped << " malformed "
    << c.commands_malformed << " injected errors " << c.injected_errors << "; replies sent " << c.replies_sent
    << " dropped " << c.replies_dropped << " late " << c.replies_late << " duplicated " << c.replies_duplicated
    << "; state sent " << c.state_sent << " dropped " << c.state_dropped << "\n";
  o << "video frames captured " << c.frames_captured << " sent " << c.frames_sent << " (key " << c.key_frames
    << ") dropped busy " << c.frames_dropped_busy << " late " << c.frames_dropped_late << " stalled "
    << c.frames_stalled << " lost " << c.frames_lost << "; datagrams sent " << c.video_datagrams_sent << " dropped " << c.video_datagrams_dropped
    << ", " << c.video_bytes_sent << " bytes; send errors " << c.send_errors << "\n";
  return o.str();
}
}  // namespace shelfcross::verification
