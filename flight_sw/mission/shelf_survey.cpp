#include "flight_sw/mission/shelf_survey.hpp"

#include <algorithm>
#include <cmath>

#include "flight_sw/guidance/guidance.hpp"
#include "flight_sw/mission/telemetry.hpp"

namespace shelfcross::flight_sw {

namespace {
using Step = SurveyStep;
Step fly(const VelocityCommand& v) {
  Step step;
  step.velocity = v;
  return step;
}
Step hover(Step::Next next = Step::Next::Stay) {
  Step step;
  step.next = next;
  step.hover = true;
  return step;
}

// The whole grid, last seen at `last_ns`, has been out of view longer than `limit_s` at `now_ns`.
bool lost_since(const std::optional<TimeNs>& last_ns, TimeNs now_ns, double limit_s) {
  return last_ns && ns_to_seconds(now_ns - *last_ns) > limit_s;
}

// The markers of the boxes in the picture `bgr` of the full view `view`, into `markers`.
void read_markers(const cv::Mat& bgr, const ShelfView& view, MarkerDetector& marker_detector, const FlightConfig& config,
                  std::vector<MarkerSighting>& markers) {
  markers.clear();
  if (config.perception.pipeline == PerceptionPipeline::fast) {
    // Markers only where boxes can be: the cells, i.e. inside the front tags' bounding box.
    cv::Rect grid = view.tags.front().bbox_px;
    for (const TagBlob& t : view.tags) grid |= t.bbox_px;
    marker_detector.detect_in(bgr, grid, config.shelf.marker_size_m * view.px_per_m,
                               config.perception.marker_area_ratio_threshold, markers);
  } else {
    marker_detector.detect(bgr, markers);
  }
}

// The cells of the full view whose rows no damaged row of `pic` touches: a damaged picture's
// view of them is whole (inventory.hpp). The cells' rows are their corner tags' centres,
// band_margin_px around (the marker detector's threshold window and the picture's motion).
std::vector<CellIndex> cells_clear_of_damage(const Picture& pic, const ShelfView& view, const FlightConfig& config) {
  std::vector<CellIndex> out;
  const double margin = config.perception.band_margin_px;
  if (margin < 0.0) return out;
  for (int l = 1; l <= config.shelf.levels(); ++l) {
    for (int c = 1; c <= config.shelf.columns(); ++c) {
      const auto q = cell_quad(view, {l, c});
      double top = q[0].y, bottom = q[0].y;
      for (const cv::Point2d& p : q) {
        top = std::min(top, p.y);
        bottom = std::max(bottom, p.y);
      }
      if (!pic.damaged_rows || !rows_touch(*pic.damaged_rows, top - margin, bottom + margin)) out.push_back({l, c});
    }
  }
  return out;
}

// The view's tags and grid, for the logs.
void update_view_telemetry(const ShelfView& view, Telemetry& t) {
  t.view.tags.clear();
  for (size_t i = 0; i < view.tags.size(); ++i) {
    const bool classified = view.grid.valid && i < view.grid.row.size();
    t.view.tags.push_back({view.tags[i].centre_px, view.tags[i].area_px, classified ? view.grid.row[i] : -1,
                      classified ? view.grid.column[i] : -1});
  }
  t.view.grid_valid = view.grid.valid;
  t.view.grid_rows = view.grid.rows;
  t.view.grid_columns = view.grid.columns;
  t.view.full_view = view.full;
  t.view.grid_refusal = view.grid.refusal;
}
}  // namespace

ShelfSurvey::ShelfSurvey(const FlightConfig& config)
    : config_(config),
      tag_detector_(config_.perception),
      marker_detector_(config_.shelf.aruco_dictionary),
      inventory_(0, config_.shelf.levels(), config_.shelf.columns(), config_.perception.marker_min_agreeing_frames),
      viewpoint_G_m_(optimal_viewpoint_G(config_.shelf, config_.camera, config_.mount, config_.mission.viewpoint.viewpoint_margin)) {}

SurveyStep ShelfSurvey::find_shelf(const Picture& pic, bool back_out, Telemetry& telemetry) {
  analyse(pic.bgr, telemetry);
  // A re-read from close backs straight out to the viewpoint's range before it looks at
  // anything. Closer than that, a whole grid in view is not the shelf being re-read, which
  // does not fit the view there, but the next one, seen through the empty cell in front of
  // the camera: 0.46 m from a 34 cm cell it spans 40 deg, and the next shelf's grid, 4.7 m
  // off, 21 deg. Taken for the re-read shelf, its viewpoint lies beyond the cell:
  // GoToViewpoint flew there through the cell, ungated, and the mission then crossed the
  // next shelf on the inventory of the one before.
  if (back_out) {
    VelocityCommand v;
    v.vx_B_mps = -config_.control.back_off_speed_mps;
    return fly(v);
  }
  if (view_.full && !pic.decides) return fly({});  // to be confirmed on a nearly whole picture
  if (view_.full) {
    Step step;
    step.next = Step::Next::WholeShelfInView;
    return step;
  }
  VelocityCommand v;
  if (!view_.tags.empty()) {
    // A fragment: back away (only while the shelf is too close to fit the view) and centre it
    // until the whole grid fits the view (guidance.hpp).
    v = fragment_velocity(config_, view_.tags, view_.largest_tag_area_px, -viewpoint_G_m_.x());
  } else {
    v.yaw_rate_radps = config_.control.search_yaw_rate_radps;  // nothing in view: turn and look
  }
  return fly(v);
}

SurveyStep ShelfSurvey::go_to_viewpoint(const Picture& pic, TimeNs now_ns, bool view_fresh, Telemetry& telemetry) {
  if (!view_fresh) analyse(pic.bgr, telemetry);
  const MissionParams& m = config_.mission;
  if (!view_.full) {
    const bool lost = lost_since(at_viewpoint_.last_full_view_ns, now_ns, m.viewpoint.viewpoint_lost_s);
    return hover(lost ? Step::Next::ShelfOutOfView : Step::Next::Stay);
  }
  at_viewpoint_.last_full_view_ns = now_ns;
  std::vector<cv::Point3d> obj;
  std::vector<cv::Point2d> img;
  for (int r = 0; r < view_.grid.rows; ++r) {
    for (int c = 0; c < view_.grid.columns; ++c) {
      obj.push_back(grid_tag_G(config_.shelf, c, r));
      img.push_back(view_.tags[static_cast<size_t>(view_.grid.at(r, c))].centre_px);
    }
  }
  const auto pose = estimate_pose(obj, img, config_.camera, config_.mount);
  if (!pose) return hover();
  telemetry.pose = pose;
  telemetry.pose_in_cell_frame = false;
  pose_G_ = pose;
  // e1: from the current position to the optimal viewpoint, in G; flown in the body frame.
  const Eigen::Vector3d e1 = viewpoint_G_m_ - pose->p_FB_m();
  telemetry.view.e1_G_m = e1;
  const bool there = e1.norm() < m.viewpoint.viewpoint_position_tolerance_m && std::abs(pose->yaw_rad) < m.viewpoint.viewpoint_yaw_tolerance_rad;
  if (!there) at_viewpoint_.settled_frames = 0;
  else if (pic.decides) ++at_viewpoint_.settled_frames;  // a damaged picture neither counts nor resets
  const VelocityCommand v = viewpoint_velocity(config_.control, e1, pose->yaw_rad);
  Step step = fly(v);
  if (at_viewpoint_.settled_frames >= m.viewpoint.viewpoint_settle_frames) {  // flown, then a hover: set now, at rest
    step.next = Step::Next::AtViewpoint;
    step.hover = true;
  }
  return step;
}

SurveyStep ShelfSurvey::take_inventory(const Picture& pic, Telemetry& telemetry) {
  if (!pic.decides) return hover();  // a guessed band may hold a marker, or shift the grid labels
  analyse(pic.bgr, telemetry);
  if (!view_.full) return hover();
  at_viewpoint_.last_full_view_ns = pic.t_ns;
  read_markers(pic.bgr, view_, marker_detector_, config_, markers_);
  telemetry.view.markers_seen = static_cast<int>(markers_.size());
  const std::vector<std::pair<CellIndex, int>> sightings = assign_markers(view_, markers_, config_);
  if (pic.whole()) {
    inventory_.observe(sightings, true);
  } else {
    inventory_.observe(sightings, cells_clear_of_damage(pic, view_, config_));
  }
  // Closed after inventory_frames full views, with enough whole views of every cell without a
  // box to decide whether it is empty (inventory.hpp); the timeout bounds the wait.
  if (inventory_.frames() < config_.perception.inventory_frames || !inventory_.empty_decidable()) return hover();
  return hover(Step::Next::InventoryTaken);
}

// The hover holds where the vehicle stopped, not the viewpoint: one reached while still moving
// (the settling counts deciding frames, five in 0.17 s at 30 Hz) coasts on by its speed times
// the velocity time constant, and 0.3 m/s of sink after a transfer's descent carries the grid's
// top row out of the view. The hover never flies back; the search does (FindShelf frames the
// grid, GoToViewpoint flies to the viewpoint), as for a viewpoint lost on the way. Asked only
// when the phase's time has run out, where the mission landed before: a run that reads its
// inventory in time flies as it did.
bool ShelfSurvey::search_again(TimeNs now_ns) {
  const bool lost = lost_since(at_viewpoint_.last_full_view_ns, now_ns, config_.mission.viewpoint.viewpoint_lost_s);
  if (!lost || at_viewpoint_.searched_again) return false;
  at_viewpoint_.searched_again = true;
  return true;
}

void ShelfSurvey::analyse(const cv::Mat& bgr, Telemetry& telemetry) {
  analyse_shelf(bgr, tag_detector_, config_, view_);
  update_view_telemetry(view_, telemetry);
}

void ShelfSurvey::next_shelf(int shelf) {
  finished_.push_back(inventory_);
  inventory_ = Inventory(shelf, config_.shelf.levels(), config_.shelf.columns(), config_.perception.marker_min_agreeing_frames);
  pose_G_.reset();
  at_viewpoint_.last_full_view_ns.reset();
  at_viewpoint_.searched_again = false;
}

}  // namespace shelfcross::flight_sw
