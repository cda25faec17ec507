#include "flight_sw/navigation/corner_tags.hpp"

#include <algorithm>
#include <cmath>

#include <opencv2/calib3d.hpp>
#include <opencv2/tracking.hpp>  // declares the trackers tracking_legacy.hpp derives from
#include <opencv2/tracking/tracking_legacy.hpp>

namespace shelfcross::flight_sw {

cv::Point2d centre_of(const cv::Rect2d& r) { return {r.x + 0.5 * r.width, r.y + 0.5 * r.height}; }

cv::Rect2d corner_box(const std::array<cv::Point2d, 4>& q, double side) {
  std::array<cv::Point2f, 4> f;
  for (size_t k = 0; k < 4; ++k) f[k] = cv::Point2f(q[k]);
  const cv::Rect centres = cv::boundingRect(f);
  return {centres.x - 0.5 * side, centres.y - 0.5 * side, centres.width + side, centres.height + side};
}

std::optional<std::array<cv::Point2d, 4>> corners_seen_from(const FlightConfig& config, CellIndex cell,
                                                            const PoseEstimate& pose_K) {
  const Eigen::Isometry3d X_CK = pose_K.X_FC.inverse();
  const auto obj = cell_corner_tags_K(config.shelf, cell);
  std::vector<cv::Point3d> p_C;
  for (const cv::Point3d& o : obj) {
    const Eigen::Vector3d c = X_CK * Eigen::Vector3d(o.x, o.y, o.z);
    if (c.z() < 0.05) return std::nullopt;
    p_C.emplace_back(c.x(), c.y(), c.z());
  }
  const CameraIntrinsics& k = config.camera;
  std::vector<cv::Point2d> px;
  cv::projectPoints(p_C, cv::Vec3d(0, 0, 0), cv::Vec3d(0, 0, 0), camera_matrix(k), distortion(k), px);
  return std::array<cv::Point2d, 4>{px[0], px[1], px[2], px[3]};
}

// ---- BoxFollower ----

void BoxFollower::start(const cv::Mat& bgr, const cv::Rect2d& box, TimeNs t_ns) {
  if (fast_) {
    box_tracker_.init(box, t_ns);
  } else {
    tracker_ = cv::legacy::TrackerMedianFlow::create();
    tracker_->init(bgr, box);
  }
}

BoxPrediction BoxFollower::predict(const Picture& pic, const cv::Rect2d& last_box) {
  BoxPrediction p{last_box, false};
  if (fast_) {
    const std::optional<cv::Rect2d> b = box_tracker_.predict(pic.t_ns);
    p.tracker_ok = b.has_value();
    if (b) p.box_px = *b;
  } else {
    p.tracker_ok = tracker_ && tracker_->update(pic.bgr, p.box_px);
    if (!p.tracker_ok) p.box_px = last_box;
  }
  return p;
}

void BoxFollower::correct(const Picture& pic, const BoxPrediction& prediction, const cv::Rect2d& measured_box) {
  if (fast_) {
    box_tracker_.correct(measured_box, pic.t_ns);
  } else {
    // Re-seed the tracker when it failed or drifted off the tags.
    const cv::Rect2d& predicted = prediction.box_px;
    const cv::Rect2d overlap = predicted & measured_box;
    const double iou = overlap.area() / (predicted.area() + measured_box.area() - overlap.area());
    if (!prediction.tracker_ok || iou < 0.7) start(pic.bgr, measured_box, pic.t_ns);
  }
}

// ---- CornerTags ----

void CornerTags::seed(const std::array<cv::Point2d, 4>& q, double side_px) {
  corner_px_ = q;
  box_px_ = corner_box(q, side_px);
  tag_side_px_ = side_px;
}

void CornerTags::accept(const std::array<cv::Point2d, 4>& q, double side_px, bool touched, cv::Size size,
                        double edge_margin_px) {
  corner_px_ = q;
  // (A touched tag's area may be cut by the band: the side is kept from clean pictures.)
  if (!touched) tag_side_px_ = side_px;
  box_px_ = corner_box(corner_px_, tag_side_px_);
  // About to leave the view: a corner tag within a tag side (plus margin) of the border.
  const double m = edge_margin_px + side_px;
  near_edge_ = false;
  for (const cv::Point2d& c : q) {
    near_edge_ = near_edge_ || c.x < m || c.y < m || c.x > size.width - 1 - m || c.y > size.height - 1 - m;
  }
}

// ---- CornerTagSearch ----

BoxMotion box_motion(const cv::Rect2d& last_box, const cv::Rect2d& predicted) {
  BoxMotion m;
  m.old_c = centre_of(last_box);
  m.new_c = centre_of(predicted);
  m.sx = predicted.width / last_box.width;
  m.sy = predicted.height / last_box.height;
  m.growth = std::sqrt(m.sx * m.sy);
  return m;
}

void CornerTagSearch::detect(const Picture& pic, const cv::Rect2d& predicted, double tag_side_px, TagDetector& detector,
                             const PerceptionParams& p) {
  const double grow_x = p.roi_expand * predicted.width, grow_y = p.roi_expand * predicted.height;
  const cv::Rect roi(cv::Point(static_cast<int>(std::floor(predicted.x - grow_x)),
                               static_cast<int>(std::floor(predicted.y - grow_y))),
                     cv::Point(static_cast<int>(std::ceil(predicted.br().x + grow_x)),
                               static_cast<int>(std::ceil(predicted.br().y + grow_y))));
  tags_.clear();
  // Fast pipeline: seeds every 0.4 tag sides (at least every 2 px, at most every 8), which
  // still puts a sample on every corner tag (exact for tags wider than the stride).
  const int stride = std::clamp(static_cast<int>(0.4 * tag_side_px), 2, 8);
  detector.detect(pic.bgr, roi, tags_, stride);
}

// The room behind the shelf, seen through the target cell: a tag of a shelf behind inside the
// box (shrunk by two tag sides: not a corner tag) lies f s / sqrt(area) from the camera along
// its axis, the front tags' plane -x_C - tag_offset (the last pose); the nearest such tag over
// the approach bounds where the crossing may end. (A tag cut by a bar looks smaller, hence
// farther: only the nearest over many pictures counts. A front corner tag cut by the picture's
// border looks small too: blobs touching the border, or within two tag sides of the box's edge,
// where the predicted box may put a corner, are left out.)
int CornerTagSearch::drop_tags_behind(const Picture& pic, const cv::Rect2d& predicted, double front_side_px,
                                      double front_area_px, const std::optional<double>& front_range_m,
                                      const FlightConfig& config, std::optional<double>& behind_m) {
  const cv::Mat& bgr = pic.bgr;
  const double threshold = config.perception.area_ratio_threshold;
  if (front_range_m) {
    const cv::Rect2d inner(predicted.x + 2.0 * front_side_px, predicted.y + 2.0 * front_side_px,
                           predicted.width - 4.0 * front_side_px, predicted.height - 4.0 * front_side_px);
    const double f_s = config.camera.fx_px * config.shelf.tag_size_m;
    for (const TagBlob& t : tags_) {
      const cv::Rect& b = t.bbox_px;
      const bool at_border = b.x <= 0 || b.y <= 0 || b.br().x >= bgr.cols || b.br().y >= bgr.rows;
      if (t.area_px >= threshold * front_area_px || at_border || !inner.contains(t.centre_px)) continue;
      const double behind = f_s / std::sqrt(t.area_px) - *front_range_m;
      // The shelf's own back face (its tags face forward too) is depth_m behind: those, with
      // the area's ranging error (about 10 %), measure up to depth + 0.15 m.
      if (behind > config.shelf.depth_m + 0.15 && (!behind_m || behind < *behind_m)) behind_m = behind;
    }
  }
  return static_cast<int>(std::erase_if(tags_, [&](const TagBlob& t) { return t.area_px < threshold * front_area_px; }));
}

void CornerTagSearch::keep_front_shelf(double threshold) { flight_sw::keep_front_shelf(tags_, threshold); }

CornerTagSearch::Outcome CornerTagSearch::pick(const std::array<cv::Point2d, 4>& corner_px, const cv::Rect2d& predicted,
                                               const BoxMotion& motion, double tag_side_px, const Picture& pic,
                                               const PerceptionParams& p) {
  const double gate = p.corner_gate * std::min(predicted.width, predicted.height);
  // Damage: the rows a lost datagram left guessed until the next key frame (CameraFrame).
  // A tag there may be shown where it was when the band was lost, or not at all.
  const std::vector<RowSpan>* damaged =
      pic.damaged_rows && !pic.damaged_rows->empty() && !pic.whole() ? pic.damaged_rows : nullptr;
  const double growth = motion.growth;
  const double expected_side_px = tag_side_px * (growth > 0.5 && growth < 2.0 ? growth : 1.0);
  std::array<int, 4> pick{-1, -1, -1, -1};
  for (size_t k = 0; k < 4; ++k) {
    const cv::Point2d d = corner_px[k] - motion.old_c;
    const cv::Point2d expect = motion.new_c + cv::Point2d(d.x * motion.sx, d.y * motion.sy);
    double best = gate;
    for (size_t i = 0; i < tags_.size(); ++i) {
      const double dist = cv::norm(tags_[i].centre_px - expect);
      if (dist < best) {
        best = dist;
        pick[k] = static_cast<int>(i);
      }
    }
    if (pick[k] < 0) {
      // Missed where the picture is guessed (within 1.5 tag sides of a guessed row, inside
      // the picture): hidden, not gone.
      const bool in_picture = expect.x >= 0.0 && expect.y >= 0.0 && expect.x < pic.bgr.cols && expect.y < pic.bgr.rows;
      if (damaged && in_picture &&
          rows_touch(*damaged, expect.y - 1.5 * expected_side_px, expect.y + 1.5 * expected_side_px)) {
        return Outcome::Hidden;
      }
      return Outcome::Missed;
    }
    for (size_t j = 0; j < k; ++j) {
      if (pick[j] == pick[k]) return Outcome::Missed;
    }
  }
  double side = 0.0;
  for (size_t k = 0; k < 4; ++k) {
    const TagBlob& t = tags_[static_cast<size_t>(pick[k])];
    picked_px_[k] = t.centre_px;
    side += 0.25 * std::sqrt(t.area_px);
  }
  picked_side_px_ = side;
  // A corner tag crossed by guessed rows (its bounding box, +-1 px): the pose may be off by
  // what the vehicle moved since the band was lost (measured: 10-20 deg of heading).
  touched_ = false;
  for (size_t k = 0; k < 4 && damaged; ++k) {
    const cv::Rect& b = tags_[static_cast<size_t>(pick[k])].bbox_px;
    touched_ = touched_ || rows_touch(*damaged, b.y - 1.0, b.y + b.height + 1.0);
  }
  return Outcome::Found;
}

std::optional<PoseEstimate> CornerTagSearch::pose(const FlightConfig& config, CellIndex cell) {
  const auto obj = cell_corner_tags_K(config.shelf, cell);
  pose_obj_.assign(obj.begin(), obj.end());
  pose_img_.assign(picked_px_.begin(), picked_px_.end());
  return estimate_pose(pose_obj_, pose_img_, config.camera, config.mount);
}

}  // namespace shelfcross::flight_sw
