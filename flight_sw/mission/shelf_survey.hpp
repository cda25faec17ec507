#pragma once
// The mission's first three airborne phases on one shelf (flight_software.hpp): FindShelf (turn
// and back away until the whole tag grid fits the view), GoToViewpoint (fly the grid pose to
// the optimal viewpoint, eq. 7-9, and settle there), TakeInventory (read the boxes' markers
// on inventory_frames full views, inventory.hpp). It owns the shelf's view, its detectors, the
// inventories of this shelf and of the finished ones; each phase step says what to fly and
// whether the phase is over, and the mission takes the transition.

#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include "flight_sw/config.hpp"
#include "flight_sw/control/control.hpp"
#include "flight_sw/navigation/navigation.hpp"
#include "flight_sw/perception/inventory.hpp"
#include "flight_sw/perception/shelf_view.hpp"

namespace shelfcross::flight_sw {

struct Telemetry;

/// What a phase step asks of the mission: the velocity to fly (or a hover: zero, the PI
/// loops restarted) and the phase that follows.
struct SurveyStep {
  enum class Next {
    Stay,              ///< the phase goes on
    WholeShelfInView,  ///< FindShelf -> GoToViewpoint
    ShelfOutOfView,    ///< GoToViewpoint -> FindShelf
    AtViewpoint,       ///< GoToViewpoint -> TakeInventory
    InventoryTaken     ///< TakeInventory: the target, the transfer, or no empty cell
  };
  Next next = Next::Stay;
  std::optional<VelocityCommand> velocity;  ///< flown when set
  bool hover = false;  ///< after the velocity, if both (it then also counts as set now)
};

class ShelfSurvey {
 public:
  /// `config` must be valid (validate_flight_config) and outlive this (the mission's one
  /// configuration, held by reference).
  explicit ShelfSurvey(const FlightConfig& config);

  /// FindShelf on a picture. `back_out`: a re-read from close, backing straight out whatever
  /// is in view (a whole grid that close is the next shelf's, through a cell). A whole grid
  /// in view on a deciding picture ends the phase (the mission enters GoToViewpoint and
  /// steps it on the same picture, `view_fresh`).
  SurveyStep find_shelf(const Picture& pic, bool back_out, Telemetry& telemetry);
  /// GoToViewpoint on a picture; `view_fresh`: this picture was analysed already.
  SurveyStep go_to_viewpoint(const Picture& pic, TimeNs now_ns, bool view_fresh, Telemetry& telemetry);
  /// TakeInventory on a picture: hovers; InventoryTaken once inventory_frames full views are
  /// read and every cell without a box has been seen whole often enough (inventory.hpp).
  SurveyStep take_inventory(const Picture& pic, Telemetry& telemetry);
  /// TakeInventory's time has run out: true, once per shelf, when no deciding picture has
  /// shown the whole grid for viewpoint_lost_s up to `now_ns` (the mission then searches for
  /// the shelf again; the readings so far are kept).
  bool search_again(TimeNs now_ns);
  /// The phase's settling restarts (every phase change).
  void restart_settling() { at_viewpoint_.settled_frames = 0; }

  /// The shelf's view analysed anew on `bgr` (the approach's re-acquisition).
  void analyse(const cv::Mat& bgr, Telemetry& telemetry);

  /// The next shelf: this one's inventory finished, a new one begun, the viewpoint's memory
  /// cleared.
  void next_shelf(int shelf);

  const ShelfView& view() const { return view_; }
  TagDetector& tag_detector() { return tag_detector_; }
  MarkerDetector& marker_detector() { return marker_detector_; }
  const Inventory& inventory() const { return inventory_; }
  const std::vector<Inventory>& finished() const { return finished_; }
  /// The optimal viewpoint in the grid frame G (eq. 7-9).
  const Eigen::Vector3d& viewpoint_G_m() const { return viewpoint_G_m_; }
  /// The last grid pose (GoToViewpoint), until the next shelf.
  const std::optional<PoseEstimate>& pose_G() const { return pose_G_; }

 private:
  const FlightConfig& config_;  ///< the mission's one configuration (outlives this)
  TagDetector tag_detector_;
  MarkerDetector marker_detector_;
  ShelfView view_;  ///< the last analysis (buffers reused frame to frame)
  std::vector<MarkerSighting> markers_;
  Inventory inventory_;
  std::vector<Inventory> finished_;
  Eigen::Vector3d viewpoint_G_m_;
  /// The viewpoint's memory of this shelf.
  struct AtViewpoint {
    int settled_frames = 0;                  ///< deciding frames in a row at the viewpoint
    std::optional<TimeNs> last_full_view_ns;  ///< GoToViewpoint's and TakeInventory's last whole grid
    bool searched_again = false;             ///< search_again() spent
  } at_viewpoint_;
  std::optional<PoseEstimate> pose_G_;
};

}  // namespace shelfcross::flight_sw
