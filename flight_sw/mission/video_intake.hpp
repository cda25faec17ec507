#pragma once
// The video as the mission takes it (flight_sw/README.md, "Damaged pictures"): a frame of the
// wrong size refused; a picture's worth settled once (its lost bands since the key frame,
// whether it decides), a damaged one deciding after all, its damaged rows blanked, when they
// lie perception.band_margin_px clear of the rows the decision rests on; and the video's stall
// (no frame for video_hover_s: hover; for video_land_s: land, unless the state records are
// gone too: the whole link is out, and the stall only hovers until it returns).

#include <functional>
#include <optional>

#include <opencv2/core.hpp>

#include "flight_sw/config.hpp"
#include "flight_sw/mission/facts.hpp"
#include "flight_sw/perception/shelf_view.hpp"
#include "shelfcross/camera.hpp"

namespace shelfcross::flight_sw {

/// What the video's stall asks of the mission (VideoIntake::stall).
enum class VideoStall {
  None,   ///< frames come, or the hover is already flown
  Hover,  ///< no frame for video_hover_s: hover (once per stall)
  Land    ///< no frame for video_land_s, the state records fresh: land
};

class VideoIntake {
 public:
  /// `config` must be valid and outlive this (the mission's one configuration).
  explicit VideoIntake(const FlightConfig& config) : config_(config) {}

  /// The rows the current phase's decisions rest on, from the last analysis (none: unknown).
  using DecisionRegion = std::function<std::optional<cv::Rect2d>()>;
  /// The frame `f` received now: its picture (referring to `f` or to this intake's blanked copy
  /// until the next frame), counted in the telemetry; empty for a frame of the wrong size or
  /// type. `region` is asked only for a damaged picture whose damage may lie clear of it.
  std::optional<Picture> take(const CameraFrame& f, MissionFacts& facts, const DecisionRegion& region);
  /// The vehicle is airborne from `t_ns`: frames are needed from then on.
  void airborne_from(TimeNs t_ns) { airborne_since_ns_ = t_ns; }
  /// The stall's verdict now (in a vision phase); a new stall writes its event.
  VideoStall stall(MissionFacts& facts);
  bool stalled() const { return video_stalled_; }  ///< no frame for video_hover_s, until the next one

 private:
  /// True when the frame's damage is placed and lies band_margin_px clear of `region`'s rows.
  bool damage_clear_of_decision(const CameraFrame& f, const DecisionRegion& region) const;

  const FlightConfig& config_;
  cv::Mat masked_bgr_;  ///< a damaged picture with its damaged rows blanked
  std::optional<TimeNs> last_frame_ns_;
  TimeNs airborne_since_ns_ = 0;  ///< video-stall timer floor: frames are needed from here
  TimeNs link_back_ns_ = 0;       ///< ... and from the state records' return after the link was out
  bool link_out_ = false;         ///< no fresh state record at the last stall check
  bool video_stalled_ = false;
};

}  // namespace shelfcross::flight_sw
