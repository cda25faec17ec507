#include "flight_sw/navigation/target_tracker.hpp"

#include <algorithm>
#include <cmath>

#include "flight_sw/text.hpp"

namespace shelfcross::flight_sw {

void TargetTracker::choose(CellIndex cell, const ShelfView& view, const cv::Mat& bgr, TimeNs t_ns,
                           const std::optional<double>& height_m) {
  target_ = cell;
  target_height_m_ = height_m;
  const auto q = cell_quad(view, cell);
  const auto idx = cell_corner_indices(view.grid, cell.level - 1, cell.column - 1);
  double side = 0.0;
  for (size_t k = 0; k < 4; ++k) side += std::sqrt(view.tags[static_cast<size_t>((*idx)[k])].area_px) * 0.25;
  corners_.seed(q, side);
  follower_.start(bgr, corners_.box_px(), t_ns);
  // Chosen on a full view, where every cell's grid position is counted from the edges.
  identification_.confirm(t_ns, corners_.box_px());
  record_.behind_m.reset();
}

void TargetTracker::forget() {
  target_.reset();
  target_height_m_.reset();
  follower_.release();
  poses_.forget_poses();
  identification_.forget_identity();
  corners_.clear_near_edge();
}

TargetTracker::Prediction TargetTracker::predict(const Picture& pic, const std::optional<OdometryFix>& odometry) {
  poses_.set_odometry_now(odometry);
  moved_box_px_.reset();
  if (poses_.pose_K() && target_ && odometry && poses_.odometry_at_pose() &&
      ns_to_seconds(pic.t_ns - poses_.pose_t_ns()) > kMotionPredictAfter_s) {
    const auto moved = corners_seen_from(config_, *target_, *poses_.carried_pose());
    if (moved) {
      // The box around the moved corners; measure() places each corner in it as the last
      // measured corners sat in the last box.
      moved_box_px_ = corner_box(*moved, corners_.tag_side_px());
      return {*moved_box_px_, true};
    }
  }
  return follower_.predict(pic, corners_.box_px());
}

void TargetTracker::correct(const Picture& pic, const Prediction& prediction) {
  follower_.correct(pic, prediction, corners_.box_px());
}

bool TargetTracker::measure(const Picture& pic, const cv::Rect2d& predicted, TagDetector& detector,
                            const RecentStates& states) {
  const TimeNs now_ns = pic.t_ns;
  identification_.begin_picture();
  record_.hidden = false;
  const PerceptionParams& p = config_.perception;
  search_.detect(pic, predicted, corners_.tag_side_px(), detector, p);
  // Where the box puts each corner: the old corners moved and scaled with the box.
  const BoxMotion motion = box_motion(corners_.box_px(), predicted);
  // Eq. 1 against the target's own corner tags (their side last measured, grown with the box):
  // the window alone is no reference, since once the target's tags have left it (lost, or
  // leaving the view) the largest tag in it may be one of a shelf behind, which eq. 1 against
  // itself would keep. A front tag has about (side sqrt(sx sy))^2 pixels; a tag of a shelf d
  // behind, seen from range r, (r / (r + d))^2 of that. (Only while the prediction is sane:
  // the box tracker's growth, extrapolated, can blow up. The tags behind are ranged only on
  // deciding pictures with a pose, and not while the corner tags leave the view: cut, they no
  // longer give the front's scale.)
  const double growth = motion.growth;
  if (corners_.tag_side_px() > 0.0 && growth > 0.5 && growth < 2.0) {
    const double front_area = corners_.tag_side_px() * corners_.tag_side_px() * motion.sx * motion.sy;
    std::optional<double> front_range_m;
    if (pic.decides && poses_.pose_K() && !corners_.near_edge() && growth > 0.8 && growth < 1.25) {
      front_range_m = -poses_.pose_K()->X_FC.translation().x() - config_.shelf.tag_offset_m;
    }
    record_.counts.behind_tags_dropped +=
        search_.drop_tags_behind(pic, predicted, corners_.tag_side_px() * growth, front_area, front_range_m, config_, record_.behind_m);
  }
  search_.keep_front_shelf(p.area_ratio_threshold);
  const CornerTagSearch::Outcome found = search_.pick(corners_.corner_px(), predicted, motion, corners_.tag_side_px(), pic, p);
  if (found == CornerTagSearch::Outcome::Hidden) return record_.hide();
  if (found == CornerTagSearch::Outcome::Missed) return false;
  const auto pose = search_.pose(config_, *target_);
  if (!pose) return false;
  const std::array<cv::Point2d, 4>& img = search_.picked_px();
  const bool touched = search_.touched();
  switch (judge_pose(config_, {*pose, now_ns, touched, 0.25 * (img[0] + img[1] + img[2] + img[3])}, poses_,
                     states.span(now_ns), target_height_m_)) {
    case PoseVerdict::Plausible: break;
    case PoseVerdict::Jumped: ++record_.counts.rejected_poses; return false;
    case PoseVerdict::Hidden: return record_.hide();
    case PoseVerdict::LevelUnsure: return record_.level_unsure();
    case PoseVerdict::WrongLevel:
      ++record_.counts.rejected_poses;
      ++record_.counts.wrong_level_poses;
      return false;
  }
  // Identity by continuity: this pose follows the last identified one (or the full view the
  // target was chosen on). (The level is checked on every pose against the state height.)
  const double side = search_.picked_side_px();
  identification_.follow(corner_box(img, side), now_ns, moved_box_px_, poses_.pose_t_ns(), config_.mission);
  poses_.accept(*pose, now_ns, pic.decides && !touched);
  corners_.accept(img, side, touched, pic.bgr.size(), config_.mission.approach.edge_margin_px);
  return true;
}

std::optional<TargetTracker::Carried> TargetTracker::carried_target(TimeNs now_ns) const {
  if (!target_ || ns_to_seconds(now_ns - poses_.pose_t_ns()) > config_.mission.approach.coast_s) return std::nullopt;
  const std::optional<PoseEstimate> carried = poses_.carried_pose();
  if (!carried) return std::nullopt;
  const auto corners = corners_seen_from(config_, *target_, *carried);
  if (!corners) return std::nullopt;
  return Carried{*carried, corner_box(*corners, corners_.tag_side_px())};
}

bool TargetTracker::reacquire(const Picture& pic, const ShelfView& view, TagDetector& detector,
                              const RecentStates& states) {
  // The target is a cell of the (possibly partial) grid near the last box: the nearest one
  // whose corner tags give a plausible pose of the right level (measure's tests), so that a
  // neighbour above or below is passed over.
  if (!view.grid.valid) return false;
  // Near where the vehicle's own motion since the last pose puts the box, if it was predicted so.
  const cv::Point2d last = centre_of(moved_box_px_ ? *moved_box_px_ : corners_.box_px());
  const double gate = 0.5 * std::min(corners_.box_px().width, corners_.box_px().height);
  std::vector<std::pair<double, std::array<int, 4>>> candidates;
  for (int r = 0; r + 1 < view.grid.rows; ++r) {
    for (int c = 0; c + 1 < view.grid.columns; ++c) {
      const auto idx = cell_corner_indices(view.grid, r, c);
      if (!idx) continue;
      cv::Point2d m(0, 0);
      for (int i : *idx) m += 0.25 * view.tags[static_cast<size_t>(i)].centre_px;
      const double d = cv::norm(m - last);
      if (d < gate) candidates.push_back({d, *idx});
    }
  }
  std::stable_sort(candidates.begin(), candidates.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
  for (const auto& [d, idx] : candidates) {
    std::array<cv::Point2d, 4> q;
    for (size_t k = 0; k < 4; ++k) q[k] = view.tags[static_cast<size_t>(idx[k])].centre_px;
    corners_.set_corners(q);
    if (measure(pic, corners_.box_px(), detector, states)) {
      follower_.start(pic.bgr, corners_.box_px(), pic.t_ns);
      return true;
    }
  }
  return false;
}

IdentityCheck TargetTracker::check_identity(const Picture& pic, const PoseEstimate& pose, TagDetector& tag_detector,
                                            MarkerDetector& marker_detector, const Inventory& inventory) {
  const cv::Mat& bgr = pic.bgr;
  // Every tag and every marker of the picture (eq. 1 is applied against the pose inside the
  // check), at the cost of a whole-frame search, paid only while the target is unidentified.
  features_.tags.clear();
  tag_detector.detect(bgr, cv::Rect(0, 0, bgr.cols, bgr.rows), features_.tags);
  features_.markers.clear();
  if (config_.perception.pipeline == PerceptionPipeline::fast) {
    const double range_m = std::max(0.1, -pose.X_FC.translation().x());
    marker_detector.detect_in(bgr, cv::Rect(0, 0, bgr.cols, bgr.rows),
                               config_.shelf.marker_size_m * config_.camera.fx_px / range_m,
                               config_.perception.marker_area_ratio_threshold, features_.markers);
  } else {
    marker_detector.detect(bgr, features_.markers);
  }
  ++record_.counts.identity_checks;
  const IdentityCheck check =
      check_cell_identity(*target_, pose, features_.tags, features_.markers, inventory, config_);
  if (check.verdict == CellIdentity::Confirmed) identification_.confirm(pic.t_ns, corners_.box_px());
  return check;
}

}  // namespace shelfcross::flight_sw
