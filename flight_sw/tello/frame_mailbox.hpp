#pragma once
// The video receiver's hand-over (video_receiver.hpp): a single-slot mailbox (a newer frame
// replaces one not yet taken, so the taker always gets the newest frame and never a backlog),
// an eventfd readable while a frame waits, and the receiver's counters. Thread-safe: the
// receiver's thread puts, the owner takes.

#include <cstdint>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include <opencv2/core/mat.hpp>

#include "flight_sw/tello/clock.hpp"
#include "flight_sw/tello/picture_damage.hpp"

namespace shelfcross::tello {

/// One decoded frame as handed over.
struct VideoFrame {
  TimeNs t_ns = 0;          ///< arrival of the frame's last datagram
  TimeNs handed_ns = 0;     ///< when it was put in the mailbox (decoded and converted)
  std::int64_t index = 0;   ///< 0, 1, 2, ... over handed-over frames; a gap = frames replaced
  bool damaged = false;     ///< error-concealed: damage since the last clean key frame
  /// Key frames decoded before and with this frame: frames of one group of pictures share
  /// it (and their damage: it lasts until the next key frame), frames of two groups do not.
  std::int64_t key_group = 0;
  /// Frames with a sign of damage since the last key frame, this one and a damaged key frame
  /// included: 0 for a clean frame of a clean group; each lost datagram adds a band (two
  /// slices or so) concealed from the previous picture, and the bands add up until the next
  /// key frame. A measure of how much of the picture is guesswork.
  int damage_events = 0;
  /// Where the damage may lie (CameraFrame::damaged_rows; picture_damage.hpp): empty for a
  /// clean frame of a clean group, and for a damaged one whose damage has left the picture.
  std::vector<RowSpan> damaged_rows;
  cv::Mat bgr;              ///< CV_8UC3
};

struct VideoStats {
  std::int64_t datagrams = 0;
  std::int64_t bytes = 0;
  std::int64_t foreign_datagrams = 0;
  std::int64_t frames_received = 0;   ///< reassembled frames (access units) decoded
  std::int64_t oversize_frames = 0;
  std::int64_t pictures = 0;          ///< pictures the decoder produced
  std::int64_t damaged = 0;           ///< frames with a sign of damage (see header comment)
  std::int64_t discarded = 0;         ///< pictures not handed over (damaged or awaiting a key frame)
  std::int64_t truncated = 0;         ///< frames whose short last datagram was lost
  std::int64_t handed = 0;            ///< frames put in the mailbox
  std::int64_t handed_damaged = 0;    ///< of which marked damaged (concealed)
  std::int64_t replaced = 0;          ///< frames replaced in the mailbox before being taken
  std::int64_t taken = 0;
  std::string text() const;           ///< "name=value ..." on one line
};

/// How a reassembled frame went, for the counters.
struct FrameCounts {
  int pictures = 0;       ///< pictures the decoder produced from it
  bool oversize = false;
  bool lost_end = false;  ///< its short last datagram was lost
  bool damaged = false;   ///< it showed a sign of damage
};

class FrameMailbox {
 public:
  /// Stamps hand-overs with `clock` (it must outlive the mailbox); started_ns: when the
  /// receiver started (stalled() counts from it before the first frame). Throws
  /// std::runtime_error when no eventfd can be made.
  FrameMailbox(const Clock& clock, TimeNs started_ns);
  ~FrameMailbox();
  FrameMailbox(const FrameMailbox&) = delete;
  FrameMailbox& operator=(const FrameMailbox&) = delete;

  /// Counts a datagram (from the drone: counted with its bytes; else as foreign); returns
  /// from_drone.
  bool count_datagram(bool from_drone, std::size_t bytes);
  /// Counts a reassembled frame and hands `frame` over (indexed and stamped now; it replaces
  /// one not taken); null: its pictures are counted discarded.
  void deliver(const FrameCounts& counts, VideoFrame* frame);
  /// The newest frame not yet taken (the mailbox empties), or nothing.
  std::optional<VideoFrame> take();
  int notify_fd() const { return notify_fd_; }
  VideoStats stats() const;
  std::optional<TimeNs> last_frame_ns() const;
  /// True when no frame was handed over for longer than `threshold_ns` (counted from the
  /// start before the first frame).
  bool stalled(TimeNs threshold_ns) const;

 private:
  const Clock& clock_;
  TimeNs started_ns_;
  int notify_fd_ = -1;
  mutable std::mutex mutex_;  // guards the mailbox, stats and last_frame_ns_
  std::optional<VideoFrame> mailbox_;
  VideoStats stats_;
  std::optional<TimeNs> last_frame_ns_;
  std::int64_t next_index_ = 0;
};

}  // namespace shelfcross::tello
