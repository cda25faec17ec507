// The ideal link of the co-simulation: whole messages (a frame, a state record, a command, a
// reply, delivered or lost whole), the flight software alone, no driver and no decoder. The world
// advances to every event time, not only to autopilot ticks.
//
// Its faults are the sdk link's: one DatagramFaults from the same settings (link_faults) and the
// same seed (the run's) as the simulated Tello's, each message drawn as the Tello draws its
// datagram: a frame's loss (frame_lost, the video stall), a command's, a state record's and a
// reply's fate (lost, twice, late), each channel's arrival (due: delay, jitter, order kept), and
// the bursts and outages (fault_windows.hpp: a command, reply or state record drawn at its time on
// air; a frame lost whole in an outage at its arrival). A message sent twice is delivered twice at
// the same instant, as the sdk link does: the firmware answers a second command as it answers any
// (a second `takeoff` in the air is refused "error"), and the flight software drops a reply that
// answers nothing as stale. What the ideal link has no part for: video datagrams (video.loss: a
// lost datagram gives an error-concealed picture on the sdk link, not a lost frame, and the ideal
// link has no decoder to damage a picture, so its pictures are always whole and per-datagram loss
// is not applied, nor the video channel's bursts), the firmware's injected refusals (not_joystick,
// no_valid_imu: the simulated Tello's command interpreter answers them; here the plant's firmware
// answers every command).

#include <algorithm>
#include <memory>
#include <variant>

#include <opencv2/core/mat.hpp>

#include "sdk/state_record.hpp"
#include "verification/cosim/cosim_run.hpp"
#include "verification/cosim/link_faults.hpp"
#include "verification/world/tello_state_format.hpp"

namespace shelfcross::verification {
namespace {

/// A message on its way to the flight software: a frame, a state datagram's text (parsed on
/// arrival by the driver's parser, as tello_pilot does), or a reply.
struct StateText {
  std::string text;
};
using ToFlightSoftware = std::variant<CameraFrame, StateText, SdkReply>;

/// The ideal link's state: the world, the flight software and what is in flight between them.
class IdealLink {
 public:
  IdealLink(RunContext& run)
      : run_(run),
        faults_(link_faults(run.cs.link), run.setup.seed),
        compute_ns_(seconds_to_ns(run.cs.link.compute_latency_s)),
        world_(run.setup, run.shelf_count),
        fsw_(run.flight_config),
        tick_mhz_(millihertz(run.sc.autopilot.rate_hz)),
        fsw_tick_mhz_(millihertz(run.cs.fsw_tick_hz)) {}

  RunResult fly();

 private:
  void send_commands(const std::vector<SdkCommand>& commands);
  void reply_to_fsw(TimeNs t_sent, const std::string& text);
  void send_state(TimeNs t);
  void step_fsw(const flight_sw::Input& input, TimeNs t);
  /// Commands due at t, to the firmware; its replies to the flight software. False when the
  /// firmware's plant failed.
  bool commands_to_vehicle(TimeNs t);
  void capture(TimeNs t);
  void deliver_to_fsw(TimeNs t);
  /// A buffer no picture in flight shares any more (see fly()).
  cv::Mat& free_frame_buffer();

