#include "flight_sw/target_tracker.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include <opencv2/calib3d.hpp>

#include "shelfcross/rotation.hpp"

namespace shelfcross::flight_sw {

const char* cell_identity_name(CellIdentity identity) {
  switch (identity) {
    case CellIdentity::Unknown: return "unknown";
    case CellIdentity::Confirmed: return "confirmed";
    case CellIdentity::Contradicted: return "contradicted";
  }
  return "?";
}

namespace {

// y_G of post i and z_G of beam j of the known grid, continued one pitch (the edge column's or
// level's) beyond each edge: post -1 lies column_pitch[0] left of post 0, post n+1
// column_pitch[n-1] right of post n; beams alike below 0 and above the top.
double post_y_G(const KnownShelf& s, int i) {
  const int n = s.columns();
  if (i < 0) return grid_tag_G(s, 0, 0).y + s.column_pitch_m.front() * static_cast<double>(-i);
  if (i > n) return grid_tag_G(s, n, 0).y - s.column_pitch_m.back() * static_cast<double>(i - n);
  return grid_tag_G(s, i, 0).y;
}
double beam_z_G(const KnownShelf& s, int j) {
  const int n = s.levels();
  if (j < 0) return grid_tag_G(s, 0, 0).z - s.row_pitch_m.front() * static_cast<double>(-j);
  if (j > n) return grid_tag_G(s, 0, n).z + s.row_pitch_m.back() * static_cast<double>(j - n);
  return grid_tag_G(s, 0, j).z;
}

struct Node {
  int post = 0, beam = 0;
  bool real = true;  ///< a tag of the shelf; false: one pitch beyond an edge
  Eigen::Vector3d p_K = Eigen::Vector3d::Zero();
  cv::Point2d px;
  double side_px = 0.0;   ///< a front tag's side there, f tag_size / z_C
  double pitch_px = 0.0;  ///< the smallest pitch there, f min_pitch / z_C
  bool in_view = false;
  bool occupied = false;  ///< a front-size tag observed within the gate
};

}  // namespace

IdentityCheck check_cell_identity(CellIndex target, const PoseEstimate& pose_K, const std::vector<TagBlob>& tags,
                                  const std::vector<MarkerSighting>& markers, const Inventory& inventory,
                                  const FlightConfig& config, const IdentityCheckParams& params) {
  IdentityCheck out;
  const KnownShelf& s = config.shelf;
  const CameraIntrinsics& k = config.camera;
  const Eigen::Vector3d o_G = cell_centre_G(s, target);  // K's origin in G (K = G moved)
  const double min_pitch = std::min(*std::min_element(s.column_pitch_m.begin(), s.column_pitch_m.end()),
                                    *std::min_element(s.row_pitch_m.begin(), s.row_pitch_m.end()));
  const cv::Matx33d K = camera_matrix(k);
  const cv::Vec<double, 5> dist = distortion(k);

  // 1. The grid and its continuation beyond the edges, placed by a pose (camera in K).
  const auto place = [&](const Eigen::Isometry3d& X_KC_pose) {
    const Eigen::Isometry3d X_CK = X_KC_pose.inverse();
    std::vector<Node> placed;
    std::vector<cv::Point3d> p_C;
    for (int i = -1; i <= s.columns() + 1; ++i) {
      for (int j = -1; j <= s.levels() + 1; ++j) {
        const bool real = i >= 0 && i <= s.columns() && j >= 0 && j <= s.levels();
        const bool beside_edge = (i == -1 || i == s.columns() + 1) != (j == -1 || j == s.levels() + 1);
        if (!real && !beside_edge) continue;  // the corners beyond both edges say nothing more
        const Eigen::Vector3d p_K(-s.tag_offset_m, post_y_G(s, i) - o_G.y(), beam_z_G(s, j) - o_G.z());
        const Eigen::Vector3d c = X_CK * p_K;
        if (c.z() < 0.1) continue;  // behind or at the camera
        Node n;
        n.post = i;
        n.beam = j;
        n.real = real;
        n.p_K = p_K;
        n.side_px = k.fx_px * s.tag_size_m / c.z();
        n.pitch_px = k.fx_px * min_pitch / c.z();
        placed.push_back(n);
        p_C.emplace_back(c.x(), c.y(), c.z());
      }
    }
    std::vector<cv::Point2d> px;
    if (!p_C.empty()) cv::projectPoints(p_C, cv::Vec3d(0, 0, 0), cv::Vec3d(0, 0, 0), K, dist, px);
    for (size_t n = 0; n < placed.size(); ++n) {
      placed[n].px = px[n];
      const double m = params.border_tag_sides * placed[n].side_px;
      placed[n].in_view = px[n].x >= m && px[n].y >= m && px[n].x <= k.width_px - 1 - m && px[n].y <= k.height_px - 1 - m;
    }
    return placed;
  };
  // Eq. 1 against the pose: a tag of the front shelf at a node has about side_px^2 pixels; a tag
  // of a shelf d behind, seen from range r, (r / (r + d))^2 of that. The nearest such tag
  // within `gate_pitch` of a pitch of the node is the node's tag (or none).
  const auto observed_at = [&](const Node& node, double gate_pitch) -> const TagBlob* {
    const double front_area = node.side_px * node.side_px;
    const double gate = gate_pitch * node.pitch_px;
    const TagBlob* best = nullptr;
    for (const TagBlob& t : tags) {
      const double d = cv::norm(t.centre_px - node.px);
      if (t.area_px >= config.perception.area_ratio_threshold * front_area && d <= gate &&
          (!best || d < cv::norm(best->centre_px - node.px))) {
        best = &t;
      }
    }
    return best;
  };
  // The 4-tag pose is weak in heading far out (0.1 rad is 0.2 m of y at 2 m, flight_sw/README.md),
  // enough to put the far nodes a third of a pitch off. So the grid is registered first: the
  // real nodes matched with a wide gate (0.45 pitch) give a pose on every matched tag (PnP),
  // and the nodes are placed again by it. A box slid by a column still registers the shifted
  // lattice: its edges then fall where the shelf's do not.
  Eigen::Isometry3d X_KC = pose_K.X_FC;
  std::vector<Node> nodes = place(X_KC);
  {
    std::vector<cv::Point3d> obj;
    std::vector<cv::Point2d> img;
    for (const Node& n : nodes) {
      if (!n.real || !n.in_view) continue;
      if (const TagBlob* t = observed_at(n, 0.45)) {
        obj.emplace_back(n.p_K.x(), n.p_K.y(), n.p_K.z());
        img.push_back(t->centre_px);
      }
    }
    if (obj.size() >= 6) {
      if (const auto refined = estimate_pose(obj, img, k, config.mount)) {
        X_KC = refined->X_FC;
        nodes = place(X_KC);
      }
    }
  }
  for (Node& node : nodes) {
    if (node.in_view) node.occupied = observed_at(node, params.node_gate_pitch) != nullptr;
  }
  // Counts, and the edges: an edge column (post 0 or n) seen with its tag at some beam and
  // the place beyond it, at that beam, empty; an edge level alike.
  const auto find = [&](int i, int j) -> const Node* {
    for (const Node& n : nodes) {
      if (n.post == i && n.beam == j) return &n;
    }
    return nullptr;
  };
  for (const Node& n : nodes) {
    if (!n.in_view) continue;
    if (n.real) {
      ++out.nodes_in_view;
      n.occupied ? ++out.nodes_matched : ++out.nodes_missing;
    } else {
      ++out.beyond_in_view;
      if (n.occupied) ++out.beyond_occupied;
      const int edge_i = n.post < 0 ? 0 : n.post > s.columns() ? s.columns() : n.post;
      const int edge_j = n.beam < 0 ? 0 : n.beam > s.levels() ? s.levels() : n.beam;
      const Node* edge = find(edge_i, edge_j);
      if (!n.occupied && edge && edge->in_view && edge->occupied) {
        if (n.post < 0 || n.post > s.columns()) out.column_edge_seen = true;
        else out.level_edge_seen = true;
      }
    }
  }

  // 2. Markers of the inventory's boxes: the ray through the marker's centre meets the front
  // bars' plane x_K = 0 at (y_K, z_K) (the box face lies at most a few centimetres behind it:
  // the parallax is well inside the margin); the cell there, under the hypothesis, must be the
  // inventory's cell of that ID.
  const std::vector<BoxEntry> boxes = inventory.boxes();
  for (const MarkerSighting& m : markers) {
    const auto box = std::find_if(boxes.begin(), boxes.end(), [&](const BoxEntry& b) { return b.id == m.id; });
    if (box == boxes.end()) continue;  // not a box of this shelf (a shelf behind has other IDs)
    std::vector<cv::Point2d> in{m.centre_px}, norm;
    cv::undistortPoints(in, norm, K, dist);
    const Eigen::Vector3d d_K = X_KC.linear() * Eigen::Vector3d(norm[0].x, norm[0].y, 1.0);
    const Eigen::Vector3d o_K = X_KC.translation();
    if (d_K.x() <= 1e-6) continue;
    const Eigen::Vector3d p_K = o_K + d_K * ((0.0 - o_K.x()) / d_K.x());
    const double y_G = p_K.y() + o_G.y(), z_G = p_K.z() + o_G.z();
    // The cell (column, level) holding (y_G, z_G) with the margin inside its bars; -1 when it
    // falls in a margin (undecided) and 0 when outside the grid.
    int column = 0, level = 0;
    bool in_margin = false;
    for (int c = 1; c <= s.columns(); ++c) {
      const double left = post_y_G(s, c - 1), right = post_y_G(s, c), margin = params.marker_cell_margin * (left - right);
      if (y_G <= left && y_G >= right) {
        column = c;
        in_margin = in_margin || y_G > left - margin || y_G < right + margin;
      }
    }
    for (int l = 1; l <= s.levels(); ++l) {
      const double bottom = beam_z_G(s, l - 1), top = beam_z_G(s, l), margin = params.marker_cell_margin * (top - bottom);
      if (z_G >= bottom && z_G <= top) {
        level = l;
        in_margin = in_margin || z_G < bottom + margin || z_G > top - margin;
      }
    }
    if (in_margin) continue;
    if (column == box->column && level == box->level) ++out.markers_agreeing;
    else ++out.markers_disagreeing;
  }

  // Verdict: any disagreement contradicts; an edge counted or a marker located confirms.
  if (out.markers_disagreeing > 0) {
    out.verdict = CellIdentity::Contradicted;
    out.why = std::to_string(out.markers_disagreeing) + " known marker(s) in another cell";
  } else if (out.beyond_occupied > 0) {
    out.verdict = CellIdentity::Contradicted;
    out.why = "shelf tags beyond the grid's edge";
  } else if (out.nodes_missing > params.max_missing_nodes) {
    out.verdict = CellIdentity::Contradicted;
    out.why = std::to_string(out.nodes_missing) + " of " + std::to_string(out.nodes_in_view) + " grid tags missing";
  } else if (out.column_edge_seen || out.markers_agreeing > 0) {
    out.verdict = CellIdentity::Confirmed;
    out.why = out.column_edge_seen ? "counted from the shelf's edge" : "located by a known marker";
  } else {
    out.verdict = CellIdentity::Unknown;
    out.why = "no edge and no known marker in view";
  }
  return out;
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
  if (input.pose_age_s > m.pose_fresh_s) return "last pose too old";
  if (input.still_for_s < m.settle_s) return "still moving sideways";
  if (psi > m.crossing_yaw_tolerance_rad) return "heading off the cell normal";
  if (d.x() <= 0.0 || room.offset_y_m() > tol_y) return "off-centre laterally";
  if (room.offset_z_m() > tol_z) return "off-centre vertically";
  // The height now, by the state record: the pose shows the vehicle a video latency ago
  // (0.1-0.35 s), and in that time a vehicle still settling vertically moves centimetres. The
  // crossing holds the cell centre's height by the state height from where the vehicle is now;
  // a vertical speed vz carries it about vz * vertical_lag_s further before the hold turns it.
  // Both heights must leave the vehicle crossing_margin_m clear of the beams.
  if (!input.height_above_cell_m) return std::string("cell height not measured against the state height");
  const double z_now = *input.height_above_cell_m, z_carried = z_now + input.vz_mps * m.vertical_lag_s;
  if (std::abs(z_now) > tol_z || std::abs(z_carried) > tol_z) return "off the cell's height by the state height";
  // The blind crossing: what the hover before it says the vehicle may wander (line_hold.hpp).
  const LineHoldForecast& f = input.line_hold;
  if (!f.measured) return std::string(kLineHoldNotMeasured);
  if (room.offset_y_m() + f.y_m > tol_y) {
    return std::string(kLineCannotBeHeld) + " across (offset " + centimetres_text(room.offset_y_m()) + " + wander " + centimetres_text(f.y_m) +
           " > " + centimetres_text(tol_y) + ")";
  }
  if (std::max(room.offset_z_m(), std::abs(z_now)) + f.z_m > tol_z) {
    return std::string(kLineCannotBeHeld) + " vertically (offset " + centimetres_text(std::max(room.offset_z_m(), std::abs(z_now))) +
           " + wander " + centimetres_text(f.z_m) + " > " + centimetres_text(tol_z) + ")";
  }
  return std::nullopt;
}

// ---- The tracked target ----

namespace {

cv::Point2d centre_of(const cv::Rect2d& r) { return {r.x + 0.5 * r.width, r.y + 0.5 * r.height}; }

/// The tracked box: the bounding box of the corner tags' centres grown by half a tag side
/// on every side. (cv::boundingRect of the centres as float points: the smallest integer
/// rectangle holding them, right and bottom edges exclusive.)
cv::Rect2d corner_box(const std::array<cv::Point2d, 4>& q, double side) {
  std::array<cv::Point2f, 4> f;
  for (size_t k = 0; k < 4; ++k) f[k] = cv::Point2f(q[k]);
  const cv::Rect centres = cv::boundingRect(f);
  return {centres.x - 0.5 * side, centres.y - 0.5 * side, centres.width + side, centres.height + side};
}

}  // namespace

std::optional<double> cell_height_m(const std::optional<StateRecord>& state, double z_K_m) {
  if (!state) return std::nullopt;
  return cell_centre_height_m(state->height_m, z_K_m);
}

std::optional<double> row_height_m(const FlightConfig& config, const std::optional<StateRecord>& state,
                                   double v_px, double range_m) {
  if (!state) return std::nullopt;
  const CameraIntrinsics& k = config.camera;
  const double elevation = std::atan((k.cy_px - v_px) / k.fy_px) - (state->pitch_rad + config.mount.pitch_rad);
  return state->height_m + range_m * std::tan(elevation);
}


cv::Point2d TargetTracker::box_centre_px() const { return centre_of(box_px_); }

void TargetTracker::choose(CellIndex cell, const ShelfView& view, const cv::Mat& bgr, TimeNs t_ns,
                           const std::optional<double>& height_m) {
  target_ = cell;
  target_height_m_ = height_m;
  const auto q = cell_quad(view, cell);
  const auto idx = cell_corner_indices(view.grid, cell.level - 1, cell.column - 1);
  double side = 0.0;
  for (size_t k = 0; k < 4; ++k) {
    corner_px_[k] = q[k];
    side += std::sqrt(view.tags[static_cast<size_t>((*idx)[k])].area_px) * 0.25;
  }
  box_px_ = corner_box(q, side);
  tag_side_px_ = side;
  start_tracker(bgr, box_px_, t_ns);
  // Chosen on a full view, where every cell's grid position is counted from the edges.
  identity_ = CellIdentity::Confirmed;
  identity_vouched_ns_ = t_ns;
  vouched_box_px_ = box_px_;
  behind_m_.reset();
  unidentified_since_ns_.reset();
}

void TargetTracker::forget() {
  target_.reset();
  target_height_m_.reset();
  tracker_.release();
  pose_K_.reset();
  decision_pose_K_.reset();
  identity_ = CellIdentity::Unknown;
  unidentified_since_ns_.reset();
  near_edge_ = false;
}

void TargetTracker::start_tracker(const cv::Mat& bgr, const cv::Rect2d& box, TimeNs t_ns) {
  if (fast()) {
    box_tracker_.init(box, t_ns);
  } else {
    tracker_ = cv::legacy::TrackerMedianFlow::create();
    tracker_->init(bgr, box);
  }
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

double pose_jump_limit_m(const MissionParams& mission, double range_m) {
  const double r = std::max(1.0, range_m / kPoseJumpRange_m);
  return mission.pose_jump_m * r * r;
}

std::optional<PoseEstimate> TargetTracker::carried_pose() const {
  if (!pose_K_ || !odometry_now_ || !odometry_at_pose_) return std::nullopt;
  return pose_after_motion(*pose_K_, odometry_at_pose_->yaw_O_rad, odometry_now_->p_O_m - odometry_at_pose_->p_O_m,
                           wrap_pi(odometry_now_->yaw_O_rad - odometry_at_pose_->yaw_O_rad));
}

TargetTracker::Prediction TargetTracker::predict(const Picture& pic, const std::optional<OdometryFix>& odometry) {
  odometry_now_ = odometry;
  moved_box_px_.reset();
  if (pose_K_ && target_ && odometry && odometry_at_pose_ &&
      ns_to_seconds(pic.t_ns - pose_t_ns_) > kMotionPredictAfter_s) {
    const auto moved = corners_seen_from(config_, *target_, *carried_pose());
    if (moved) {
      // The box around the moved corners; measure() places each corner in it as the last
      // measured corners sat in the last box.
      moved_box_px_ = corner_box(*moved, tag_side_px_);
      return {*moved_box_px_, true};
    }
  }
  Prediction p{box_px_, false};
  if (fast()) {
    const std::optional<cv::Rect2d> b = box_tracker_.predict(pic.t_ns);
    p.tracker_ok = b.has_value();
    if (b) p.box_px = *b;
  } else {
    p.tracker_ok = tracker_ && tracker_->update(pic.bgr, p.box_px);
    if (!p.tracker_ok) p.box_px = box_px_;
  }
  return p;
}

void TargetTracker::correct(const Picture& pic, const Prediction& prediction) {
  if (fast()) {
    box_tracker_.correct(box_px_, pic.t_ns);
  } else {
    // Re-seed the tracker when it failed or drifted off the tags.
    const cv::Rect2d& predicted = prediction.box_px;
    const cv::Rect2d overlap = predicted & box_px_;
    const double iou = overlap.area() / (predicted.area() + box_px_.area() - overlap.area());
    if (!prediction.tracker_ok || iou < 0.7) start_tracker(pic.bgr, box_px_, pic.t_ns);
  }
}

// Looks for the target's four corner tags around `predicted`: tags in a window around it,
// eq. 1 inside the window, each corner the nearest tag to where the box puts it.
bool TargetTracker::measure(const Picture& pic, const cv::Rect2d& predicted, TagDetector& detector,
                            const std::optional<StateRecord>& state) {
  const cv::Mat& bgr = pic.bgr;
  const TimeNs now_ns = pic.t_ns;
  continuity_lost_ = false;
  hidden_by_damage_ = false;
  const PerceptionParams& p = config_.perception;
  const double grow_x = p.roi_expand * predicted.width, grow_y = p.roi_expand * predicted.height;
  const cv::Rect roi(cv::Point(static_cast<int>(std::floor(predicted.x - grow_x)),
                               static_cast<int>(std::floor(predicted.y - grow_y))),
                     cv::Point(static_cast<int>(std::ceil(predicted.br().x + grow_x)),
                               static_cast<int>(std::ceil(predicted.br().y + grow_y))));
  roi_tags_.clear();
  // Fast pipeline: seeds every 0.4 tag sides (at least every 2 px, at most every 8), which
  // still puts a sample on every corner tag (exact for tags wider than the stride).
  const int stride = std::clamp(static_cast<int>(0.4 * tag_side_px_), 2, 8);
  detector.detect(bgr, roi, roi_tags_, stride);
  // Where the box puts each corner: the old corners moved and scaled with the box.
  const cv::Point2d old_c = centre_of(box_px_), new_c = centre_of(predicted);
  const double sx = predicted.width / box_px_.width, sy = predicted.height / box_px_.height;
  // Eq. 1 against the target's own corner tags (their side last measured, grown with the box):
  // the window alone is no reference, since once the target's tags have left it (lost, or
  // leaving the view) the largest tag in it may be one of a shelf behind, which eq. 1 against
  // itself would keep. A front tag has about (side sqrt(sx sy))^2 pixels; a tag of a shelf d
  // behind, seen from range r, (r / (r + d))^2 of that.
  // (Only while the prediction is sane: the box tracker's growth, extrapolated, can blow up.)
  const double growth = std::sqrt(sx * sy);
  if (tag_side_px_ > 0.0 && growth > 0.5 && growth < 2.0) {
    const double front_area = tag_side_px_ * tag_side_px_ * sx * sy;
    // The room behind the shelf, seen through the target cell: a tag of a shelf behind inside
    // the box (shrunk by two tag sides: not a corner tag) lies f s / sqrt(area) from the camera
    // along its axis, the front tags' plane -x_C - tag_offset (the last pose); the nearest such
    // tag over the approach bounds where the crossing may end. (A tag cut by a bar looks
    // smaller, hence farther: only the nearest over many pictures counts. A front corner tag
    // cut by the picture's border looks small too: blobs touching the border, or within two tag
    // sides of the box's edge, where the predicted box may put a corner, are left out. Not while
    // the corner tags leave the view: cut, they no longer give the front's scale.)
    if (pic.decides && pose_K_ && !near_edge_ && growth > 0.8 && growth < 1.25) {
      const double front_side_px = tag_side_px_ * growth;
      const double front_range_m = -pose_K_->X_FC.translation().x() - config_.shelf.tag_offset_m;
      const cv::Rect2d inner(predicted.x + 2.0 * front_side_px, predicted.y + 2.0 * front_side_px,
                             predicted.width - 4.0 * front_side_px, predicted.height - 4.0 * front_side_px);
      const double f_s = config_.camera.fx_px * config_.shelf.tag_size_m;
      for (const TagBlob& t : roi_tags_) {
        const cv::Rect& b = t.bbox_px;
        const bool at_border = b.x <= 0 || b.y <= 0 || b.br().x >= bgr.cols || b.br().y >= bgr.rows;
        if (t.area_px >= p.area_ratio_threshold * front_area || at_border || !inner.contains(t.centre_px)) continue;
        const double behind_m = f_s / std::sqrt(t.area_px) - front_range_m;
        // The shelf's own back face (its tags face forward too) is depth_m behind: those, with
        // the area's ranging error (about 10 %), measure up to depth + 0.15 m.
        if (behind_m > config_.shelf.depth_m + 0.15 && (!behind_m_ || behind_m < *behind_m_)) behind_m_ = behind_m;
      }
    }
    counts_.behind_tags_dropped += static_cast<int>(std::erase_if(
        roi_tags_, [&](const TagBlob& t) { return t.area_px < p.area_ratio_threshold * front_area; }));
  }
  keep_front_shelf(roi_tags_, p.area_ratio_threshold);
  const double gate = p.corner_gate * std::min(predicted.width, predicted.height);
  // Damage: the rows a lost datagram left guessed until the next key frame (CameraFrame).
  // A tag there may be shown where it was when the band was lost, or not at all.
  const std::vector<RowSpan>* damaged =
      pic.damaged_rows && !pic.damaged_rows->empty() && !pic.whole() ? pic.damaged_rows : nullptr;
  const double expected_side_px = tag_side_px_ * (growth > 0.5 && growth < 2.0 ? growth : 1.0);
  std::array<int, 4> pick{-1, -1, -1, -1};
  for (size_t k = 0; k < 4; ++k) {
    const cv::Point2d d = corner_px_[k] - old_c;
    const cv::Point2d expect = new_c + cv::Point2d(d.x * sx, d.y * sy);
    double best = gate;
    for (size_t i = 0; i < roi_tags_.size(); ++i) {
      const double dist = cv::norm(roi_tags_[i].centre_px - expect);
      if (dist < best) {
        best = dist;
        pick[k] = static_cast<int>(i);
      }
    }
    if (pick[k] < 0) {
      // Missed where the picture is guessed (within 1.5 tag sides of a guessed row, inside
      // the picture): hidden, not gone.
      const bool in_picture = expect.x >= 0.0 && expect.y >= 0.0 && expect.x < bgr.cols && expect.y < bgr.rows;
      if (damaged && in_picture &&
          rows_touch(*damaged, expect.y - 1.5 * expected_side_px, expect.y + 1.5 * expected_side_px)) {
        return hidden();
      }
      return false;
    }
    for (size_t j = 0; j < k; ++j) {
      if (pick[j] == pick[k]) return false;
    }
  }
  const auto obj = cell_corner_tags_K(config_.shelf, *target_);
  pose_obj_.assign(obj.begin(), obj.end());
  pose_img_.clear();
  double side = 0.0;
  for (size_t k = 0; k < 4; ++k) {
    const TagBlob& t = roi_tags_[static_cast<size_t>(pick[k])];
    pose_img_.push_back(t.centre_px);
    side += 0.25 * std::sqrt(t.area_px);
  }
  // A corner tag crossed by guessed rows (its bounding box, +-1 px): the pose may be off by
  // what the vehicle moved since the band was lost (measured: 10-20 deg of heading).
  bool touched = false;
  for (size_t k = 0; k < 4 && damaged; ++k) {
    const cv::Rect& b = roi_tags_[static_cast<size_t>(pick[k])].bbox_px;
    touched = touched || rows_touch(*damaged, b.y - 1.0, b.y + b.height + 1.0);
  }
  const std::vector<cv::Point2d>& img = pose_img_;
  const auto pose = estimate_pose(pose_obj_, img, config_.camera, config_.mount);
  if (!pose) return false;
  // Plausibility: between frames the vehicle moves centimetres, so a pose that jumps further
  // than pose_jump_limit_m (+ 1 m/s of the time since the last one) or turns more than
  // pose_jump_rad (+ 1 rad/s) comes from a wrong corner tag (a neighbour's, as a true corner
  // leaves the view close to the shelf): not a measurement. Once the last pose is older than
  // pose_jump_window_s there is nothing to compare with.
  const MissionParams& mp = config_.mission;
  if (pose_K_) {
    const double dt = ns_to_seconds(now_ns - pose_t_ns_);
    const double jump_m = (pose->p_FB_m() - pose_K_->p_FB_m()).norm();
    const double turn = std::abs(wrap_pi(pose->yaw_rad - pose_K_->yaw_rad));
    const double range_m = -pose_K_->p_FB_m().x();
    if (dt <= mp.pose_jump_window_s && (jump_m > pose_jump_limit_m(mp, range_m) + 1.0 * dt ||
                                        turn > mp.pose_jump_rad + 1.0 * dt)) {
      ++counts_.rejected_poses;
      return false;
    }
  }
  // A pose from touched tags must agree with the last pose carried to now by the state
  // odometry: within the jump limit plus the odometry's drift since, within pose_jump_rad, and
  // for at most mission.coast_s after the last pose. Otherwise the picture hides the target.
  if (touched) {
    const std::optional<PoseEstimate> carried = carried_pose();
    const double age_s = ns_to_seconds(now_ns - pose_t_ns_);
    const bool agrees =
        carried && age_s <= mp.coast_s &&
        (pose->p_FB_m() - carried->p_FB_m()).norm() <=
            pose_jump_limit_m(mp, -carried->p_FB_m().x()) + kOdometryDrift_mps * age_s &&
        std::abs(wrap_pi(pose->yaw_rad - carried->yaw_rad)) <= mp.pose_jump_rad;
    if (!agrees) return hidden();
  }
  // Identity: the target cell's centre stays at one height above the take-off point. After
  // the target was lost, the tracked box can settle on the cell above or below (and the
  // jump test above no longer applies once the last pose is old); a level's corner tags make
  // as good a pose as the target's, but one a row pitch off in height. The height check tells
  // them apart: the cell centre's height must stay within 0.4 of the smallest row pitch of the
  // height found, from the grid's pose, when the target was chosen. The height is the pose's
  // (cell_height_m) when the pose's pitch agrees with the state record's: the pose solves the
  // camera's attitude, which the record gives only in whole degrees and a video latency late
  // (a Tello tipping 3 deg as it starts, stops or meets a gust moves the cell's image row by
  // 12 cm at 2.3 m). Far out, four tags leave the pose's tilt ambiguous (planar PnP's two
  // solutions: the other one tilted several degrees more, its height decimetres off); a pose
  // whose pitch disagrees falls back on the image row under the state's pitch (row_height_m).
  // (mission.level_check off: for verification studies only, to show what the check prevents.)
  if (mp.level_check && target_height_m_) {
    const bool pose_attitude_agrees =
        state && std::abs(wrap_pi(pose->pitch_rad - state->pitch_rad)) <= kLevelPitchAgreement_rad;
    const cv::Point2d c = 0.25 * (img[0] + img[1] + img[2] + img[3]);
    const auto height_m = pose_attitude_agrees ? cell_height_m(state, pose->p_FB_m().z())
                                               : row_height_m(config_, state, c.y, -pose->X_FC.translation().x());
    const auto& rows = config_.shelf.row_pitch_m;
    if (height_m && std::abs(*height_m - *target_height_m_) > 0.4 * *std::min_element(rows.begin(), rows.end())) {
      ++counts_.rejected_poses;
      ++counts_.wrong_level_poses;
      return false;
    }
  }
  // Identity by continuity: this pose follows the last identified one (or the full view the
  // target was chosen on). Within pose_jump_window_s the jump test above compared the two.
  // Beyond it, up to identity_continuity_s (pictures too damaged to use, a tag missed for a
  // few frames), the box must be found where it was last identified, within 0.3 of its width:
  // a box slid one column moves by (w_i + w_j) / 2 over a box of w_i + tag, at least 0.7 of
  // its width on the test shelf, while the yaw loop holds the target's box at the image centre
  // and the vehicle drifts sideways by V_y dt (8 cm in 1 s, 0.2 of a 0.4 m box at any range).
  // A longer gap, or a box found elsewhere, leaves the target unidentified until a picture
  // confirms it (check_identity). (The level is checked on every pose against the state height.)
  // Where the vouched box is expected now: moved by the vehicle's own motion since, when this
  // picture's prediction was made so from the last pose, which was the vouched one (every pose
  // accepted while identified vouches); the state odometry drifts centimetres over such a gap,
  // a few pixels, against the 0.7 box widths a slid column moves.
  const cv::Rect2d box_now = corner_box({img[0], img[1], img[2], img[3]}, side);
  const double gap_s = ns_to_seconds(now_ns - identity_vouched_ns_);
  const std::optional<cv::Rect2d> vouched_now =
      moved_box_px_ && identity_vouched_ns_ == pose_t_ns_ ? moved_box_px_ : vouched_box_px_;
  const bool continuous =
      gap_s <= mp.pose_jump_window_s ||
      (gap_s <= mp.identity_continuity_s && vouched_now &&
       cv::norm(centre_of(box_now) - centre_of(*vouched_now)) < 0.3 * vouched_now->width &&
       std::abs(box_now.width / vouched_now->width - 1.0) < 0.2);
  if (identity_ == CellIdentity::Confirmed && continuous) {
    identity_vouched_ns_ = now_ns;
    vouched_box_px_ = box_now;
  } else if (identity_ == CellIdentity::Confirmed) {
    identity_ = CellIdentity::Unknown;
    continuity_lost_ = true;  // the mission logs it
  }
  if (identity_ != CellIdentity::Confirmed && !unidentified_since_ns_) unidentified_since_ns_ = now_ns;
  for (size_t k = 0; k < 4; ++k) corner_px_[k] = img[k];
  pose_K_ = pose;
  pose_t_ns_ = now_ns;
  odometry_at_pose_ = odometry_now_;
  pose_decides_ = pic.decides && !touched;
  if (pose_decides_) {  // the crossing is judged on poses from nearly whole pictures only
    decision_pose_K_ = pose;
    decision_pose_t_ns_ = now_ns;
  }
  // (A touched tag's area may be cut by the band: the side is kept from clean pictures.)
  if (!touched) tag_side_px_ = side;
  box_px_ = corner_box(corner_px_, tag_side_px_);
  // About to leave the view: a corner tag within a tag side (plus margin) of the border.
  const double m = config_.mission.edge_margin_px + side;
  near_edge_ = false;
  for (const cv::Point2d& c : img) {
    near_edge_ = near_edge_ || c.x < m || c.y < m || c.x > bgr.cols - 1 - m || c.y > bgr.rows - 1 - m;
  }
  return true;
}

std::optional<TargetTracker::Carried> TargetTracker::carried_target(TimeNs now_ns) const {
  if (!target_ || ns_to_seconds(now_ns - pose_t_ns_) > config_.mission.coast_s) return std::nullopt;
  const std::optional<PoseEstimate> carried = carried_pose();
  if (!carried) return std::nullopt;
  const auto corners = corners_seen_from(config_, *target_, *carried);
  if (!corners) return std::nullopt;
  return Carried{*carried, corner_box(*corners, tag_side_px_)};
}

bool TargetTracker::hidden() {
  hidden_by_damage_ = true;
  ++counts_.hidden_target_pictures;
  return false;
}

bool TargetTracker::reacquire(const Picture& pic, const ShelfView& view, TagDetector& detector,
                              const std::optional<StateRecord>& state) {
  const cv::Mat& bgr = pic.bgr;
  // The target is a cell of the (possibly partial) grid near the last box: the nearest one
  // whose corner tags give a plausible pose of the right level (measure's tests), so that a
  // neighbour above or below is passed over.
  if (!view.grid.valid) return false;
  // Near where the vehicle's own motion since the last pose puts the box, if it was predicted so.
  const cv::Point2d last = centre_of(moved_box_px_ ? *moved_box_px_ : box_px_);
  const double gate = 0.5 * std::min(box_px_.width, box_px_.height);
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
    for (size_t k = 0; k < 4; ++k) corner_px_[k] = view.tags[static_cast<size_t>(idx[k])].centre_px;
    if (measure(pic, box_px_, detector, state)) {
      start_tracker(bgr, box_px_, pic.t_ns);
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
  frame_tags_.clear();
  tag_detector.detect(bgr, cv::Rect(0, 0, bgr.cols, bgr.rows), frame_tags_);
  frame_markers_.clear();
  if (fast()) {
    const double range_m = std::max(0.1, -pose.X_FC.translation().x());
    marker_detector.detect_in(bgr, cv::Rect(0, 0, bgr.cols, bgr.rows),
                               config_.shelf.marker_size_m * config_.camera.fx_px / range_m,
                               config_.perception.marker_area_ratio_threshold, frame_markers_);
  } else {
    marker_detector.detect(bgr, frame_markers_);
  }
  ++counts_.identity_checks;
  const IdentityCheck check = check_cell_identity(*target_, pose, frame_tags_, frame_markers_, inventory, config_);
  if (check.verdict == CellIdentity::Confirmed) {
    identity_ = CellIdentity::Confirmed;
    identity_vouched_ns_ = pic.t_ns;
    vouched_box_px_ = box_px_;
    unidentified_since_ns_.reset();
  }
  return check;
}

}  // namespace shelfcross::flight_sw
