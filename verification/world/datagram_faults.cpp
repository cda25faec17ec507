#include "verification/world/datagram_faults.hpp"

#include <algorithm>
#include <cmath>

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

}  // namespace

// Each stream's seed is the run's seed mixed with a number of its own (1 to 10): streams apart,
// and a run's draws fixed by its seed. The bursts' and outages' streams are of a stream id of
// their own (link_bursts), numbered the same way (1 to 5).
DatagramFaults::DatagramFaults(const EmulatorFaults& faults, std::uint64_t seed)
    : faults_(faults),
      command_(mix64(seed ^ 1), StreamId::link_faults),
      reply_(mix64(seed ^ 2), StreamId::link_faults),
      state_(mix64(seed ^ 3), StreamId::link_faults),
      video_(mix64(seed ^ 4), StreamId::link_faults),
      error_(mix64(seed ^ 5), StreamId::link_faults),
      frame_(mix64(seed ^ 6), StreamId::link_faults),
      command_jitter_(mix64(seed ^ 7), StreamId::link_faults),
      reply_jitter_(mix64(seed ^ 8), StreamId::link_faults),
      state_jitter_(mix64(seed ^ 9), StreamId::link_faults),
      video_jitter_(mix64(seed ^ 10), StreamId::link_faults),
      bursts_{burst_windows(faults.bursts, RandomStream(mix64(seed ^ 1), StreamId::link_bursts)),
              burst_windows(faults.bursts, RandomStream(mix64(seed ^ 2), StreamId::link_bursts)),
              burst_windows(faults.bursts, RandomStream(mix64(seed ^ 3), StreamId::link_bursts)),
              burst_windows(faults.bursts, RandomStream(mix64(seed ^ 4), StreamId::link_bursts))},
      outages_(outage_windows(faults.outages, RandomStream(mix64(seed ^ 5), StreamId::link_bursts))) {}

bool DatagramFaults::outage(TimeNs t) {
  const LinkOutages& o = faults_.outages;
  if (o.start_s && t >= seconds_to_ns(*o.start_s) && t < seconds_to_ns(*o.start_s + o.duration_s)) return true;
  return outages_.active(t);
}

bool DatagramFaults::burst(Channel channel, TimeNs t) { return bursts_[static_cast<int>(channel)].active(t); }

bool DatagramFaults::lost(RandomStream& stream, double loss, Channel channel, TimeNs t) {
  // One draw, always (as RandomStream::bernoulli takes it): the stream's place never depends on
  // the state of the link.
  const double u = stream.uniform01();
  if (outage(t)) return true;
  return u < (burst(channel, t) ? faults_.bursts.bad_loss : loss);
}

DatagramFaults::Fate DatagramFaults::command(std::string_view text, TimeNs t) {
  Fate f;
  f.lost = lost(command_, faults_.commands.loss, Channel::command, t);
  f.twice = command_.bernoulli(faults_.commands.duplicate);
  const std::string& prefix = faults_.lost_command_prefix;
  if (!prefix.empty() && text.starts_with(prefix)) {
    ++prefixed_commands_seen_;
    if (faults_.lost_command_count == 0 || prefixed_commands_seen_ <= faults_.lost_command_count) f.lost = true;
  }
  return f;
}

DatagramFaults::Fate DatagramFaults::reply(TimeNs t) {
  Fate f;
  f.lost = lost(reply_, faults_.replies.loss, Channel::reply, t);
  f.late = reply_.bernoulli(faults_.late_replies);
  f.twice = reply_.bernoulli(faults_.replies.duplicate);
  return f;
}

DatagramFaults::Fate DatagramFaults::state(TimeNs t) {
  Fate f;
  f.lost = lost(state_, faults_.state.loss, Channel::state, t);
  f.twice = state_.bernoulli(faults_.state.duplicate);
  return f;
}

bool DatagramFaults::frame_lost() { return frame_.bernoulli(faults_.video_frame_loss); }

bool DatagramFaults::video_datagram_lost(TimeNs t) { return lost(video_, faults_.video.loss, Channel::video, t); }

DatagramFaults::Refusal DatagramFaults::refusal() {
  Refusal r;
  r.not_joystick = error_.bernoulli(faults_.not_joystick);
  r.no_valid_imu = error_.bernoulli(faults_.no_valid_imu);
  return r;
}

bool DatagramFaults::video_stalled(TimeNs t) const {
  const std::optional<double>& start_s = faults_.video_stall_start_s;
  return start_s && t >= seconds_to_ns(*start_s) && t < seconds_to_ns(*start_s + faults_.video_stall_duration_s);
}

TimeNs DatagramFaults::due(Channel channel, TimeNs t) {
  const ChannelFaults& c = channel == Channel::command ? faults_.commands
                           : channel == Channel::reply ? faults_.replies
                           : channel == Channel::state ? faults_.state
                                                       : faults_.video;
  RandomStream& jitter = channel == Channel::command ? command_jitter_
                         : channel == Channel::reply ? reply_jitter_
                         : channel == Channel::state ? state_jitter_
                                                     : video_jitter_;
  TimeNs& last = last_due_[static_cast<int>(channel)];
  last = std::max(last, t + jittered_ms(jitter, c.delay_ms, c.jitter_ms));
  return last;
}

TimeNs DatagramFaults::reply_due(const Fate& fate, TimeNs t) {
  const TimeNs due_ns = due(Channel::reply, t);
  return fate.late ? due_ns + ms_to_ns(faults_.late_reply_ms) : due_ns;
}

}  // namespace shelfcross::verification
