#pragma once
// Reassembly of the Tello's video frames from their datagrams (docs/tello_sdk.md, Video): a
// frame ends at the first datagram shorter than the datagram size once it holds more than
// parameter sets (the Tello sends SPS and PPS as short datagrams of their own); a datagram
// that begins an access unit while a frame is gathered ends that frame too, which lost its
// short last datagram. A frame growing past the limit is dropped and reported oversize.

#include <cstddef>
#include <string>
#include <vector>

#include "shelfcross/time.hpp"

namespace shelfcross::tello {

/// One frame as reassembled.
struct AssembledFrame {
  std::string bytes;                       ///< the access unit (empty when oversize)
  std::vector<std::size_t> datagram_ends;  ///< where each datagram ended in `bytes`
  TimeNs t_ns = 0;                         ///< arrival of its newest datagram
  bool lost_end = false;                   ///< ended by the next frame's first datagram
  bool oversize = false;                   ///< grew past max_frame_bytes: dropped
};

class FrameAssembler {
 public:
  /// datagram_size: a datagram shorter than this ends a frame; max_frame_bytes: a frame
  /// growing past this is dropped.
  FrameAssembler(std::size_t datagram_size, std::size_t max_frame_bytes)
      : datagram_size_(datagram_size), max_frame_bytes_(max_frame_bytes) {}

  /// Adds a datagram from the drone that arrived at now; returns the frames it ended (none,
  /// one, or the frame that lost its end and then the one it completes).
  std::vector<AssembledFrame> add(const std::string& datagram, TimeNs now);

 private:
  AssembledFrame finish(TimeNs t_ns, bool lost_end);

  std::size_t datagram_size_;
  std::size_t max_frame_bytes_;
  std::string frame_bytes_;
  bool frame_overflow_ = false;
  TimeNs last_datagram_ns_ = 0;             ///< arrival of the newest datagram of the frame gathered
  std::vector<std::size_t> datagram_ends_;  ///< where each datagram of the frame gathered ended
};

}  // namespace shelfcross::tello
