#include "verification/cosim/link_model.hpp"

#include <algorithm>

namespace shelfcross::verification {

LinkModel::LinkModel(const LinkSettings& settings, std::uint64_t run_seed)
    : settings_(settings),
      video_latency_(run_seed, StreamId::video_latency),
      frame_drop_(run_seed, StreamId::frame_drop),
      state_latency_(run_seed, StreamId::state_latency),
      command_latency_(run_seed, StreamId::command_latency),
      command_loss_(run_seed, StreamId::command_loss) {}

TimeNs LinkModel::jittered(RandomStream& stream, double mean_s, double jitter_s) {
  // One normal draw per message whatever the settings, so streams stay aligned across
  // configurations; truncated at 3 sigma and at zero latency.
  const double z = std::clamp(stream.normal(), -3.0, 3.0);
  return seconds_to_ns(std::max(0.0, mean_s + jitter_s * z));
}

std::optional<TimeNs> LinkModel::video_arrival(TimeNs t_capture_ns) {
  const bool dropped = frame_drop_.bernoulli(settings_.frame_drop_probability);
  const TimeNs latency = jittered(video_latency_, settings_.video_latency_mean_s, settings_.video_latency_jitter_s);
  if (dropped) return std::nullopt;
  last_video_ns_ = std::max(last_video_ns_, t_capture_ns + latency);
  return last_video_ns_;
}

TimeNs LinkModel::state_arrival(TimeNs t_send_ns) {
  const TimeNs latency = jittered(state_latency_, settings_.state_latency_mean_s, settings_.state_latency_jitter_s);
  last_state_ns_ = std::max(last_state_ns_, t_send_ns + latency);
  return last_state_ns_;
}

std::optional<TimeNs> LinkModel::command_arrival(TimeNs t_issue_ns) {
  const bool lost = command_loss_.bernoulli(settings_.command_loss_probability);
  const TimeNs latency =
      jittered(command_latency_, settings_.command_latency_mean_s, settings_.command_latency_jitter_s);
  if (lost) return std::nullopt;
  last_command_ns_ = std::max(last_command_ns_, t_issue_ns + seconds_to_ns(settings_.compute_latency_s) + latency);
  return last_command_ns_;
}

}  // namespace shelfcross::verification
