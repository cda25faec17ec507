#include "flight_sw/target_tracker.hpp"

#include <algorithm>
#include <cmath>

#include "flight_sw/mission_text.hpp"

namespace shelfcross::flight_sw {

bool heading_turning(const FlightConfig& config, double yaw_rate_radps) {
  return std::abs(yaw_rate_radps) > config.control.kp_psi * config.mission.approach.settle_psi_rad;
}

std::optional<std::string> crossing_refusal(const FlightConfig& config, CellIndex target, const PoseEstimate& pose,
                                            const CrossingGateInput& input) {
  const MissionParams& m = config.mission;
  const double psi = std::abs(pose.yaw_rad);
  const LineRoom room = line_room(config, target, pose);
  const double tol_y = room.tol_y_m, tol_z = room.tol_z_m;
  const Eigen::Vector3d d = crossing_direction_K(config.shelf, pose);
  // Identity first: a well centred crossing of the wrong cell is a collision.
  if (input.identity != CellIdentity::Confirmed) return std::string("target cell not identified (") + cell_identity_name(input.identity) + ")";
  // The pose is honest only if it is recent (frames may drop) and the vehicle was not moving
  // sideways when it was taken: the video latency hides up to V_y (latency + tau) of motion.
  if (input.pose_age_s > m.crossing.pose_fresh_s) return "last pose too old";
  if (input.still_for_s < m.approach.settle_s) return "still moving sideways";
  // The crossing flies on the heading it starts with: a heading that turned since the pose's
  // picture, or that a turn commanded now carries on turning, turns the line with it.
  if (input.heading_still_for_s < m.approach.settle_s || heading_turning(config, input.yaw_rate_cmd_radps)) {
    return "heading still turning";
  }
  if (psi > m.crossing.crossing_yaw_tolerance_rad) return "heading off the cell normal";
  if (d.x() <= 0.0 || room.offset_y_m() > tol_y) return "off-centre laterally";
  if (room.offset_z_m() > tol_z) return "off-centre vertically";
  // The height now, by the state record: the pose shows the vehicle a video latency ago
  // (0.1-0.35 s), and in that time a vehicle still settling vertically moves centimetres. The
  // crossing holds the cell centre's height by the state height from where the vehicle is now;
  // a vertical speed vz carries it about vz * vertical_lag_s further before the hold turns it.
  // Both heights must leave the vehicle crossing_margin_m clear of the beams.
  if (!input.height_above_cell_m) return std::string("cell height not measured against the state height");
  const double z_now = *input.height_above_cell_m, z_carried = z_now + input.vz_mps * m.crossing.vertical_lag_s;
  if (std::abs(z_now) > tol_z || std::abs(z_carried) > tol_z) return "off the cell's height by the state height";
  // The blind crossing: what the hover before it says the vehicle may wander (line_hold.hpp).
  const LineHoldForecast& f = input.line_hold;
  if (!f.measured) return std::string(kLineHoldNotMeasured);
  // Air that has just left the line no room is not trusted on the next quiet window: the
  // window is 2.5 s of a gust process of about 1 s correlation, a noisy estimate of the next
  // blind seconds, and a lull right after a rough window vouches for little. The calm since
  // must outlast the blind crossing (docs/method.md section 7, "A calm after rough air").
  const double blind_s = blind_crossing_s(config, -pose.p_FB_m().x());
  if (input.calm_for_s && *input.calm_for_s < blind_s) {
    return std::string(kLineCannotBeHeld) + " (calm for " + format_m(*input.calm_for_s) +
           " s since the air left no room, less than the blind crossing's " + format_m(blind_s) + " s)";
  }
  // Offset plus wander past the room: the air's doing if even an arrival centred as the
  // approach settles (within lateral_threshold_m across, settle_z_m up) would leave the wander
  // no room, and then the crossing is given up at the last attempt; else the offset's, and the
  // approach may mend it (a re-read at the last attempt, as for any off-centre arrival).
  const auto verdict = [&](double offset_m, double wander_m, double tol_m, double settled_offset_m, const char* axis) {
    const char* why = settled_offset_m + wander_m > tol_m ? kLineCannotBeHeld : kOffCentreForTheWander;
    return std::string(why) + " " + axis + " (offset " + centimetres_text(offset_m) + " + wander " +
           centimetres_text(wander_m) + " > " + centimetres_text(tol_m) + ")";
  };
  if (room.offset_y_m() + f.y_m > tol_y) {
    return verdict(room.offset_y_m(), f.y_m, tol_y, config.control.lateral_threshold_m, "across") + air_text(f);
  }
  const double offset_z = std::max(room.offset_z_m(), std::abs(z_now));
  if (offset_z + f.z_m > tol_z) return verdict(offset_z, f.z_m, tol_z, m.approach.settle_z_m, "vertically");
  return std::nullopt;
}

// ---- The tracked target ----

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
    record_.behind_tags_dropped +=
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
    case PoseVerdict::Jumped: ++record_.rejected_poses; return false;
    case PoseVerdict::Hidden: return record_.hide();
    case PoseVerdict::LevelUnsure: return record_.level_unsure();
    case PoseVerdict::WrongLevel:
      ++record_.rejected_poses;
      ++record_.wrong_level_poses;
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
  ++record_.identity_checks;
  const IdentityCheck check =
      check_cell_identity(*target_, pose, features_.tags, features_.markers, inventory, config_);
  if (check.verdict == CellIdentity::Confirmed) identification_.confirm(pic.t_ns, corners_.box_px());
  return check;
}

}  // namespace shelfcross::flight_sw
