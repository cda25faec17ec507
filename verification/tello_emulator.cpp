#include "verification/tello_emulator.hpp"

#include <poll.h>

#include <algorithm>
#include <cassert>
#include <chrono>
#include <cmath>
#include <set>
#include <sstream>
#include <stdexcept>
#include <variant>

#include <nlohmann/json.hpp>
#include <opencv2/core/mat.hpp>

#include "render/ground_truth.hpp"
#include "render/renderer.hpp"
#include "sdk/command.hpp"
#include "sdk/video_framing.hpp"
#include "verification/campaign.hpp"
#include "verification/cosim.hpp"
#include "verification/h264_encoder.hpp"
#include "verification/run_metrics_json.hpp"
#include "verification/strict_json.hpp"
#include "verification/tello_state_format.hpp"

namespace shelfcross::verification {
namespace {

TimeNs ms_to_ns(double ms) { return static_cast<TimeNs>(std::llround(ms * 1e6)); }

/// mean + N(0, sigma) truncated at +-3 sigma, never below 0, in ns. No draw when sigma is 0,
/// so a channel without jitter draws nothing from its jitter stream.
TimeNs jittered_ms(RandomStream& stream, double mean_ms, double sigma_ms) {
  double ms = mean_ms;
  if (sigma_ms > 0.0) ms += sigma_ms * std::clamp(stream.normal(), -3.0, 3.0);
  return ms_to_ns(std::max(0.0, ms));
}

/// A command datagram the firmware may see: 1..max bytes of printable ASCII, optionally
/// ended by "\r\n" or "\n" (the firmware trims whitespace).
bool well_formed(const std::string& bytes, std::size_t max_bytes) {
  if (bytes.empty() || bytes.size() > max_bytes) return false;
  return std::all_of(bytes.begin(), bytes.end(), [](char ch) {
    const auto c = static_cast<unsigned char>(ch);
    return (c >= 0x20 && c < 0x7f) || c == '\r' || c == '\n';
  });
}

/// Manoeuvres a real Tello refuses with "error Not joystick" / "error No valid imu". Land and
/// emergency are never refused here, so a client can always end a flight.
bool refusable(const std::string& text) {
  const auto parsed = sdk::parse(text);
  const auto* c = std::get_if<sdk::Command>(&parsed);
  return c && sdk::is_manoeuvre(c->verb) && c->verb != sdk::Verb::land;
}

bool is_manoeuvre_text(const std::string& text) {
  const auto parsed = sdk::parse(text);
  const auto* c = std::get_if<sdk::Command>(&parsed);
  return c && sdk::is_manoeuvre(c->verb);
}

void check_probability(double p, const char* name) {
  if (!(p >= 0.0 && p <= 1.0)) throw std::invalid_argument(std::string(name) + " must be a probability in 0..1");
}
void check_delay(double ms, const char* name) {
  if (!(ms >= 0.0 && ms <= 600'000.0)) throw std::invalid_argument(std::string(name) + " must be 0..600000 ms");
}

RunSetup make_setup(const Scenario& nominal, const EmulatorConfig& c) {
  if (c.disperse) return disperse(nominal, c.seed);
  RunSetup setup;
  setup.seed = c.seed;
  setup.scenario = std::make_shared<Scenario>(nominal);
  setup.believed_camera = nominal.camera;
  return setup;
}

EmulatorConfig with_seed(EmulatorConfig c, const RunSetup& setup) {
  c.seed = setup.seed;
  c.disperse = !setup.drawn.empty();
  return c;
}

}  // namespace

bool emulator_applies_dispersion(const std::string& name) {
  static const std::set<std::string> not_applied{
      "camera_focal_error_rel", "camera_cx_error_px",       "camera_cy_error_px",
      "video_latency_mean_s",   "frame_drop_probability",   "command_latency_mean_s",
      "command_loss_probability", "compute_latency_s",      "compute_latency_quantile",
      "video_datagram_loss",    "state_loss",               "reply_loss",
      "not_joystick_probability", "video_stall_start_s",    "video_stall_duration_s"};
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
  if (!(c.linger_s >= 0.0 && std::isfinite(c.linger_s))) throw std::invalid_argument("linger must be >= 0 s");
  if (c.client_state_port == 0 || c.client_video_port == 0) throw std::invalid_argument("client ports must be 1..65535");
  if (c.key_interval_frames < 0 || c.key_interval_frames > 600) throw std::invalid_argument("key interval must be 0..600 frames");
  if (c.slices_per_frame < 1 || c.slices_per_frame > 45) throw std::invalid_argument("slices per frame must be 1..45");
  if (c.max_datagram_bytes < 16) throw std::invalid_argument("max datagram size must be >= 16 bytes");
  tello::parse_ipv4(c.bind_ip);  // throws std::invalid_argument naming the text
}

struct TelloEmulator::VideoWorker {
  /// own_renderer: the worker thread's renderer; inline video uses the co-simulation's.
  VideoWorker(const Scenario& sc, int key_interval_frames, int slices, bool own_renderer = true)
      : renderer(own_renderer ? std::make_unique<render::Renderer>(sc.warehouse, sc.camera, render_options_for(sc))
                              : nullptr),
        // The emulator forces every key frame (by capture time); the encoder's own interval
        // is a backstop far beyond it.
        encoder(sc.camera.width_px, sc.camera.height_px, std::max(1, static_cast<int>(std::lround(sc.frame_rate_hz))),
                4 * (key_interval_frames > 0 ? key_interval_frames
                                             : std::max(1, static_cast<int>(std::lround(sc.frame_rate_hz)))),
                H264Encoder::kTelloQp, std::min(slices, (sc.camera.height_px + 15) / 16)),
        motion_blur(sc.cosim.motion_blur_samples > 1) {}
  std::unique_ptr<render::Renderer> renderer;
  H264Encoder encoder;
  bool motion_blur;
  cv::Mat bgr;
  std::string error;  ///< set (under the emulator's mutex) when rendering or encoding failed
};

TelloEmulator::TelloEmulator(const Scenario& scenario, EmulatorConfig config)
    : TelloEmulator(make_setup(scenario, config), std::move(config), {}, nullptr, {}) {}

TelloEmulator::TelloEmulator(const RunSetup& setup, EmulatorConfig config, EmulatorChannels channels,
                             render::Renderer& renderer, TickObserver on_tick)
    : TelloEmulator(setup, with_seed(std::move(config), setup), std::move(channels), &renderer, std::move(on_tick)) {}

TelloEmulator::TelloEmulator(RunSetup setup, EmulatorConfig config, EmulatorChannels channels,
                             render::Renderer* inline_renderer, TickObserver on_tick)
    : setup_(std::move(setup)),
      scenario_(setup_.scenario),
      config_((validate_emulator_config(config), std::move(config))),
      command_socket_(channels.command ? std::move(channels.command)
                                       : std::make_unique<tello::UdpSocket>(config_.bind_ip, config_.command_port)),
      state_socket_(channels.state ? std::move(channels.state)
                                   : std::make_unique<tello::UdpSocket>(config_.bind_ip, config_.state_source_port)),
      video_socket_(channels.video ? std::move(channels.video)
                                   : std::make_unique<tello::UdpSocket>(config_.bind_ip, config_.video_source_port)),
      inline_renderer_(inline_renderer),
      on_tick_(std::move(on_tick)),
      world_(scenario_->warehouse, scenario_->vehicle.size_m, scenario_->cosim.vehicle_margin_m),
      tello_(scenario_->vehicle, autopilot_params_for(*scenario_), scenario_->wind,
             RandomStream(config_.seed, StreamId::wind).next_u64(), {}, scenario_->start.p_WB_m.x(),
             scenario_->start.p_WB_m.y(), scenario_->start.yaw_rad),
      ground_z_m_(tello_.state().p_WB_m.z()),
      command_faults_(mix64(config_.seed ^ 1), StreamId::link_faults),
      reply_faults_(mix64(config_.seed ^ 2), StreamId::link_faults),
      state_faults_(mix64(config_.seed ^ 3), StreamId::link_faults),
      video_faults_(mix64(config_.seed ^ 4), StreamId::link_faults),
      error_faults_(mix64(config_.seed ^ 5), StreamId::link_faults),
      frame_faults_(mix64(config_.seed ^ 6), StreamId::link_faults),
      render_noise_(config_.seed, StreamId::render_noise),
      command_jitter_(mix64(config_.seed ^ 7), StreamId::link_faults),
      reply_jitter_(mix64(config_.seed ^ 8), StreamId::link_faults),
      state_jitter_(mix64(config_.seed ^ 9), StreamId::link_faults),
      video_jitter_(mix64(config_.seed ^ 10), StreamId::link_faults),
      tick_mhz_(millihertz(scenario_->autopilot.rate_hz)),
      frame_mhz_(millihertz(scenario_->frame_rate_hz)),
      state_mhz_(millihertz(scenario_->cosim.state_rate_hz)),
      X_prev_(body_pose(tello_.state())),
      X_WC_prev_frame_(render::camera_pose_W(X_prev_, scenario_->camera_mount)),
      v_prev_(tello_.state().v_WB_W_mps),
      crossing_(scenario_->warehouse.shelves.at(0), tello_.state().p_WB_m) {
  if (!scenario_->start.landed) throw std::invalid_argument("the Tello emulator starts landed (start.landed: true)");
  report_.inventory_truth = true_inventory(*scenario_);
  report_.start_p_W_m = scenario_->start.p_WB_m;
  report_.start_yaw_rad = scenario_->start.yaw_rad;
  report_.seed = config_.seed;
  report_.dispersed = config_.disperse;
  report_.drawn = setup_.drawn;
  start_video();
}

void TelloEmulator::start_video() {
  if (inline_renderer_) {
    video_ = std::make_unique<VideoWorker>(*scenario_, config_.key_interval_frames, config_.slices_per_frame, false);
    renderer_description_ = inline_renderer_->backend_description();
    return;
  }
  // The renderer's EGL context is made current on the thread that creates it, and a context
  // is current on one thread at a time: the worker creates (and alone uses) the renderer.
  worker_ = std::thread([this] { video_loop(); });
  std::unique_lock lock(mutex_);
  job_ready_.wait(lock, [this] { return worker_ready_; });
  if (!video_) {
    const std::string why = worker_error_;
    lock.unlock();
    worker_.join();
    throw std::runtime_error("tello emulator video: " + why);
  }
}

TelloEmulator::~TelloEmulator() {
  {
    std::lock_guard lock(mutex_);
    stop_ = true;
  }
  job_ready_.notify_all();
  if (worker_.joinable()) worker_.join();
}

std::string TelloEmulator::renderer_description() const { return renderer_description_; }

void TelloEmulator::end(const std::string& reason) {
  if (!end_reason_) end_reason_ = reason;
}

TimeNs TelloEmulator::next_due_ns() const {
  // Commands that fell due are handed to the firmware at the next tick, so they never make
  // anything due before it.
  TimeNs t = event_time(k_tick_, tick_mhz_);
  std::lock_guard lock(mutex_);
  if (!outgoing_.empty()) t = std::min(t, outgoing_.top().due_ns);
  return t;
}

void TelloEmulator::advance(TimeNs now_ns) {
  assert(now_ns >= now_ns_);
  now_ns_ = now_ns;
  receive_commands(now_ns);
  while (!end_reason_) {
    const TimeNs t = event_time(k_tick_, tick_mhz_);
    if (t > now_ns) break;
    tick(t, now_ns);
    ++k_tick_;
  }
  std::lock_guard lock(mutex_);
  if (!video_->error.empty()) {
    end_detail_ = video_->error;
    end("video_error");
  }
  flush_locked(now_ns);
}

void TelloEmulator::receive_commands(TimeNs now_ns) {
  while (auto d = command_socket_->receive()) {
    last_datagram_ns_ = now_ns;
    std::lock_guard lock(mutex_);
    ++counters_.commands_received;
    if (!well_formed(d->bytes, config_.max_datagram_bytes)) {
      ++counters_.commands_malformed;
      continue;
    }
    // Two draws per datagram, always, so one setting never shifts the other's draws.
    const bool lost = command_faults_.bernoulli(config_.faults.commands.loss);
    const bool twice = command_faults_.bernoulli(config_.faults.commands.duplicate);
    const std::string& prefix = config_.faults.lost_command_prefix;
    if (lost || (!prefix.empty() && d->bytes.rfind(prefix, 0) == 0)) {
      ++counters_.commands_dropped;
      continue;
    }
    const ChannelFaults& f = config_.faults.commands;
    const TimeNs due = std::max(last_command_due_, now_ns + jittered_ms(command_jitter_, f.delay_ms, f.jitter_ms));
    last_command_due_ = due;
    incoming_.push({due, seq_++, d->bytes, d->from});
    if (twice) {
      ++counters_.commands_duplicated;
      incoming_.push({due, seq_++, d->bytes, d->from});
    }
  }
}

TimeNs TelloEmulator::due_time(Channel channel, TimeNs t) {
  const EmulatorFaults& f = config_.faults;
  const ChannelFaults& c = channel == Channel::reply ? f.replies : channel == Channel::state ? f.state : f.video;
  RandomStream& jitter = channel == Channel::reply ? reply_jitter_ : channel == Channel::state ? state_jitter_ : video_jitter_;
  TimeNs& last = last_due_[static_cast<int>(channel)];
  last = std::max(last, t + jittered_ms(jitter, c.delay_ms, c.jitter_ms));
  return last;
}

std::int64_t TelloEmulator::key_interval_captures() const {
  return config_.key_interval_frames > 0 ? config_.key_interval_frames
                                         : std::max<std::int64_t>(1, std::llround(scenario_->frame_rate_hz));
}

void TelloEmulator::tick(TimeNs t, TimeNs now_ns) {
  const Scenario& sc = *scenario_;
  // 1. The plant and the autopilot to t; the motion checked for contacts, the crossing watched.
  try {
    tello_.step_to(t);
  } catch (const std::exception& e) {
    end_detail_ = e.what();
    end("numerical_failure");
    return;
  }
  const plant::RigidBodyState& s = tello_.state();
  if (!s.p_WB_m.allFinite() || !s.v_WB_W_mps.allFinite() || !s.q_WB.coeffs().allFinite()) {
    end_detail_ = "non-finite state";
    end("numerical_failure");
    return;
  }
  const Eigen::Isometry3d X = body_pose(s);
  if (t > t_prev_) {
    const double dt_s = ns_to_seconds(t - t_prev_);
    a_W_ = (s.v_WB_W_mps - v_prev_) / dt_s;
    report_.path_length_m += (X.translation() - X_prev_.translation()).norm();
    if (const auto contact = world_.sweep(X_prev_, t_prev_, X, t, plant::FloorContacts::ignore)) {
      report_.contact = *contact;
      end_detail_ = contact->element.name;
      end(plant::is_shelf_part(contact->element.kind) ? "collision" : "left_arena");
    }
    const Eigen::Vector3d& p = s.p_WB_m;
    if ((p.array() < sc.warehouse.arena_min_W_m.array()).any() || (p.array() > sc.warehouse.arena_max_W_m.array()).any()) {
      end_detail_ = "outside the arena";
      end("left_arena");
    }
    crossing_.update(p);
    const ShelfSpec& shelf = sc.warehouse.shelves.at(0);
    const double half_length_m = 0.5 * sc.vehicle.size_m.x() + sc.cosim.vehicle_margin_m;
    const double x_S = crossing_.p_S_m().x();
    if (x_S > -half_length_m - 0.05 && x_S < shelf.depth_m + half_length_m + 0.05) {
      const double clearance = world_.clearance_to_shelves(X).distance_m;
      report_.min_clearance_m = std::min(report_.min_clearance_m.value_or(clearance), clearance);
    }
    X_prev_ = X;
    v_prev_ = s.v_WB_W_mps;
    t_prev_ = t;
  }
  if (tello_.mode() != plant::FlightMode::landed) report_.flew = true;
  if (on_tick_) on_tick_(t, tello_);
  if (end_reason_) return;

  // 2. Commands due by t, to the firmware; its replies.
  while (!incoming_.empty() && incoming_.top().due_ns <= t && !end_reason_) {
    const IncomingCommand c = incoming_.top();
    incoming_.pop();
    deliver(t, c);
  }
  for (const SdkReply& r : tello_.take_replies()) send_reply(r.t_ns, r.text, manoeuvre_reply_to_);

  // 3. The state record, to the `command` sender's state port.
  if (t >= event_time(k_state_, state_mhz_)) {
    if (tello_.autopilot().sdk_mode() && client_) {
      const plant::Autopilot& firmware = tello_.autopilot();
      const std::string text = format_state_record(
          state_from_truth(s, a_W_, ground_z_m_, firmware.battery_pct(), firmware.motor_on_time_s(), t));
      std::lock_guard lock(mutex_);
      const bool lost = state_faults_.bernoulli(config_.faults.state.loss);
      const bool twice = state_faults_.bernoulli(config_.faults.state.duplicate);
      if (lost) {
        ++counters_.state_dropped;
      } else {
        const TimeNs due = due_time(Channel::state, t);
        const tello::Endpoint to{client_->ip, config_.client_state_port};
        outgoing_.push({due, out_seq_++, Channel::state, to, text});
        if (twice) {
          ++counters_.state_duplicated;
          outgoing_.push({due, out_seq_++, Channel::state, to, text});
        }
      }
    }
    while (event_time(k_state_, state_mhz_) <= t) ++k_state_;
  }

  // 4. A frame capture: handed to the video worker if it is free and the capture is recent.
  if (t >= event_time(k_frame_, frame_mhz_)) {
    const Eigen::Isometry3d X_WC = render::camera_pose_W(X, sc.camera_mount);
    const std::uint64_t noise_seed = render_noise_.next_u64();  // one per capture, as in the co-simulation
    const bool streaming = tello_.autopilot().stream_on() && client_.has_value();
    if (streaming) {
      const TimeNs frame_period_ns = event_time(k_frame_ + 1, frame_mhz_) - event_time(k_frame_, frame_mhz_);
      const auto& f = config_.faults;
      const bool stalled = f.video_stall_start_s && t >= seconds_to_ns(*f.video_stall_start_s) &&
                           t < seconds_to_ns(*f.video_stall_start_s + f.video_stall_duration_s);
      std::lock_guard lock(mutex_);
      ++counters_.frames_captured;
      const bool lost = frame_faults_.bernoulli(config_.faults.video_frame_loss);  // one draw per capture
      if (stalled) {
        ++counters_.frames_stalled;
      } else if (lost) {
        ++counters_.frames_lost;
      } else if (!inline_renderer_ && now_ns - t > frame_period_ns) {
        ++counters_.frames_dropped_late;
      } else if (worker_busy_ || job_) {
        ++counters_.frames_dropped_busy;
      } else {
        // Key frames by capture time, not by frames encoded: frames dropped here (renderer
        // busy) must not stretch the group of pictures past its interval, as they would
        // if the encoder counted (the Tello's encoder sees every frame).
        const bool key = !video_was_on_ || k_frame_ >= next_key_capture_;
        if (key) next_key_capture_ = k_frame_ + key_interval_captures();
        const FrameJob job{k_frame_, t, X_WC_prev_frame_, X_WC, noise_seed, key, {client_->ip, config_.client_video_port}};
        video_was_on_ = true;
        if (inline_renderer_) {
          // The co-simulation: rendered and encoded now, in simulated time (an encoding
          // error is a failure of the run, not a dropped frame).
          queue_frame_locked(job, encode_frame(*video_, *inline_renderer_, job), now_ns);
        } else {
          job_ = job;
          job_ready_.notify_one();
        }
      }
    } else {
      video_was_on_ = false;  // the next streamon starts with a key frame
    }
    X_WC_prev_frame_ = X_WC;
    while (event_time(k_frame_, frame_mhz_) <= t) ++k_frame_;
  }

  // 5. Landed after flying, and nobody talking any more: the flight is over.
  if (report_.flew && tello_.mode() == plant::FlightMode::landed && t - last_datagram_ns_ >= seconds_to_ns(config_.linger_s)) {
    end("landed");
  }
}

void TelloEmulator::deliver(TimeNs t, const IncomingCommand& c) {
  std::string text = c.text;
  while (!text.empty() && (text.back() == '\n' || text.back() == '\r')) text.pop_back();
  {
    std::lock_guard lock(mutex_);
    ++counters_.commands_delivered;
  }
  if (tello_.autopilot().sdk_mode() && refusable(text)) {
    // Two draws per refusable command, always, so one setting never shifts the other's draws.
    const bool joystick = error_faults_.bernoulli(config_.faults.not_joystick);
    const bool imu = error_faults_.bernoulli(config_.faults.no_valid_imu);
    if (joystick || imu) {
      {
        std::lock_guard lock(mutex_);
        ++counters_.injected_errors;
      }
      // The drone received a command and answered it: that counts for its 15 s no-command
      // watchdog like any other ("any command counts", docs/tello_sdk.md). The simulated firmware
      // only learns of a datagram through a command, so it is handed the one command with no
      // effect but an immediate answer, a read, whose answer is dropped.
      try {
        (void)tello_.submit(t, "sdk?");
      } catch (const std::exception& e) {
        end_detail_ = e.what();
        end("numerical_failure");
        return;
      }
      send_reply(t, joystick ? "error Not joystick" : "error No valid imu", c.from);
      return;
    }
  }
  if (is_manoeuvre_text(text)) manoeuvre_reply_to_ = c.from;
  std::optional<std::string> reply;
  try {
    reply = tello_.submit(t, text);
  } catch (const std::exception& e) {
    end_detail_ = e.what();
    end("numerical_failure");
    return;
  }
  if (text == "command" && reply == "ok") client_ = c.from;
  if (reply) send_reply(t, *reply, c.from);
}

void TelloEmulator::send_reply(TimeNs t, const std::string& text, const tello::Endpoint& to) {
  const EmulatorFaults& f = config_.faults;
  std::lock_guard lock(mutex_);
  // Three draws per reply, always.
  const bool lost = reply_faults_.bernoulli(f.replies.loss);
  const bool late = reply_faults_.bernoulli(f.late_replies);
  const bool twice = reply_faults_.bernoulli(f.replies.duplicate);
  if (lost) {
    ++counters_.replies_dropped;
    return;
  }
  TimeNs due = due_time(Channel::reply, t);
  if (late) {
    due += ms_to_ns(f.late_reply_ms);
    ++counters_.replies_late;
  }
  outgoing_.push({due, out_seq_++, Channel::reply, to, text});
  if (twice) {
    ++counters_.replies_duplicated;
    outgoing_.push({due, out_seq_++, Channel::reply, to, text});
  }
}

void TelloEmulator::flush_locked(TimeNs now_ns) {
  while (!outgoing_.empty() && outgoing_.top().due_ns <= now_ns) {
    const Outgoing& o = outgoing_.top();
    tello::DatagramChannel& socket =
        o.channel == Channel::reply ? *command_socket_ : o.channel == Channel::state ? *state_socket_ : *video_socket_;
    if (!socket.send_to(o.to, o.bytes)) {
      ++counters_.send_errors;
    } else if (o.channel == Channel::reply) {
      ++counters_.replies_sent;
    } else if (o.channel == Channel::state) {
      ++counters_.state_sent;
    } else {
      ++counters_.video_datagrams_sent;
      counters_.video_bytes_sent += static_cast<std::int64_t>(o.bytes.size());
    }
    outgoing_.pop();
  }
}

void TelloEmulator::video_loop() {
  {
    std::unique_ptr<VideoWorker> worker;
    std::string error;
    try {
      worker = std::make_unique<VideoWorker>(*scenario_, config_.key_interval_frames, config_.slices_per_frame);
      renderer_description_ = worker->renderer->backend_description();
    } catch (const std::exception& e) {
      error = e.what();
    }
    std::lock_guard lock(mutex_);
    video_ = std::move(worker);
    worker_error_ = error;
    worker_ready_ = true;
    job_ready_.notify_all();
    if (!video_) return;
  }
  for (;;) {
    FrameJob job;
    {
      std::unique_lock lock(mutex_);
      job_ready_.wait(lock, [this] { return stop_ || job_.has_value(); });
      if (stop_) {
        // The renderer's EGL context is destroyed on the thread it is current on: another
        // thread's eglDestroyContext could only defer it (and the context would leak).
        video_.reset();
        return;
      }
      job = *job_;
      job_.reset();
      worker_busy_ = true;
    }
    EncodedFrame frame;
    std::string error;
    try {
      frame = encode_frame(*video_, *video_->renderer, job);
    } catch (const std::exception& e) {
      error = e.what();
    }
    std::lock_guard lock(mutex_);
    worker_busy_ = false;
    if (!error.empty()) {
      video_->error = "video: " + error;
      continue;
    }
    // Sends what is due by the capture time: the frame itself unless delayed (the worker has
    // no clock; the main loop sends delayed datagrams when they fall due).
    queue_frame_locked(job, std::move(frame), job.t_ns);
  }
}

TelloEmulator::EncodedFrame TelloEmulator::encode_frame(VideoWorker& video, render::Renderer& renderer,
                                                        const FrameJob& job) {
  if (video.motion_blur) {
    renderer.render_blurred_into(job.X_WC_prev, job.X_WC, job.noise_seed, video.bgr);
  } else {
    renderer.render_into(job.X_WC, job.noise_seed, video.bgr);
  }
  const std::string access_unit = video.encoder.encode(video.bgr, job.force_key);
  const std::vector<int> types = sdk::nal_unit_types(access_unit);
  EncodedFrame frame;
  frame.key = std::find(types.begin(), types.end(), 5) != types.end();
  frame.datagrams = sdk::tello_datagrams(access_unit);
  return frame;
}

void TelloEmulator::queue_frame_locked(const FrameJob& job, EncodedFrame frame, TimeNs t_send) {
  ++counters_.frames_sent;
  if (frame.key) ++counters_.key_frames;
  // One delay per frame (its datagrams leave back to back).
  const TimeNs due = due_time(Channel::video, job.t_ns);
  for (std::string& d : frame.datagrams) {
    if (video_faults_.bernoulli(config_.faults.video.loss)) {
      ++counters_.video_datagrams_dropped;
    } else {
      outgoing_.push({due, out_seq_++, Channel::video, job.to, std::move(d)});
    }
  }
  flush_locked(t_send);
}

EmulatorReport TelloEmulator::report() const {
  EmulatorReport r = report_;
  r.end_reason = end_reason_.value_or("running");
  r.detail = end_detail_;
  r.elapsed_s = ns_to_seconds(tello_.time_ns());
  r.flight_time_s = tello_.autopilot().motor_on_time_s();
  r.landed = tello_.mode() == plant::FlightMode::landed;
  r.crossed = crossing_.crossed();
  r.entry_offset_y_m = crossing_.entry_offset_y_m();
  r.entry_offset_z_m = crossing_.entry_offset_z_m();
  std::lock_guard lock(mutex_);
  r.counters = counters_;
  return r;
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
         {"path_length_m", r.path_length_m},
         {"flew", r.flew},
         {"landed", r.landed},
         {"crossed", r.crossed ? json{{"level", r.crossed->level}, {"column", r.crossed->column}} : json(nullptr)},
         {"entry_offset_y_m", number_or_null(r.entry_offset_y_m)},
         {"entry_offset_z_m", number_or_null(r.entry_offset_z_m)},
         {"min_clearance_m", number_or_null(r.min_clearance_m)},
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
  j["contact"] = r.contact ? contact_json(*r.contact) : json(nullptr);
  return j.dump(2);
}

std::string emulator_report_text(const EmulatorReport& r) {
  std::ostringstream o;
  const EmulatorCounters& c = r.counters;
  o << "tello-sim: " << r.end_reason << (r.detail.empty() ? "" : " (" + r.detail + ")") << " after " << r.elapsed_s
    << " s; flight time " << r.flight_time_s << " s, path " << r.path_length_m << " m, "
    << (r.landed ? "landed" : "airborne") << "\n";
  o << "contact: " << (r.contact ? r.contact->element.name : std::string("none")) << "\n";
  o << "crossed: ";
  if (r.crossed) {
    o << "shelf 0 level " << r.crossed->level << " column " << r.crossed->column << ", entry offset y "
      << r.entry_offset_y_m.value_or(NAN) << " m z " << r.entry_offset_z_m.value_or(NAN) << " m";
  } else {
    o << "no cell";
  }
  if (r.min_clearance_m) o << "; min clearance " << *r.min_clearance_m << " m";
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

void run_tello_emulator(TelloEmulator& emulator, const std::atomic<bool>& stop, double max_seconds) {
  // The emulator's one wall clock: simulated time follows the time elapsed since here.
  const auto origin = std::chrono::steady_clock::now();
  const auto elapsed_ns = [&] {
    return static_cast<TimeNs>(
        std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::steady_clock::now() - origin).count());
  };
  const TimeNs max_ns = max_seconds > 0.0 ? seconds_to_ns(max_seconds) : 0;
  for (;;) {
    const TimeNs now = elapsed_ns();
    emulator.advance(now);
    if (emulator.finished()) break;
    if (stop.load()) {
      emulator.end("signal");
      break;
    }
    if (max_ns > 0 && now >= max_ns) {
      emulator.end("max_seconds");
      break;
    }
    // Sleep in poll until a command arrives or the next thing falls due (at most 2 ms, so a
    // signal is seen promptly).
    const TimeNs wait_ns = std::clamp<TimeNs>(emulator.next_due_ns() - elapsed_ns(), 0, 2'000'000);
    pollfd p{emulator.command_fd(), POLLIN, 0};
    const timespec ts{0, static_cast<long>(wait_ns)};
    ppoll(&p, 1, &ts, nullptr);
  }
  // What is already queued (a land reply, say) goes out before the report.
  emulator.advance(elapsed_ns());
}

}  // namespace shelfcross::verification
