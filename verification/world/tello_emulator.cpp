#include "verification/world/tello_emulator.hpp"

#include <poll.h>

#include <algorithm>
#include <cassert>
#include <chrono>
#include <cmath>
#include <stdexcept>
#include <variant>

#include <opencv2/core/mat.hpp>

#include "render/ground_truth.hpp"
#include "render/renderer.hpp"
#include "sdk/command.hpp"
#include "sdk/video_framing.hpp"
#include "verification/world/h264_encoder.hpp"
#include "verification/world/mission_setup.hpp"
#include "verification/world/tello_state_format.hpp"

namespace shelfcross::verification {
namespace {

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

RunSetup make_setup(const Scenario& nominal, const EmulatorConfig& c) {
  if (c.disperse) return disperse(nominal, c.seed);
  RunSetup setup;
  setup.seed = c.seed;
  setup.scenario = std::make_shared<Scenario>(nominal);
  setup.believed_camera = nominal.camera;
  return setup;
}

void check_landed(const Scenario& sc) {
  if (!sc.start.landed) throw std::invalid_argument("the Tello emulator starts landed (start.landed: true)");
}

EmulatorConfig with_seed(EmulatorConfig c, const RunSetup& setup) {
  c.seed = setup.seed;
  c.disperse = !setup.drawn.empty();
  return c;
}

}  // namespace

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
      world_((check_landed(*scenario_), setup_), mission_shelf_count(*scenario_)),
      faults_(config_.faults, config_.seed),
      tick_mhz_(millihertz(scenario_->autopilot.rate_hz)) {
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
    const DatagramFaults::Fate fate = faults_.command();
    const std::string& prefix = config_.faults.lost_command_prefix;
    if (fate.lost || (!prefix.empty() && d->bytes.rfind(prefix, 0) == 0)) {
      ++counters_.commands_dropped;
      continue;
    }
    const TimeNs due = faults_.due(DatagramFaults::Channel::command, now_ns);
    incoming_.push({due, seq_++, d->bytes, d->from});
    if (fate.twice) {
      ++counters_.commands_duplicated;
      incoming_.push({due, seq_++, d->bytes, d->from});
    }
  }
}

std::int64_t TelloEmulator::key_interval_captures() const {
  return config_.key_interval_frames > 0 ? config_.key_interval_frames
                                         : std::max<std::int64_t>(1, std::llround(scenario_->frame_rate_hz));
}

void TelloEmulator::tick(TimeNs t, TimeNs now_ns) {
  // 1. The world to t: the plant and the firmware, the motion checked for contacts, the arena,
  // the crossings, the clearance.
  const TickReport r = world_.tick(t);
  if (r.end != WorldEnd::none) {
    end_detail_ = r.detail;
    end(world_end_name(r.end));
    if (r.end == WorldEnd::numerical_failure) return;
  }
  if (on_tick_) on_tick_(r, world_);
  if (end_reason_) return;
  plant::SimulatedTello& tello = world_.tello();

  // 2. Commands due by t, to the firmware; its replies.
  while (!incoming_.empty() && incoming_.top().due_ns <= t && !end_reason_) {
    const IncomingCommand c = incoming_.top();
    incoming_.pop();
    deliver(t, c);
  }
  for (const SdkReply& reply : tello.take_replies()) send_reply(reply.t_ns, reply.text, manoeuvre_reply_to_);

  // 3. The state record, to the `command` sender's state port.
  if (world_.state_due(t)) {
    if (tello.autopilot().sdk_mode() && client_) {
      const std::string text = format_state_record(world_.state_record(t));
      std::lock_guard lock(mutex_);
      const DatagramFaults::Fate fate = faults_.state();
      if (fate.lost) {
        ++counters_.state_dropped;
      } else {
        const TimeNs due = faults_.due(DatagramFaults::Channel::state, t);
        const tello::Endpoint to{client_->ip, config_.client_state_port};
        outgoing_.push({due, out_seq_++, Channel::state, to, text});
        if (fate.twice) {
          ++counters_.state_duplicated;
          outgoing_.push({due, out_seq_++, Channel::state, to, text});
        }
      }
    }
  }

  // 4. A frame capture: handed to the video worker if it is free and the capture is recent.
  if (const auto capture = world_.capture_due(t)) {
    const bool streaming = tello.autopilot().stream_on() && client_.has_value();
    if (streaming) {
      const TimeNs frame_period_ns = capture->period_ns;
      const auto& f = config_.faults;
      const bool stalled = f.video_stall_start_s && t >= seconds_to_ns(*f.video_stall_start_s) &&
                           t < seconds_to_ns(*f.video_stall_start_s + f.video_stall_duration_s);
      std::lock_guard lock(mutex_);
      ++counters_.frames_captured;
      const bool lost = faults_.frame_lost();
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
        const bool key = !video_was_on_ || capture->index >= next_key_capture_;
        if (key) next_key_capture_ = capture->index + key_interval_captures();
        const FrameJob job{capture->index, t,   capture->X_WC_prev, capture->X_WC, capture->noise_seed,
                           key,            {client_->ip, config_.client_video_port}};
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
  }

  // 5. Landed after flying, and nobody talking any more: the flight is over.
  if (world_.truth().flew && tello.mode() == plant::FlightMode::landed && t - last_datagram_ns_ >= seconds_to_ns(config_.linger_s)) {
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
  if (world_.tello().autopilot().sdk_mode() && refusable(text)) {
    const DatagramFaults::Refusal refusal = faults_.refusal();
    const bool joystick = refusal.not_joystick, imu = refusal.no_valid_imu;
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
        (void)world_.tello().submit(t, "sdk?");
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
    reply = world_.tello().submit(t, text);
  } catch (const std::exception& e) {
    end_detail_ = e.what();
    end("numerical_failure");
    return;
  }
  if (text == "command" && reply == "ok") client_ = c.from;
  if (reply) send_reply(t, *reply, c.from);
}

void TelloEmulator::send_reply(TimeNs t, const std::string& text, const tello::Endpoint& to) {
  std::lock_guard lock(mutex_);
  const DatagramFaults::Fate fate = faults_.reply();
  if (fate.lost) {
    ++counters_.replies_dropped;
    return;
  }
  TimeNs due = faults_.due(DatagramFaults::Channel::reply, t);
  if (fate.late) {
    due += faults_.late_reply_hold_ns();
    ++counters_.replies_late;
  }
  outgoing_.push({due, out_seq_++, Channel::reply, to, text});
  if (fate.twice) {
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
  const TimeNs due = faults_.due(DatagramFaults::Channel::video, job.t_ns);
  for (std::string& d : frame.datagrams) {
    if (faults_.video_datagram_lost()) {
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
  const plant::SimulatedTello& tello = world_.tello();
  const TruthRecord& truth = world_.truth();
  const ShelfCrossingMonitor& crossing = world_.crossings().front();
  r.elapsed_s = ns_to_seconds(tello.time_ns());
  r.flight_time_s = tello.autopilot().motor_on_time_s();
  r.path_length_m = truth.path_length_m;
  r.flew = truth.flew;
  r.landed = tello.mode() == plant::FlightMode::landed;
  r.contact = truth.contact;
  r.min_clearance_m = truth.min_clearance_m;
  r.crossed = crossing.crossed();
  r.entry_offset_y_m = crossing.entry_offset_y_m();
  r.entry_offset_z_m = crossing.entry_offset_z_m();
  std::lock_guard lock(mutex_);
  r.counters = counters_;
  return r;
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
