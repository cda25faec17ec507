#pragma once
// The target cell's identity: which cell of the known shelf is the tracked box, from what one
// picture shows around it, not only from where the box was last seen.
//
// The tracker follows the four corner tags of a cell from frame to frame. A tag grid repeats
// itself: the corner tags of the neighbouring column or level give as good a pose as the
// target's (the state height catches a level; nothing caught a column), and after the target
// was lost, or when tags of a shelf behind are taken for the target's, the box can settle one
// column or level away. Crossing there is a collision. So the crossing needs the cell's
// identity, and identity comes from three places:
//   1. Continuity: the target chosen on a full view (every cell's grid position known) stays
//      identified as long as each accepted pose is compared with the one before it (the
//      pose-jump test of the approach). A gap (target lost, re-acquired, poses too far apart
//      in time to be compared) leaves it unidentified (TargetIdentity).
//   2. The shelf's edges: the known grid (pitches from the configuration), placed by the
//      pose, predicts where every tag of the shelf is in the picture and where the lattice's
//      continuation one pitch beyond each edge would be. Seeing the edge column (or level)
//      with its tags and the place beyond it empty counts the target's position from that
//      edge. A tag of front-shelf size where the grid should have ended, or tags missing where
//      it should go on, contradicts the hypothesis (a box slid toward or away from an edge).
//   3. The inventory: a marker (ArUco ID) seen whose box the inventory holds in a known cell
//      must lie in that cell as the pose projects it. One agreeing marker confirms; one
//      disagreeing contradicts.
// The row is also checked against the state height on every pose (target_pose.hpp,
// judge_pose).
//
// Frames: the hypothesis' cell frame K (navigation.hpp): x into the shelf, y left, z up, origin
// the cell centre on the front bars' plane. The pose X_KC is the camera in K (OpenCV camera
// axes: x right, y down, z forward). A point p_K is seen at p_C = X_KC^-1 p_K, projected with
// the intrinsics and the distortion.
//
// What counts as a tag of the front shelf here: eq. 1 against the area a front tag would have
// at that point (f tag_size / z_C)^2, not against the largest tag in a window (a window can hold
// only tags of a shelf behind, the largest of which then passes eq. 1 against itself).

#include <optional>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "flight_sw/config.hpp"
#include "flight_sw/navigation/navigation.hpp"
#include "flight_sw/perception/inventory.hpp"
#include "flight_sw/perception/shelf_view.hpp"
#include "shelfcross/sdk_messages.hpp"

namespace shelfcross::flight_sw {

enum class CellIdentity {
  Unknown,       ///< nothing in this picture says which cell it is (nor that it is wrong)
  Confirmed,     ///< counted from an edge or located by a known marker, nothing disagreeing
  Contradicted,  ///< the picture disagrees with the hypothesis: never cross on it
};
const char* cell_identity_name(CellIdentity identity);

/// The verdict on one picture and the evidence counted for it.
struct IdentityCheck {
  CellIdentity verdict = CellIdentity::Unknown;
  std::string why;             ///< the evidence that decided (for logs and refusals)
  int nodes_in_view = 0;       ///< grid tags the pose puts inside the picture
  int nodes_matched = 0;       ///< ... with a front-size tag observed there
  int nodes_missing = 0;       ///< ... without
  int beyond_in_view = 0;      ///< places one pitch beyond an edge inside the picture
  int beyond_occupied = 0;     ///< ... with a front-size tag observed there
  bool column_edge_seen = false;  ///< an edge column seen with the place beyond it empty
  bool level_edge_seen = false;   ///< an edge level alike
  int markers_agreeing = 0;    ///< inventory markers seen in their cell
  int markers_disagreeing = 0; ///< inventory markers seen in another cell
};

/// Where the check looks: the tags' image gate as a fraction of the smallest projected pitch,
/// the border margin in tag sides, and how many missing grid tags a picture may have (tags cut
/// by the picture border, a blob lost to noise) before the hypothesis is contradicted.
struct IdentityCheckParams {
  double node_gate_pitch = 0.3;    ///< an observed tag within this fraction of a pitch is at a node
  double border_tag_sides = 1.5;   ///< nodes closer than this to the border are not judged
  int max_missing_nodes = 1;
  double marker_cell_margin = 0.2; ///< a marker must be this fraction of a pitch inside its cell
};

/// Judges one picture: is the tracked box the cell `target` of the known shelf? `pose_K` is the
/// camera pose measured on the box's corner tags under that hypothesis, `tags` every tag blob
/// found in the picture (before any eq. 1; the check applies its own against the pose), and
/// `markers` the ArUco markers found in it; `inventory` the shelf's inventory (boxes by cell).
/// The verdict is Contradicted if any evidence disagrees, Confirmed if an edge was counted or a
/// marker agreed and nothing disagreed, Unknown otherwise.
IdentityCheck check_cell_identity(CellIndex target, const PoseEstimate& pose_K,
                                  const std::vector<TagBlob>& tags,
                                  const std::vector<MarkerSighting>& markers, const Inventory& inventory,
                                  const FlightConfig& config, const IdentityCheckParams& params = {});

/// The target's identity kept by continuity (1. above): confirmed on the full view the target
/// was chosen on, or by a picture check_cell_identity confirms, and kept while every accepted
/// pose follows the last identified one (mission.identity_continuity_s).
class TargetIdentity {
 public:
  CellIdentity identity() const { return identity_; }
  /// Since when the target is unidentified (empty while identified).
  const std::optional<TimeNs>& unidentified_since_ns() const { return unidentified_since_ns_; }
  /// The last successful measure found the target's continuity broken (identity to confirm).
  bool continuity_lost() const { return continuity_lost_; }

  /// The target identified on the picture at `t_ns`, its box there `box_px`.
  void confirm(TimeNs t_ns, const cv::Rect2d& box_px);
  /// Unidentified, no target (unidentified_since_ns empty).
  void forget_identity();
  /// A new picture is measured: continuity_lost() is about it alone.
  void begin_picture() { continuity_lost_ = false; }
  /// A pose accepted at `now_ns` with the target's box `box_now_px` (its corner tags, as
  /// measured) keeps the identity if it follows the last identified one: within
  /// pose_jump_window_s of it (the jump test compared the two), or within
  /// identity_continuity_s with the box found within 0.3 of its width where the identified box
  /// is expected now: `moved_box_px` (the box moved by the vehicle's own motion since the last
  /// pose, taken at `last_pose_t_ns`) when that pose was the identified one, else where it was
  /// identified. Otherwise the identity is lost (continuity_lost()); unidentified, the time
  /// since is kept.
  void follow(const cv::Rect2d& box_now_px, TimeNs now_ns, const std::optional<cv::Rect2d>& moved_box_px,
              TimeNs last_pose_t_ns, const MissionParams& mission);

 private:
  CellIdentity identity_ = CellIdentity::Unknown;
  TimeNs vouched_ns_ = 0;                     ///< the last picture that kept or confirmed it
  std::optional<cv::Rect2d> vouched_box_px_;  ///< the target's box on that picture
  std::optional<TimeNs> unidentified_since_ns_;
  bool continuity_lost_ = false;
};

}  // namespace shelfcross::flight_sw
