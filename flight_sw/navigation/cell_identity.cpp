#include "flight_sw/navigation/cell_identity.hpp"

#include <algorithm>
#include <cmath>

#include <opencv2/calib3d.hpp>

#include "flight_sw/navigation/corner_tags.hpp"

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

/// The hypothesis under judgement: the known grid with K's origin at the target cell's centre,
/// the camera, and what the picture shows.
struct Hypothesis {
  Hypothesis(CellIndex target, const std::vector<TagBlob>& tags_in, const FlightConfig& config_in,
             const IdentityCheckParams& params_in)
      : s(config_in.shelf), k(config_in.camera), config(config_in), params(params_in), tags(tags_in),
        o_G(cell_centre_G(s, target)),
        min_pitch(std::min(*std::min_element(s.column_pitch_m.begin(), s.column_pitch_m.end()),
                           *std::min_element(s.row_pitch_m.begin(), s.row_pitch_m.end()))),
        K(camera_matrix(k)), dist(distortion(k)) {}
  const KnownShelf& s;
  const CameraIntrinsics& k;
  const FlightConfig& config;
  const IdentityCheckParams& params;
  const std::vector<TagBlob>& tags;
  const Eigen::Vector3d o_G;  ///< K's origin in G (K = G moved)
  const double min_pitch;
  const cv::Matx33d K;
  const cv::Vec<double, 5> dist;
};

/// The grid and its continuation beyond the edges, placed by a pose (camera in K): every real
/// node and every place one pitch beyond an edge in front of the camera, projected.
std::vector<Node> place_grid(const Hypothesis& h, const Eigen::Isometry3d& X_KC_pose) {
  const KnownShelf& s = h.s;
  const Eigen::Isometry3d X_CK = X_KC_pose.inverse();
  std::vector<Node> placed;
  std::vector<cv::Point3d> p_C;
  for (int i = -1; i <= s.columns() + 1; ++i) {
    for (int j = -1; j <= s.levels() + 1; ++j) {
      const bool real = i >= 0 && i <= s.columns() && j >= 0 && j <= s.levels();
      const bool beside_edge = (i == -1 || i == s.columns() + 1) != (j == -1 || j == s.levels() + 1);
      if (!real && !beside_edge) continue;  // the corners beyond both edges say nothing more
      const Eigen::Vector3d p_K(-s.tag_offset_m, post_y_G(s, i) - h.o_G.y(), beam_z_G(s, j) - h.o_G.z());
      const Eigen::Vector3d c = X_CK * p_K;
      if (c.z() < 0.1) continue;  // behind or at the camera
      Node n;
      n.post = i;
      n.beam = j;
      n.real = real;
      n.p_K = p_K;
      n.side_px = h.k.fx_px * s.tag_size_m / c.z();
      n.pitch_px = h.k.fx_px * h.min_pitch / c.z();
      placed.push_back(n);
      p_C.emplace_back(c.x(), c.y(), c.z());
    }
  }
  std::vector<cv::Point2d> px;
  if (!p_C.empty()) cv::projectPoints(p_C, cv::Vec3d(0, 0, 0), cv::Vec3d(0, 0, 0), h.K, h.dist, px);
  for (size_t n = 0; n < placed.size(); ++n) {
    placed[n].px = px[n];
    const double m = h.params.border_tag_sides * placed[n].side_px;
    placed[n].in_view = px[n].x >= m && px[n].y >= m && px[n].x <= h.k.width_px - 1 - m && px[n].y <= h.k.height_px - 1 - m;
  }
  return placed;
}

/// Eq. 1 against the pose: a tag of the front shelf at a node has about side_px^2 pixels; a tag
/// of a shelf d behind, seen from range r, (r / (r + d))^2 of that. The nearest such tag within
/// `gate_pitch` of a pitch of the node is the node's tag (or none).
const TagBlob* observed_at(const Hypothesis& h, const Node& node, double gate_pitch) {
  const double front_area = node.side_px * node.side_px;
  const double gate = gate_pitch * node.pitch_px;
  const TagBlob* best = nullptr;
  for (const TagBlob& t : h.tags) {
    const double d = cv::norm(t.centre_px - node.px);
    if (t.area_px >= h.config.perception.area_ratio_threshold * front_area && d <= gate &&
        (!best || d < cv::norm(best->centre_px - node.px))) {
      best = &t;
    }
  }
  return best;
}

