#pragma once
// The target cell's four corner tags in the picture: where they were last measured (the
// tracked box), how the box is followed from picture to picture (BoxFollower), and how the
// four tags are found again around a predicted box (CornerTagSearch). The pose they give and
// its plausibility: target_pose.hpp; the tracker that ties them: target_tracker.hpp.

#include <array>
#include <optional>
#include <vector>

#include <opencv2/core.hpp>

#include "flight_sw/config.hpp"
#include "flight_sw/navigation/navigation.hpp"
#include "flight_sw/perception/box_tracker.hpp"
#include "flight_sw/perception/shelf_view.hpp"
#include "shelfcross/sdk_messages.hpp"

// Median Flow's base class, declared as opencv2/tracking/tracking_legacy.hpp does: the follower
// holds one by pointer, and only corner_tags.cpp needs the tracking module's headers.
namespace cv::legacy {
inline namespace tracking {
class Tracker;
}  // namespace tracking
}  // namespace cv::legacy

namespace shelfcross::flight_sw {

cv::Point2d centre_of(const cv::Rect2d& r);

/// The tracked box: the bounding box of the corner tags' centres `q` grown by half a tag side
/// `side` on every side. (cv::boundingRect of the centres as float points: the smallest integer
/// rectangle holding them, right and bottom edges exclusive.)
cv::Rect2d corner_box(const std::array<cv::Point2d, 4>& q, double side);

/// The target cell's four corner tags (cell_corner_tags_K order) as seen from the camera of
/// `pose_K` (projected with the intrinsics and the distortion). Empty when a tag would lie
/// behind the camera.
std::optional<std::array<cv::Point2d, 4>> corners_seen_from(const FlightConfig& config, CellIndex cell,
                                                            const PoseEstimate& pose_K);

/// Where the follower puts the box in a picture, and whether it could (else: the last box).
struct BoxPrediction {
  cv::Rect2d box_px;
  bool tracker_ok = false;
};

/// The box followed by its image motion: the fast pipeline's constant image velocity
/// (BoxTracker), the reference pipeline's Median Flow.
class BoxFollower {
 public:
  explicit BoxFollower(bool fast) : fast_(fast) {}
  /// Starts following `box` in the picture `bgr` taken at `t_ns`.
  void start(const cv::Mat& bgr, const cv::Rect2d& box, TimeNs t_ns);
  /// Where the box is in `pic`; `last_box` where the follower cannot say.
  BoxPrediction predict(const Picture& pic, const cv::Rect2d& last_box);
  /// The box measured in `pic` at `measured_box` after `prediction`: followed from there (Median
  /// Flow is re-seeded when it failed or drifted off the tags).
  void correct(const Picture& pic, const BoxPrediction& prediction, const cv::Rect2d& measured_box);
  /// Stops Median Flow (the fast pipeline's BoxTracker is restarted by start()).
  void release() { tracker_.release(); }

 private:
  bool fast_ = true;
  cv::Ptr<cv::legacy::Tracker> tracker_;  ///< reference pipeline: Median Flow
  BoxTracker box_tracker_;                ///< fast pipeline: constant image velocity
};

/// The corner tags as last measured: their centres, their mean side, the box they make and
/// whether they were about to leave the view.
class CornerTags {
 public:
  const cv::Rect2d& box_px() const { return box_px_; }
  cv::Point2d box_centre_px() const { return centre_of(box_px_); }
  /// A corner tag was about to leave the view on the last measurement.
  bool near_edge() const { return near_edge_; }
  /// Mean side of the corner tags, last seen whole, px.
  double tag_side_px() const { return tag_side_px_; }
  const std::array<cv::Point2d, 4>& corner_px() const { return corner_px_; }

