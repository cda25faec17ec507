#include "flight_sw/tello/frame_assembler.hpp"

#include "sdk/video_framing.hpp"

namespace shelfcross::tello {

using sdk::begins_access_unit;
using sdk::only_parameter_sets;

std::vector<AssembledFrame> FrameAssembler::add(const std::string& datagram, TimeNs now) {
  std::vector<AssembledFrame> ended;
  // The next frame begins while one is gathered: that one lost its short last datagram.
  if (begins_access_unit(datagram) &&
      (frame_overflow_ || (!frame_bytes_.empty() && !only_parameter_sets(frame_bytes_)))) {
    ended.push_back(finish(last_datagram_ns_, true));
  }
  last_datagram_ns_ = now;
  if (!frame_overflow_) {
    if (frame_bytes_.size() + datagram.size() > max_frame_bytes_) {
      frame_overflow_ = true;
      frame_bytes_.clear();
      datagram_ends_.clear();
    } else {
      frame_bytes_ += datagram;
      datagram_ends_.push_back(frame_bytes_.size());
    }
  }
  if (datagram.size() < datagram_size_ && (frame_overflow_ || !only_parameter_sets(frame_bytes_))) {
    ended.push_back(finish(now, false));
  }
  return ended;
}

AssembledFrame FrameAssembler::finish(TimeNs t_ns, bool lost_end) {
  AssembledFrame f;
  f.t_ns = t_ns;
  f.lost_end = lost_end;
  f.oversize = frame_overflow_;
  f.bytes = std::move(frame_bytes_);
  f.datagram_ends = std::move(datagram_ends_);
  frame_bytes_.clear();
  datagram_ends_.clear();
  frame_overflow_ = false;
  return f;
}

}  // namespace shelfcross::tello
