#include "verification/world/emulator_outbox.hpp"

#include <algorithm>

namespace shelfcross::verification {
namespace {

std::unique_ptr<tello::DatagramChannel> or_udp(std::unique_ptr<tello::DatagramChannel> given, const std::string& ip,
                                               std::uint16_t port) {
  return given ? std::move(given) : std::make_unique<tello::UdpSocket>(ip, port);
}

}  // namespace

EmulatorOutbox::EmulatorOutbox(EmulatorChannels channels, const EmulatorConfig& config)
    : command_socket_(or_udp(std::move(channels.command), config.bind_ip, config.command_port)),
      state_socket_(or_udp(std::move(channels.state), config.bind_ip, config.state_source_port)),
      video_socket_(or_udp(std::move(channels.video), config.bind_ip, config.video_source_port)),
      faults_(config.faults, config.seed) {}

EmulatorPorts EmulatorOutbox::ports() const {
  return {command_socket_->fd(), command_socket_->local_port(), state_socket_->local_port(),
          video_socket_->local_port()};
}

void EmulatorOutbox::queue_locked(TimeNs due_ns, Channel channel, const tello::Endpoint& to, std::string bytes) {
  outgoing_.push({due_ns, seq_++, channel, to, std::move(bytes)});
}

void EmulatorOutbox::send_reply_locked(TimeNs t, const std::string& text, const tello::Endpoint& to) {
  const DatagramFaults::Fate fate = faults_.reply(t);
  if (fate.lost) {
    ++counters_.replies_dropped;
    return;
  }
  const TimeNs due = faults_.reply_due(fate, t);
  if (fate.late) ++counters_.replies_late;
  queue_locked(due, Channel::reply, to, text);
  if (fate.twice) {
    ++counters_.replies_duplicated;
    queue_locked(due, Channel::reply, to, text);
  }
}

void EmulatorOutbox::send_state_locked(TimeNs t, const std::string& text, const tello::Endpoint& to) {
  const DatagramFaults::Fate fate = faults_.state(t);
  if (fate.lost) {
    ++counters_.state_dropped;
    return;
  }
  const TimeNs due = faults_.due(DatagramFaults::Channel::state, t);
  queue_locked(due, Channel::state, to, text);
  if (fate.twice) {
    ++counters_.state_duplicated;
    queue_locked(due, Channel::state, to, text);
  }
}

void EmulatorOutbox::send_frame_locked(TimeNs t_capture, std::vector<std::string> datagrams, bool key,
                                       const tello::Endpoint& to, TimeNs t_send) {
  ++counters_.frames_sent;
  if (key) ++counters_.key_frames;
  const TimeNs due = faults_.due(DatagramFaults::Channel::video, t_capture);
  for (std::string& d : datagrams) {
    if (faults_.video_datagram_lost(due)) {  // on air from its due time
      ++counters_.video_datagrams_dropped;
    } else {
      queue_locked(due, Channel::video, to, std::move(d));
    }
  }
  flush_locked(t_send);
}

void EmulatorOutbox::flush_locked(TimeNs now_ns) {
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

TimeNs EmulatorOutbox::next_due_locked(TimeNs t) const {
  return outgoing_.empty() ? t : std::min(t, outgoing_.top().due_ns);
}

}  // namespace shelfcross::verification
