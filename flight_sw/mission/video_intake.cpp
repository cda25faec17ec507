#include "flight_sw/mission/video_intake.hpp"

#include <algorithm>

namespace shelfcross::flight_sw {

namespace {

// `out` = the frame's picture with its damaged rows mid-grey (no tag colour, no marker).
void blank_rows(const CameraFrame& f, cv::Mat& out) {
  f.bgr.copyTo(out);
  for (const RowSpan& r : f.damaged_rows) {
    const int b = std::clamp(r.v_begin_px, 0, out.rows), e = std::clamp(r.v_end_px, 0, out.rows);
    if (e > b) out.rowRange(b, e).setTo(cv::Scalar(128, 128, 128));
  }
}

}  // namespace

std::optional<Picture> VideoIntake::take(const CameraFrame& f, MissionFacts& facts, const DecisionRegion& region) {
  LinkTelemetry& link = facts.telemetry.link;
  if (f.bgr.type() != CV_8UC3 || f.bgr.cols != config_.camera.width_px || f.bgr.rows != config_.camera.height_px) {
    ++link.bad_frames;
    return std::nullopt;
  }
  last_frame_ns_ = facts.now_ns;
  if (video_stalled_) {
    video_stalled_ = false;
    facts.telemetry.event = "video back";
  }
  // Damaged pictures (error-concealed bands, see CameraFrame): the guessed bands last until
  // the next key frame, so such frames come in runs and can show a tag where it is not, or
  // lose it. Decisions (viewpoint reached, inventory read and closed, target chosen or
  // re-acquired, crossing committed, the last centimetres before it) are taken only on
  // pictures with at most decide_max_damage_events lost bands; up to steer_max_damage_events a
  // picture steers the loops; beyond, it is video but not a view: the vehicle hovers on it.
  const int damage = f.damaged || f.damage_events > 0 ? std::max(1, f.damage_events) : 0;
  if (damage > 0) ++link.damaged_frames;
  bool decides = damage <= config_.perception.decide_max_damage_events;
  const cv::Mat* image = &f.bgr;
  if (!decides && damage_clear_of_decision(f, region)) {
    // The damage lies away from what the decisions need: decide on the rest, with the
    // guessed rows blanked so that nothing is detected in them.
    decides = true;
    blank_rows(f, masked_bgr_);
    image = &masked_bgr_;
    ++link.band_decided_frames;
  }
  return Picture{*image, facts.now_ns, damage, decides, &f.damaged_rows};
}

bool VideoIntake::damage_clear_of_decision(const CameraFrame& f, const DecisionRegion& region) const {
  const double margin = config_.perception.band_margin_px;
  if (margin < 0.0) return false;
  if (f.damaged_rows.empty()) return true;  // the damage has left the picture
  const std::optional<cv::Rect2d> rows = region();
  if (!rows) return false;
  return !rows_touch(f.damaged_rows, rows->y - margin, rows->y + rows->height + margin);
}

// The timers run on whatever input arrives (state records at 10 Hz). With the state records
// gone too, the whole link is out (a Wi-Fi re-association), not the video: nothing sent reaches
// the drone until the link returns, so a `land` gains nothing, and the ground station rides the
// outage through and bounds it (tello_pilot: failsafes.link_outage_s). The stall then only
// hovers, and from the link's return the video has video_land_s to come back (a key frame first).
VideoStall VideoIntake::stall(MissionFacts& facts) {
  const Timeouts& to = config_.timeouts;
  const bool link_live = !facts.state || facts.state_fresh();  // state records came, then stopped: out
  if (!link_live) {
    link_out_ = true;
  } else if (link_out_) {
    link_out_ = false;
    link_back_ns_ = facts.now_ns;
  }
  const TimeNs since_ns = facts.now_ns - std::max({last_frame_ns_.value_or(0), airborne_since_ns_, link_back_ns_});
  if (link_live && ns_to_seconds(since_ns) > to.video_land_s) return VideoStall::Land;
  if (ns_to_seconds(since_ns) > to.video_hover_s && !video_stalled_) {
    video_stalled_ = true;
    facts.telemetry.event = "video stalled: hovering";
    return VideoStall::Hover;
  }
  return VideoStall::None;
}

}  // namespace shelfcross::flight_sw
