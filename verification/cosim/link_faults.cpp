#include "verification/cosim/link_faults.hpp"

namespace shelfcross::verification {

EmulatorFaults link_faults(const LinkSettings& l) {
  EmulatorFaults f;
  f.commands = {l.command_loss_probability, 1e3 * l.command_latency_mean_s, 1e3 * l.command_latency_jitter_s,
                l.duplicate_probability};
  f.replies = {l.reply_loss, 1e3 * l.state_latency_mean_s, 1e3 * l.state_latency_jitter_s, l.duplicate_probability};
  f.state = {l.state_loss, 1e3 * l.state_latency_mean_s, 1e3 * l.state_latency_jitter_s, l.duplicate_probability};
  f.video = {l.video_datagram_loss, 1e3 * l.video_latency_mean_s, 1e3 * l.video_latency_jitter_s, 0.0};
  f.video_frame_loss = l.frame_drop_probability;
  f.late_replies = l.late_reply_probability;
  f.late_reply_ms = 1e3 * l.late_reply_s;
  f.not_joystick = l.not_joystick_probability;
  f.no_valid_imu = l.no_valid_imu_probability;
  f.lost_command_prefix = l.lost_command;
  f.lost_command_count = l.lost_command_count;
  if (l.spells.video_stall_start_s >= 0.0 && l.spells.video_stall_duration_s > 0.0) {
    f.video_stall_start_s = l.spells.video_stall_start_s;
    f.video_stall_duration_s = l.spells.video_stall_duration_s;
  }
  f.bursts = {l.spells.burst_loss, l.spells.burst_mean_s, l.spells.burst_interval_s};
  f.outages.interval_mean_s = l.spells.outage_interval_s;
  f.outages.min_s = l.spells.outage_min_s;
  f.outages.max_s = l.spells.outage_max_s;
  if (l.spells.outage_start_s >= 0.0 && l.spells.outage_duration_s > 0.0) {
    f.outages.start_s = l.spells.outage_start_s;
    f.outages.duration_s = l.spells.outage_duration_s;
  }
  return f;
}

}  // namespace shelfcross::verification
