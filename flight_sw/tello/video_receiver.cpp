#include "flight_sw/tello/video_receiver.hpp"

#include <poll.h>
#include <sys/eventfd.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <stdexcept>

#include "flight_sw/tello/h264_decoder.hpp"
#include "flight_sw/tello/stream_damage.hpp"
#include "sdk/video_framing.hpp"

namespace shelfcross::tello {

struct VideoReceiver::ThreadState {
  std::unique_ptr<DatagramChannel> channel;
  H264Decoder decoder;
  in_addr drone_ip;
  FrameAssembler assembler;
  StreamDamage damage;
  ThreadState(const VideoReceiverConfig& c, std::unique_ptr<DatagramChannel> ch)
      : channel(std::move(ch)),
        drone_ip(parse_ipv4(c.drone_ip)),
        assembler(c.datagram_size, c.max_frame_bytes),
        damage(c.damaged == DamagedFrames::conceal) {}
};

VideoReceiver::VideoReceiver(VideoReceiverConfig config, const Clock& clock)
    : VideoReceiver(config, clock,
                    std::make_unique<UdpSocket>(config.local_ip, config.local_port, config.receive_buffer_bytes)) {}

VideoReceiver::VideoReceiver(VideoReceiverConfig config, const Clock& clock, std::unique_ptr<DatagramChannel> channel)
    : config_(std::move(config)), clock_(clock), mailbox_(clock, clock.now_ns()) {
  thread_state_ = std::make_unique<ThreadState>(config_, std::move(channel));
  local_port_ = thread_state_->channel->local_port();
  stop_fd_ = ::eventfd(0, EFD_NONBLOCK | EFD_CLOEXEC);
  if (stop_fd_ < 0) throw std::runtime_error(std::string("eventfd: ") + std::strerror(errno));
  if (config_.threaded) {
    if (thread_state_->channel->fd() < 0) throw std::invalid_argument("a threaded video receiver needs a pollable channel");
    thread_ = std::thread([this] { run(); });
  }
}

void VideoReceiver::service() {
  if (config_.threaded) return;
  while (auto d = thread_state_->channel->receive()) on_datagram(*d);
}

VideoReceiver::~VideoReceiver() {
  stop_ = true;
  const std::uint64_t one = 1;
  [[maybe_unused]] const ssize_t n = ::write(stop_fd_, &one, sizeof one);
  if (thread_.joinable()) thread_.join();
  ::close(stop_fd_);
}

void VideoReceiver::run() {
  DatagramChannel& channel = *thread_state_->channel;
  while (!stop_) {
    pollfd fds[2] = {{channel.fd(), POLLIN, 0}, {stop_fd_, POLLIN, 0}};
    if (::poll(fds, 2, 200) <= 0) continue;
    while (!stop_) {
      auto d = channel.receive();
      if (!d) break;
      on_datagram(*d);
    }
  }
}

void VideoReceiver::on_datagram(const Datagram& d) {
  const TimeNs now = clock_.now_ns();
  const bool from_drone = parse_ipv4(d.from.ip).s_addr == thread_state_->drone_ip.s_addr &&
                          (config_.source_port == 0 || d.from.port == config_.source_port);
  if (!mailbox_.count_datagram(from_drone, d.bytes.size())) return;
  for (AssembledFrame& f : thread_state_->assembler.add(d.bytes, now)) finish_frame(std::move(f));
}

void VideoReceiver::finish_frame(AssembledFrame f) {
  H264Decoder& decoder = thread_state_->decoder;
  bool damaged = f.lost_end;
  DecodeResult r;
  PictureEvidence evidence;
  if (f.oversize) {
    damaged = true;
  } else {
    // A frame not starting with a start code lost its first datagram.
    if (!sdk::starts_with_start_code(f.bytes)) damaged = true;
    r = decoder.decode(f.bytes);
    if (r.error) damaged = true;
    if (r.pictures == 0) damaged = true;  // a frame's worth of bytes and no picture
    evidence.slices = sdk::slice_spans(f.bytes);
    evidence.datagram_ends = std::move(f.datagram_ends);
  }
  const int pictures = r.pictures;
  FrameVerdict v = thread_state_->damage.judge(damaged, r, evidence, decoder);

  VideoFrame frame;
  if (v.hand_over && !decoder.latest_bgr(frame.bgr)) frame.bgr.release();
  const bool handed = v.hand_over && !frame.bgr.empty();
  if (handed) {
    frame.t_ns = f.t_ns;
    frame.damaged = v.damaged;
    frame.key_group = v.key_group;
    frame.damage_events = v.damage_events;
    if (frame.damaged) frame.damaged_rows = std::move(v.damaged_rows);
  }
  mailbox_.deliver({pictures, f.oversize, f.lost_end, damaged}, handed ? &frame : nullptr);
}

}  // namespace shelfcross::tello