  RunContext& run_;
  DatagramFaults faults_;
  /// The flight software's step time (compute_latency_s), added to a command before its
  /// channel's delay: not a fault of the link.
  const TimeNs compute_ns_;
  TelloWorld world_;
  flight_sw::FlightSoftware fsw_;
  const std::int64_t tick_mhz_, fsw_tick_mhz_;
  std::int64_t k_tick_ = 1, k_fsw_tick_ = 1;
  TimedQueue<std::string> to_vehicle_;
  TimedQueue<ToFlightSoftware> to_fsw_;
  std::uint64_t seq_ = 0;
  bool sdk_on_ = false, video_on_ = false;
  // Pictures in flight to the flight software share their pixels with the queue (and with
  // whatever the flight software keeps); each capture is drawn into a buffer that nothing
  // else holds any more, so no picture is copied (a 960 x 720 copy was 6 % of a run).
  std::vector<cv::Mat> frame_buffers_;
};

void IdealLink::send_commands(const std::vector<SdkCommand>& commands) {
  LinkMetrics& l = run_.result.metrics.link;
  for (const SdkCommand& c : commands) {
    const DatagramFaults::Fate fate = faults_.command(c.text, c.t_ns + compute_ns_);
    run_.log_event(c.t_ns, "send " + c.text + (fate.lost ? " (lost)" : ""));
    ++l.commands_sent;
    if (fate.lost) {
      ++l.commands_lost;
      continue;
    }
    const TimeNs arrival = faults_.due(DatagramFaults::Channel::command, c.t_ns + compute_ns_);
    to_vehicle_.push({arrival, seq_++, c.text});
    if (fate.twice) to_vehicle_.push({arrival, seq_++, c.text});
  }
}

void IdealLink::reply_to_fsw(TimeNs t_sent, const std::string& text) {
  const DatagramFaults::Fate fate = faults_.reply(t_sent);
  if (fate.lost) {
    ++run_.result.metrics.link.replies_lost;
    return;
  }
  const TimeNs arrival = faults_.reply_due(fate, t_sent);
  to_fsw_.emplace(arrival, seq_++, SdkReply{0, text});
  if (fate.twice) to_fsw_.emplace(arrival, seq_++, SdkReply{0, text});
}

void IdealLink::send_state(TimeNs t) {
  const StateText record{format_state_record(world_.state_record(t))};
  const DatagramFaults::Fate fate = faults_.state(t);
  if (fate.lost) {
    ++run_.result.metrics.link.state_records_lost;
    return;
  }
  const TimeNs arrival = faults_.due(DatagramFaults::Channel::state, t);
  to_fsw_.push({arrival, seq_++, record});
  if (fate.twice) to_fsw_.push({arrival, seq_++, record});
}

void IdealLink::step_fsw(const flight_sw::Input& input, TimeNs t) {
  std::vector<SdkCommand> commands;
  try {
    if (injected_fault_due(run_.cs, t)) throw std::runtime_error("injected fault (cosim.inject_flight_software_exception_s)");
    commands = fsw_.step(input);
  } catch (const std::exception& e) {
    run_.flight_software_threw(t, e.what());
    return;
  }
  send_commands(commands);
  run_.after_fsw_step(fsw_, t);
}

cv::Mat& IdealLink::free_frame_buffer() {
  for (cv::Mat& b : frame_buffers_) {
    if (!b.u || b.u->refcount == 1) return b;  // not drawn into yet, or held by the pool alone
  }
  return frame_buffers_.emplace_back();
}

bool IdealLink::commands_to_vehicle(TimeNs t) {
  plant::SimulatedTello& tello = world_.tello();
  for (const SdkReply& r : tello.take_replies()) {
    run_.log_event(r.t_ns, "reply " + r.text);
    reply_to_fsw(r.t_ns, r.text);
  }
  while (!to_vehicle_.empty() && to_vehicle_.top().t_ns == t) {
    const std::string text = to_vehicle_.top().payload;
    to_vehicle_.pop();
    std::optional<std::string> reply;
    try {
      reply = tello.submit(t, text);
    } catch (const std::exception& e) {
      run_.outcome = RunOutcome::numerical_failure;
      run_.result.detail = e.what();
      return false;
    }
    if (reply) {
      if (text == "command" && *reply == "ok") sdk_on_ = true;
      if (text == "streamon" && *reply == "ok") video_on_ = true;
      if (text == "streamoff" && *reply == "ok") video_on_ = false;
      run_.log_event(t, "reply " + *reply);
      reply_to_fsw(t, *reply);
    }
  }
  return true;
}

void IdealLink::capture(TimeNs t) {
  const auto capture = world_.capture_due(t);
  if (!capture || !video_on_) return;
  LinkMetrics& l = run_.result.metrics.link;
  ++l.frames_captured;
  const bool lost = faults_.frame_lost();  // drawn for every capture, stalled or not, as the Tello does
  if (lost || faults_.video_stalled(t)) {
    ++l.frames_lost;
    return;
  }
  const TimeNs arrival = faults_.due(DatagramFaults::Channel::video, t);
  // On air from its arrival, as the sdk link's datagrams are: lost whole in an outage.
  if (faults_.outage(arrival)) {
    ++l.frames_lost;
    return;
  }
  cv::Mat& frame_bgr = free_frame_buffer();
  if (run_.cs.motion_blur_samples > 1) {
    run_.renderer.render_blurred_rolling_into(capture->X_WC_prev, capture->X_WC_readout_start, capture->X_WC,
                                              capture->noise_seed, frame_bgr);
  } else {
    run_.renderer.render_rolling_into(capture->X_WC_readout_start, capture->X_WC, capture->noise_seed, frame_bgr);
  }
  to_fsw_.push({arrival, seq_++, CameraFrame{arrival, capture->index, frame_bgr}});
}

void IdealLink::deliver_to_fsw(TimeNs t) {
  while (!run_.outcome && !to_fsw_.empty() && to_fsw_.top().t_ns == t) {
    ToFlightSoftware msg = to_fsw_.top().payload;  // cv::Mat copies share the pixels
    to_fsw_.pop();
    if (auto* frame = std::get_if<CameraFrame>(&msg)) {
      ++run_.result.metrics.link.frames_decoded;
      ++run_.result.metrics.link.frames_handed;
      step_fsw(*frame, t);
      if (run_.observer && !run_.outcome) run_.observer(*frame, fsw_);
    } else if (auto* state = std::get_if<StateText>(&msg)) {
      if (auto record = sdk::parse_state_record(state->text, t)) step_fsw(*record, t);
    } else {
      SdkReply reply = std::get<SdkReply>(msg);
      reply.t_ns = t;
      step_fsw(reply, t);
    }
  }
}

RunResult IdealLink::fly() {
  send_commands(fsw_.start(0));
  run_.started(fsw_);
  while (!run_.outcome) {
    TimeNs t = std::min({event_time(k_tick_, tick_mhz_), world_.next_capture_ns(), world_.next_state_ns(),
                         run_.next_sample_ns(), event_time(k_fsw_tick_, fsw_tick_mhz_)});
    if (!to_vehicle_.empty()) t = std::min(t, to_vehicle_.top().t_ns);
    if (!to_fsw_.empty()) t = std::min(t, to_fsw_.top().t_ns);
    if (const TimeNs limit = run_.limit_ns(fsw_); t > limit) {
      run_.time_out(limit);
      break;
    }
    inject_process_faults(run_.cs, t);

    // 1. The world to t: plant and autopilot, the motion checked for contacts.
    run_.observe(world_.tick(t), world_);
    if (run_.outcome) break;

    // 2. Events at t, in a fixed order: the autopilot's tick, commands to the vehicle and its
    // replies, a capture, a state record, deliveries to the flight software, its own timer.
    if (t == event_time(k_tick_, tick_mhz_)) ++k_tick_;
    if (!commands_to_vehicle(t)) break;
    capture(t);
    if (world_.state_due(t) && sdk_on_) send_state(t);
    deliver_to_fsw(t);
    if (run_.outcome) break;
    if (t == event_time(k_fsw_tick_, fsw_tick_mhz_)) {  // the flight computer's own timer
      step_fsw(flight_sw::ClockTick{t}, t);
      ++k_fsw_tick_;
      if (run_.outcome) break;
    }
    run_.sample_trajectory(t, world_.tello().state(), fsw_);
    if (fsw_.finished() && world_.tello().mode() == plant::FlightMode::landed) break;
  }
  // No driver here: the replies that answered nothing (duplicates, late ones) the flight
  // software dropped itself.
  run_.result.metrics.link.stale_replies = fsw_.telemetry().link.stale_replies;
  return run_.finish(world_, fsw_, "");
}

}  // namespace

RunResult fly_ideal_link(RunContext& run) { return IdealLink(run).fly(); }

}  // namespace shelfcross::verification
