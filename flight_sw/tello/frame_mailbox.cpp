#include "flight_sw/tello/frame_mailbox.hpp"

#include <sys/eventfd.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <sstream>
#include <stdexcept>

namespace shelfcross::tello {
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

std::string VideoStats::text() const {
  std::ostringstream s;
  s << "datagrams=" << datagrams << " bytes=" << bytes << " foreign_datagrams=" << foreign_datagrams
    << " frames_received=" << frames_received << " oversize_frames=" << oversize_frames
    << " pictures=" << pictures << " damaged=" << damaged << " truncated=" << truncated
    << " discarded=" << discarded << " handed=" << handed << " handed_damaged=" << handed_damaged
    << " replaced=" << replaced << " taken=" << taken;
  return s.str();
}

FrameMailbox::FrameMailbox(const Clock& clock, TimeNs started_ns)
    : clock_(clock), started_ns_(started_ns), notify_fd_(make_eventfd()) {}

FrameMailbox::~FrameMailbox() { ::close(notify_fd_); }

bool FrameMailbox::count_datagram(bool from_drone, std::size_t bytes) {
  std::lock_guard lock(mutex_);
  if (!from_drone) {
    ++stats_.foreign_datagrams;
    return false;
  }
  ++stats_.datagrams;
  stats_.bytes += static_cast<std::int64_t>(bytes);
  return true;
}

void FrameMailbox::deliver(const FrameCounts& counts, VideoFrame* frame) {
  std::lock_guard lock(mutex_);
  ++stats_.frames_received;
  if (counts.oversize) ++stats_.oversize_frames;
  if (counts.lost_end) ++stats_.truncated;
  if (counts.damaged) ++stats_.damaged;
  stats_.pictures += counts.pictures;
  if (!frame) {
    stats_.discarded += counts.pictures;
    return;
  }
  frame->index = next_index_++;
  frame->handed_ns = clock_.now_ns();
  if (mailbox_) ++stats_.replaced;
  mailbox_ = std::move(*frame);
  last_frame_ns_ = mailbox_->handed_ns;
  ++stats_.handed;
  if (mailbox_->damaged) ++stats_.handed_damaged;
  signal_fd(notify_fd_);
}

std::optional<VideoFrame> FrameMailbox::take() {
  std::lock_guard lock(mutex_);
  clear_fd(notify_fd_);
  if (!mailbox_) return std::nullopt;
  std::optional<VideoFrame> out = std::move(mailbox_);
  mailbox_.reset();
  ++stats_.taken;
  return out;
}

VideoStats FrameMailbox::stats() const {
  std::lock_guard lock(mutex_);
  return stats_;
}

std::optional<TimeNs> FrameMailbox::last_frame_ns() const {
  std::lock_guard lock(mutex_);
  return last_frame_ns_;
}

bool FrameMailbox::stalled(TimeNs threshold_ns) const {
  const TimeNs now = clock_.now_ns();
  std::lock_guard lock(mutex_);
  return now - last_frame_ns_.value_or(started_ns_) > threshold_ns;
}

}  // namespace shelfcross::tello
