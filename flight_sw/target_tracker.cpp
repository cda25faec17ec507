#include "flight_sw/target_tracker.hpp"

#include <algorithm>
#include <cmath>

#include <opencv2/calib3d.hpp>

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
  const cv::Matx33d K(k.fx_px, 0, k.cx_px, 0, k.fy_px, k.cy_px, 0, 0, 1);
  const cv::Vec<double, 5> dist(k.k1, k.k2, k.p1, k.p2, k.k3);

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

Eigen::Vector3d crossing_direction_K(const KnownShelf& shelf, const PoseEstimate& pose) {
  const Eigen::Vector3d aim(0.5 * shelf.depth_m, 0.0, 0.0);
  return (aim - pose.p_FB_m()).normalized();
}

std::optional<std::string> crossing_refusal(const FlightConfig& config, CellIndex target, const PoseEstimate& pose,
                                            const CrossingGateInput& input) {
  const MissionParams& m = config.mission;
  const Eigen::Vector2d opening = cell_opening_m(config.shelf, target);
  const double psi = std::abs(pose.yaw_rad);
  // Footprint across the opening of a vehicle turned by psi (its heading is held).
  const double footprint = m.vehicle_size_m.y() * std::cos(psi) + m.vehicle_size_m.x() * std::sin(psi);
  const double tol_y = 0.5 * (opening.x() - footprint) - m.crossing_margin_m;
  const double tol_z = 0.5 * (opening.y() - m.vehicle_size_m.z()) - m.crossing_margin_m;
  const Eigen::Vector3d p = pose.p_FB_m();
  const Eigen::Vector3d d = crossing_direction_K(config.shelf, pose);
  // Where the crossing line meets the front and back faces.
  const auto at = [&](double x) -> Eigen::Vector3d { return p + d * ((x - p.x()) / d.x()); };
  const Eigen::Vector3d front = at(0.0), back = at(config.shelf.depth_m);
  // Identity first: a well centred crossing of the wrong cell is a collision.
  if (input.identity != CellIdentity::Confirmed) return std::string("target cell not identified (") + cell_identity_name(input.identity) + ")";
  // The pose is honest only if it is recent (frames may drop) and the vehicle was not moving
  // sideways when it was taken: the video latency hides up to V_y (latency + tau) of motion.
  if (input.pose_age_s > m.pose_fresh_s) return "last pose too old";
  if (input.still_for_s < m.settle_s) return "still moving sideways";
  if (psi > m.crossing_yaw_tolerance_rad) return "heading off the cell normal";
  if (d.x() <= 0.0 || std::abs(front.y()) > tol_y || std::abs(back.y()) > tol_y) return "off-centre laterally";
  if (std::abs(front.z()) > tol_z || std::abs(back.z()) > tol_z) return "off-centre vertically";
  // The height now, by the state record: the pose shows the vehicle a video latency ago
  // (0.1-0.35 s), and in that time a vehicle still settling vertically moves centimetres. The
  // crossing holds the cell centre's height by the state height from where the vehicle is now;
  // a vertical speed vz carries it about vz * vertical_lag_s further before the hold turns it.
  // Both heights must leave the vehicle crossing_margin_m clear of the beams.
  if (!input.height_above_cell_m) return std::string("cell height not measured against the state height");
  const double z_now = *input.height_above_cell_m, z_carried = z_now + input.vz_mps * m.vertical_lag_s;
  if (std::abs(z_now) > tol_z || std::abs(z_carried) > tol_z) return "off the cell's height by the state height";
  return std::nullopt;
}

}  // namespace shelfcross::flight_sw