/// The grid registered on the picture: the 4-tag pose is weak in heading far out (0.1 rad is
/// 0.2 m of y at 2 m, flight_sw/README.md), enough to put the far nodes a third of a pitch off.
/// So the real nodes matched with a wide gate (0.45 pitch) give a pose on every matched tag
/// (PnP, at least 6), and the nodes are placed again by it. A box slid by a column still
/// registers the shifted lattice: its edges then fall where the shelf's do not. Returns the
/// pose the nodes are placed by (`pose_K`'s without the registration); `nodes` placed by it.
Eigen::Isometry3d register_grid(const Hypothesis& h, const PoseEstimate& pose_K, std::vector<Node>& nodes) {
  Eigen::Isometry3d X_KC = pose_K.X_FC;
  nodes = place_grid(h, X_KC);
  std::vector<cv::Point3d> obj;
  std::vector<cv::Point2d> img;
  for (const Node& n : nodes) {
    if (!n.real || !n.in_view) continue;
    if (const TagBlob* t = observed_at(h, n, 0.45)) {
      obj.emplace_back(n.p_K.x(), n.p_K.y(), n.p_K.z());
      img.push_back(t->centre_px);
    }
  }
  if (obj.size() >= 6) {
    if (const auto refined = estimate_pose(obj, img, h.k, h.config.mount)) {
      X_KC = refined->X_FC;
      nodes = place_grid(h, X_KC);
    }
  }
  return X_KC;
}

/// The nodes in view counted, matched and missing, the places beyond the edges, and the edges:
/// an edge column (post 0 or n) seen with its tag at some beam and the place beyond it, at that
/// beam, empty; an edge level alike.
void count_nodes_and_edges(const Hypothesis& h, const std::vector<Node>& nodes, IdentityCheck& out) {
  const KnownShelf& s = h.s;
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
}

/// The cell (column, level) holding the front-plane point (y_G, z_G) with the margin inside its
/// bars: (0, 0) in a coordinate outside the grid; empty when it falls in a margin (undecided).
std::optional<CellIndex> cell_holding(const Hypothesis& h, double y_G, double z_G) {
  const KnownShelf& s = h.s;
  int column = 0, level = 0;
  bool in_margin = false;
  for (int c = 1; c <= s.columns(); ++c) {
    const double left = post_y_G(s, c - 1), right = post_y_G(s, c), margin = h.params.marker_cell_margin * (left - right);
    if (y_G <= left && y_G >= right) {
      column = c;
      in_margin = in_margin || y_G > left - margin || y_G < right + margin;
    }
  }
  for (int l = 1; l <= s.levels(); ++l) {
    const double bottom = beam_z_G(s, l - 1), top = beam_z_G(s, l), margin = h.params.marker_cell_margin * (top - bottom);
    if (z_G >= bottom && z_G <= top) {
      level = l;
      in_margin = in_margin || z_G < bottom + margin || z_G > top - margin;
    }
  }
  if (in_margin) return std::nullopt;
  return CellIndex{level, column};
}

/// Markers of the inventory's boxes: the ray through the marker's centre meets the front bars'
/// plane x_K = 0 at (y_K, z_K) (the box face lies at most a few centimetres behind it: the
/// parallax is well inside the margin); the cell there, under the hypothesis (the registered
/// pose X_KC), must be the inventory's cell of that ID.
void count_markers(const Hypothesis& h, const Eigen::Isometry3d& X_KC, const std::vector<MarkerSighting>& markers,
                   const Inventory& inventory, IdentityCheck& out) {
  const std::vector<BoxEntry> boxes = inventory.boxes();
  for (const MarkerSighting& m : markers) {
    const auto box = std::find_if(boxes.begin(), boxes.end(), [&](const BoxEntry& b) { return b.id == m.id; });
    if (box == boxes.end()) continue;  // not a box of this shelf (a shelf behind has other IDs)
    std::vector<cv::Point2d> in{m.centre_px}, norm;
    cv::undistortPoints(in, norm, h.K, h.dist);
    const Eigen::Vector3d d_K = X_KC.linear() * Eigen::Vector3d(norm[0].x, norm[0].y, 1.0);
    const Eigen::Vector3d o_K = X_KC.translation();
    if (d_K.x() <= 1e-6) continue;
    const Eigen::Vector3d p_K = o_K + d_K * ((0.0 - o_K.x()) / d_K.x());
    const std::optional<CellIndex> cell = cell_holding(h, p_K.y() + h.o_G.y(), p_K.z() + h.o_G.z());
    if (!cell) continue;
    if (cell->column == box->column && cell->level == box->level) ++out.markers_agreeing;
    else ++out.markers_disagreeing;
  }
}

