#include "flight_sw/tello/video_receiver.hpp"

#include <poll.h>
#include <sys/eventfd.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <sstream>
#include <stdexcept>

#include "flight_sw/tello/h264_decoder.hpp"
#include "sdk/video_framing.hpp"

namespace shelfcross::tello {

using sdk::begins_access_unit;
using sdk::only_parameter_sets;
using sdk::starts_with_start_code;

std::string VideoStats::text() const {
  std::ostringstream s;
  s << "datagrams=" << datagrams << " bytes=" << bytes << " foreign_datagrams=" << foreign_datagrams
    << " frames_received=" << frames_received << " oversize_frames=" << oversize_frames
    << " pictures=" << pictures << " damaged=" << damaged << " truncated=" << truncated
    << " discarded=" << discarded << " handed=" << handed << " handed_damaged=" << handed_damaged
    << " replaced=" << replaced << " taken=" << taken;
  return s.str();
}

struct VideoReceiver::ThreadState {
  std::unique_ptr<DatagramChannel> channel;
  H264Decoder decoder;
  in_addr drone_ip;
  ThreadState(const VideoReceiverConfig& c, std::unique_ptr<DatagramChannel> ch)
      : channel(std::move(ch)), drone_ip(parse_ipv4(c.drone_ip)) {}
};

namespace {

int make_eventfd() {
  const int fd = ::eventfd(0, EFD_NONBLOCK | EFD_CLOEXEC);
  if (fd < 0) throw std::runtime_error(std::string("eventfd: ") + std::strerror(errno));
  return fd;
}

void signal_fd(int fd) {
  const std::uint64_t one = 1;
  [[maybe_unused]] const ssize_t n = ::write(fd, &one, sizeof one);
}

void clear_fd(int fd) {
  std::uint64_t v = 0;
  [[maybe_unused]] const ssize_t n = ::read(fd, &v, sizeof v);
}

}  // namespace

VideoReceiver::VideoReceiver(VideoReceiverConfig config, const Clock& clock)
    : VideoReceiver(config, clock,
                    std::make_unique<UdpSocket>(config.local_ip, config.local_port, config.receive_buffer_bytes)) {}

VideoReceiver::VideoReceiver(VideoReceiverConfig config, const Clock& clock, std::unique_ptr<DatagramChannel> channel)
    : config_(std::move(config)), clock_(clock), started_ns_(clock.now_ns()) {
  thread_state_ = std::make_unique<ThreadState>(config_, std::move(channel));
  local_port_ = thread_state_->channel->local_port();
  notify_fd_ = make_eventfd();
  stop_fd_ = make_eventfd();
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
  signal_fd(stop_fd_);
  if (thread_.joinable()) thread_.join();
  ::close(notify_fd_);
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
  {
    std::lock_guard lock(mutex_);
    if (!from_drone) {
      ++stats_.foreign_datagrams;
      return;
    }
    ++stats_.datagrams;
    stats_.bytes += static_cast<std::int64_t>(d.bytes.size());
  }
  // The next frame begins while one is gathered: that one lost its short last datagram.
  if (begins_access_unit(d.bytes) &&
      (frame_overflow_ || (!frame_bytes_.empty() && !only_parameter_sets(frame_bytes_)))) {
    finish_frame(last_datagram_ns_, true);
  }
  last_datagram_ns_ = now;
  if (!frame_overflow_) {
    if (frame_bytes_.size() + d.bytes.size() > config_.max_frame_bytes) {
      frame_overflow_ = true;
      frame_bytes_.clear();
      datagram_ends_.clear();
    } else {
      frame_bytes_ += d.bytes;
      datagram_ends_.push_back(frame_bytes_.size());
    }
  }
  if (d.bytes.size() < config_.datagram_size && (frame_overflow_ || !only_parameter_sets(frame_bytes_))) {
    finish_frame(now, false);
  }
}

void VideoReceiver::finish_frame(TimeNs t_ns, bool lost_end) {
  bool damaged = lost_end;
  bool oversize = false;
  DecodeResult r;
  PictureEvidence evidence;
  if (frame_overflow_) {
    oversize = damaged = true;
  } else {
    // A frame not starting with a start code lost its first datagram.
    if (!starts_with_start_code(frame_bytes_)) damaged = true;
    r = thread_state_->decoder.decode(frame_bytes_);
    if (r.error) damaged = true;
    if (r.pictures == 0) damaged = true;  // a frame's worth of bytes and no picture
    evidence.slices = sdk::slice_spans(frame_bytes_);
    evidence.datagram_ends = std::move(datagram_ends_);
  }
  frame_bytes_.clear();
  datagram_ends_.clear();
  frame_overflow_ = false;

  if (r.pictures > 0 && r.key_frame) {
    ++key_frames_;
    damage_events_ = 0;
  }
  if (damaged) ++damage_events_;
  // A clean key frame ends the damage (and starts the stream); any sign of damage starts it.
  // Conceal mode starts at the first key frame that gives a picture, damaged or not (at a few
  // percent of loss a clean one may take many groups to come: a key frame is 20 to 40
  // datagrams); its lost bands have no previous picture to come from and stay marked.
  const bool key = r.pictures > 0 && r.key_frame;
  if (!damaged && key && r.clean) {
    synced_ = true;
    damaged_since_key_ = false;
  } else if (damaged) {
    damaged_since_key_ = true;
  }
  if (key && config_.damaged == DamagedFrames::conceal) synced_ = true;
  const bool hand_over = synced_ && r.pictures > 0 &&
                         (config_.damaged == DamagedFrames::conceal || !damaged_since_key_);

  // Where the damage lies: followed over every decoded picture, handed over or not.
  std::vector<RowSpan> damaged_rows;
  if (r.pictures > 0 && thread_state_->decoder.latest_size(picture_width_px_, picture_height_px_)) {
    if (!picture_damage_) picture_damage_ = std::make_unique<PictureDamage>(picture_width_px_, picture_height_px_);
    evidence.lost = damaged;
    evidence.unplaced = picture_lost_ && !(key && !damaged);  // a whole key frame refers to nothing
    evidence.motion = std::move(r.motion);
    evidence.error_mbs = std::move(r.error_mbs);
    evidence.concealed_mbs = r.concealed_mbs;
    evidence.refs = r.refs;
    picture_lost_ = false;
    damaged_rows = picture_damage_->update(evidence);
  } else if (damaged) {
    picture_lost_ = true;  // a picture the next ones may refer to is missing
  }

  VideoFrame frame;
  if (hand_over && !thread_state_->decoder.latest_bgr(frame.bgr)) frame.bgr.release();
  std::lock_guard lock(mutex_);
  ++stats_.frames_received;
  if (oversize) ++stats_.oversize_frames;
  if (lost_end) ++stats_.truncated;
  if (damaged) ++stats_.damaged;
  stats_.pictures += r.pictures;
  if (!hand_over || frame.bgr.empty()) {
    stats_.discarded += r.pictures;
    return;
  }
  frame.t_ns = t_ns;
  frame.index = next_index_++;
  frame.damaged = damaged_since_key_;
  frame.key_group = key_frames_;
  frame.damage_events = damage_events_;
  if (frame.damaged) frame.damaged_rows = std::move(damaged_rows);
  frame.handed_ns = clock_.now_ns();
  if (mailbox_) ++stats_.replaced;
  mailbox_ = std::move(frame);
  last_frame_ns_ = mailbox_->handed_ns;
  ++stats_.handed;
  if (damaged_since_key_) ++stats_.handed_damaged;
  signal_fd(notify_fd_);
}

std::optional<VideoFrame> VideoReceiver::take_latest() {
  std::lock_guard lock(mutex_);
  clear_fd(notify_fd_);
  if (!mailbox_) return std::nullopt;
  std::optional<VideoFrame> out = std::move(mailbox_);
  mailbox_.reset();
  ++stats_.taken;
  return out;
}

VideoStats VideoReceiver::stats() const {
  std::lock_guard lock(mutex_);
  return stats_;
}

std::optional<TimeNs> VideoReceiver::last_frame_ns() const {
  std::lock_guard lock(mutex_);
  return last_frame_ns_;
}

bool VideoReceiver::stalled(TimeNs threshold_ns) const {
  const TimeNs now = clock_.now_ns();
  std::lock_guard lock(mutex_);
  return now - last_frame_ns_.value_or(started_ns_) > threshold_ns;
}

}  // namespace shelfcross::tello
