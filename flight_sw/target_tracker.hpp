#pragma once
// The target tracker's identity check (issue 17): which cell of the known shelf is the tracked
// box, from what one picture shows around it, not only from where the box was last seen.
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
//      in time to be compared) leaves it unidentified.
//   2. The shelf's edges: the known grid (pitches from the configuration), placed by the
//      pose, predicts where every tag of the shelf is in the picture and where the lattice's
//      continuation one pitch beyond each edge would be. Seeing the edge column (or level)
//      with its tags and the place beyond it empty counts the target's position from that
//      edge. A tag of front-shelf size where the grid should have ended, or tags missing where
//      it should go on, contradicts the hypothesis (a box slid toward or away from an edge).
//   3. The inventory: a marker (ArUco ID) seen whose box the inventory holds in a known cell
//      must lie in that cell as the pose projects it. One agreeing marker confirms; one
//      disagreeing contradicts.
// The row is also checked against the state height on every pose (flight_software.cpp).
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

#include "flight_sw/config.hpp"
#include "flight_sw/inventory.hpp"
#include "flight_sw/navigation.hpp"
#include "flight_sw/perception.hpp"

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

/// The inputs of the crossing gate besides the pose.
struct CrossingGateInput {
  double pose_age_s = 0.0;        ///< now less the pose's frame time
  double still_for_s = 0.0;       ///< the pose's frame time less the last lateral command
  CellIdentity identity = CellIdentity::Unknown;  ///< the target's identity (never cross unless Confirmed)
  /// The vehicle's height above the target cell's centre now, m, from the state record: its
  /// height h less the cell centre's height in h's frame, measured in the approach. Empty when
  /// that was never measured (never crossed then).
  std::optional<double> height_above_cell_m;
  double vz_mps = 0.0;            ///< the state record's vertical speed (vgz), m/s, up positive
};

/// The crossing gate (flight_sw/README.md): empty when the crossing of `target` from `pose_K`
/// may start, otherwise why not. Refused unless the cell's identity is confirmed; then on the
/// pose's age and stillness, the heading and where the crossing line meets the front and back
/// faces (the footprint crossing_margin_m inside the clear opening); then on the height the
/// state record gives now and where the vertical speed carries it (vz * vertical_lag_s): both
/// must leave the vehicle's height crossing_margin_m inside the opening between the beams,
/// since the pose is a video latency old and the crossing holds the height by the state.
std::optional<std::string> crossing_refusal(const FlightConfig& config, CellIndex target,
                                            const PoseEstimate& pose_K, const CrossingGateInput& input);

/// The crossing line (open loop, docs/method.md section 3): the unit direction in K from the pose's
/// body position through the cell's centre at mid-depth, so that a residual offset y0 at range r
/// leaves only y0 (depth/2) / (r + depth/2) at either face.
Eigen::Vector3d crossing_direction_K(const KnownShelf& shelf, const PoseEstimate& pose_K);

}  // namespace shelfcross::flight_sw
