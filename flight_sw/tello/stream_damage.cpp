#include "flight_sw/tello/stream_damage.hpp"

namespace shelfcross::tello {

FrameVerdict StreamDamage::judge(bool damaged, DecodeResult& r, PictureEvidence& evidence,
                                 const H264Decoder& decoder) {
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
  if (key && conceal_) synced_ = true;
  FrameVerdict v;
  v.hand_over = synced_ && r.pictures > 0 && (conceal_ || !damaged_since_key_);

  // Where the damage lies: followed over every decoded picture, handed over or not.
  int width_px = 0, height_px = 0;
  if (r.pictures > 0 && decoder.latest_size(width_px, height_px)) {
    if (!picture_damage_) picture_damage_ = std::make_unique<PictureDamage>(width_px, height_px);
    evidence.lost = damaged;
    evidence.unplaced = picture_lost_ && !(key && !damaged);  // a whole key frame refers to nothing
    evidence.motion = std::move(r.motion);
    evidence.error_mbs = std::move(r.error_mbs);
    evidence.concealed_mbs = r.concealed_mbs;
    evidence.refs = r.refs;
    picture_lost_ = false;
    v.damaged_rows = picture_damage_->update(evidence);
  } else if (damaged) {
    picture_lost_ = true;  // a picture the next ones may refer to is missing
  }
  v.damaged = damaged_since_key_;
  v.key_group = key_frames_;
  v.damage_events = damage_events_;
  return v;
}

}  // namespace shelfcross::tello