  /// The corners `q` of a chosen target, their mean side `side_px`.
  void seed(const std::array<cv::Point2d, 4>& q, double side_px);
  /// Corners to look for the target around (re-acquisition), the box kept.
  void set_corners(const std::array<cv::Point2d, 4>& q) { corner_px_ = q; }
  /// The corners `q` measured with mean side `side_px` in a picture of `size`: the side is kept
  /// unless a corner tag was `touched` by the picture's damage (its area may be cut by the band);
  /// near the edge when a corner lies within `edge_margin_px` plus a tag side of the border.
  void accept(const std::array<cv::Point2d, 4>& q, double side_px, bool touched, cv::Size size, double edge_margin_px);
  void clear_near_edge() { near_edge_ = false; }

 private:
  double tag_side_px_ = 0.0;              ///< mean side of the target's corner tags, last seen
  cv::Rect2d box_px_;                     ///< tracked box: corner tag centres +- half a tag
  std::array<cv::Point2d, 4> corner_px_;  ///< last measured corner tag centres
  bool near_edge_ = false;                ///< a corner tag was about to leave the view
};

/// How the predicted box moved and scaled from the last one.
struct BoxMotion {
  cv::Point2d old_c, new_c;  ///< the last box's centre, the predicted one's
  double sx = 1.0, sy = 1.0; ///< width and height ratios, predicted over last
  double growth = 1.0;       ///< sqrt(sx sy)
};
BoxMotion box_motion(const cv::Rect2d& last_box, const cv::Rect2d& predicted);

/// Finding the four corner tags around a predicted box (TargetTracker::measure): the tags in
/// a window around it, eq. 1 inside the window, each corner the nearest tag to where the box
/// puts it, and the pose from them.
class CornerTagSearch {
 public:
  enum class Outcome {
    Found,   ///< four distinct tags
    Missed,  ///< a corner without a tag, or two corners on one
    Hidden,  ///< a corner missed where the picture's damage lies
  };
  /// The window's tags: `predicted` grown by roi_expand, seeds every 0.4 tag sides (fast
  /// pipeline).
  void detect(const Picture& pic, const cv::Rect2d& predicted, double tag_side_px, TagDetector& detector,
              const PerceptionParams& perception);
  /// Eq. 1 against the target's own corner tags, `front_area_px` the area one has now; when
  /// `front_range_m` (the front tags' range) is given, the tags behind the target seen through
  /// it are ranged first and the nearest beyond the shelf's back face kept in `behind_m`.
  /// Returns how many tags were dropped as too small for the front shelf.
  int drop_tags_behind(const Picture& pic, const cv::Rect2d& predicted, double front_side_px, double front_area_px,
                       const std::optional<double>& front_range_m, const FlightConfig& config,
                       std::optional<double>& behind_m);
  /// Eq. 1 among the window's tags (keep_front_shelf).
  void keep_front_shelf(double threshold);
  /// Each of `corner_px` moved and scaled with `motion` to where the predicted box puts it, and
  /// the nearest tag to it within corner_gate of the box's size. On Found the picked tags'
  /// centres, mean side and whether the picture's damage touches one are kept.
  Outcome pick(const std::array<cv::Point2d, 4>& corner_px, const cv::Rect2d& predicted, const BoxMotion& motion,
               double tag_side_px, const Picture& pic, const PerceptionParams& perception);
  /// The camera pose in the cell frame of `cell` from the picked tags (estimate_pose).
  std::optional<PoseEstimate> pose(const FlightConfig& config, CellIndex cell);

  const std::array<cv::Point2d, 4>& picked_px() const { return picked_px_; }
  double picked_side_px() const { return picked_side_px_; }
  /// A picked tag's rows (+-1 px) are crossed by the picture's guessed rows.
  bool touched() const { return touched_; }

 private:
  std::vector<TagBlob> tags_;          ///< the window's tags, reused
  std::vector<cv::Point3d> pose_obj_;  ///< PnP buffers, reused
  std::vector<cv::Point2d> pose_img_;
  std::array<cv::Point2d, 4> picked_px_;
  double picked_side_px_ = 0.0;
  bool touched_ = false;
};

}  // namespace shelfcross::flight_sw
