#pragma once
// The video receiver's damage bookkeeping (video_receiver.hpp, header comment): which frames
// are damaged (from the first sign of damage until a key frame decodes cleanly), which are
// handed over (conceal: every picture after the first key frame that gives one; discard: only
// undamaged ones after the first clean key frame), how many signs of damage the group of
// pictures has seen, and where in the picture the damage lies (PictureDamage). One per
// stream; used by the receiver's thread only.

#include <cstdint>
#include <memory>
#include <vector>

#include "flight_sw/tello/h264_decoder.hpp"
#include "flight_sw/tello/picture_damage.hpp"

namespace shelfcross::tello {

/// What the bookkeeping makes of one reassembled frame.
struct FrameVerdict {
  bool hand_over = false;       ///< hand its picture over
  bool damaged = false;         ///< damage since the last clean key frame (VideoFrame::damaged)
  std::int64_t key_group = 0;   ///< VideoFrame::key_group
  int damage_events = 0;        ///< VideoFrame::damage_events
  std::vector<RowSpan> damaged_rows;  ///< where the damage may lie (of a decoded picture)
};

class StreamDamage {
 public:
  /// conceal: hand over damaged (error-concealed) pictures, marked; else discard them.
  explicit StreamDamage(bool conceal) : conceal_(conceal) {}

  /// The next frame: `damaged` says whether it showed a sign of damage, `r` is what the
  /// decoder made of it (its motion and error macroblocks are moved out), `evidence` holds
  /// its slices and datagram ends, `decoder` gives the decoded picture's size.
  FrameVerdict judge(bool damaged, DecodeResult& r, PictureEvidence& evidence, const H264Decoder& decoder);

 private:
  bool conceal_;
  bool synced_ = false;             ///< a key frame decoded since the start (discard: a clean one)
  bool damaged_since_key_ = false;  ///< a sign of damage since the last clean key frame
  std::int64_t key_frames_ = 0;     ///< key frames decoded (damaged or not)
  int damage_events_ = 0;           ///< damaged frames since the last key frame (see VideoFrame)
  std::unique_ptr<PictureDamage> picture_damage_;  ///< sized by the first picture
  bool picture_lost_ = false;  ///< an access unit gave no picture: the next one's damage is unplaced
};

}  // namespace shelfcross::tello