/// Verdict: any disagreement contradicts; an edge counted or a marker located confirms.
void judge(const IdentityCheckParams& params, IdentityCheck& out) {
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
}

}  // namespace

IdentityCheck check_cell_identity(CellIndex target, const PoseEstimate& pose_K, const std::vector<TagBlob>& tags,
                                  const std::vector<MarkerSighting>& markers, const Inventory& inventory,
                                  const FlightConfig& config, const IdentityCheckParams& params) {
  IdentityCheck out;
  const Hypothesis h(target, tags, config, params);
  // 1. The grid and its continuation beyond the edges, registered and judged node by node.
  std::vector<Node> nodes;
  const Eigen::Isometry3d X_KC = register_grid(h, pose_K, nodes);
  for (Node& node : nodes) {
    if (node.in_view) node.occupied = observed_at(h, node, params.node_gate_pitch) != nullptr;
  }
  count_nodes_and_edges(h, nodes, out);
  // 2. Markers of the inventory's boxes.
  count_markers(h, X_KC, markers, inventory, out);
  judge(params, out);
  return out;
}

void TargetIdentity::confirm(TimeNs t_ns, const cv::Rect2d& box_px) {
  identity_ = CellIdentity::Confirmed;
  vouched_ns_ = t_ns;
  vouched_box_px_ = box_px;
  unidentified_since_ns_.reset();
}

void TargetIdentity::forget_identity() {
  identity_ = CellIdentity::Unknown;
  unidentified_since_ns_.reset();
}

// Within pose_jump_window_s the jump test compared the two poses. Beyond it, up to
// identity_continuity_s (pictures too damaged to use, a tag missed for a few frames), the box
// must be found where it was last identified, within 0.3 of its width: a box slid one column
// moves by (w_i + w_j) / 2 over a box of w_i + tag, at least 0.7 of its width on the test
// shelf, while the yaw loop holds the target's box at the image centre and the vehicle drifts
// sideways by V_y dt (8 cm in 1 s, 0.2 of a 0.4 m box at any range). A longer gap, or a box
// found elsewhere, leaves the target unidentified until a picture confirms it. Where the
// identified box is expected now: moved by the vehicle's own motion since, when this picture's
// prediction was made so from the last pose, which was the identified one (every pose accepted
// while identified vouches); the state odometry drifts centimetres over such a gap, a few
// pixels, against the 0.7 box widths a slid column moves.
void TargetIdentity::follow(const cv::Rect2d& box_now_px, TimeNs now_ns, const std::optional<cv::Rect2d>& moved_box_px,
                            TimeNs last_pose_t_ns, const MissionParams& mission) {
  const double gap_s = ns_to_seconds(now_ns - vouched_ns_);
  const std::optional<cv::Rect2d> vouched_now =
      moved_box_px && vouched_ns_ == last_pose_t_ns ? moved_box_px : vouched_box_px_;
  const bool continuous =
      gap_s <= mission.target.pose_jump_window_s ||
      (gap_s <= mission.target.identity_continuity_s && vouched_now &&
       cv::norm(centre_of(box_now_px) - centre_of(*vouched_now)) < 0.3 * vouched_now->width &&
       std::abs(box_now_px.width / vouched_now->width - 1.0) < 0.2);
  if (identity_ == CellIdentity::Confirmed && continuous) {
    vouched_ns_ = now_ns;
    vouched_box_px_ = box_now_px;
  } else if (identity_ == CellIdentity::Confirmed) {
    identity_ = CellIdentity::Unknown;
    continuity_lost_ = true;  // the mission logs it
  }
  if (identity_ != CellIdentity::Confirmed && !unidentified_since_ns_) unidentified_since_ns_ = now_ns;
}

}  // namespace shelfcross::flight_sw
