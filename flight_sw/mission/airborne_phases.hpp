#pragma once
// The airborne phases across the shelves (flight_software.hpp): each picture's work in
// FindShelf, GoToViewpoint, TakeInventory (shelf_survey.hpp) and Approach (target_approach.hpp);
// each state record's in Approach (the gate's measures), Cross (the height hold and the watch,
// cell_crossing.hpp) and Transfer (transfer_flight.hpp); their timers; the shelf index and the
// hand-over to the next shelf. What the units' steps say is flown here; each step returns what
// it decided (Decision, mission.hpp: a transition, a landing, the rc), which the mission takes
// and which keeps the phase. A step that goes on in the phase it decided on (the viewpoint
// reached on the picture that found the shelf, the crossing's line flown once in Cross, the
// approach's back-off once back in it) says so (Decision::resume) and the mission, having
// taken the decision, asks for the rest (resume). The mission's own failsafes (battery, video,
// keep-alive) are not here.

#include <optional>
#include <string>
#include <variant>

#include <opencv2/core.hpp>

#include "flight_sw/config.hpp"
#include "flight_sw/control/sticks.hpp"
#include "flight_sw/mission/cell_crossing.hpp"
#include "flight_sw/mission/facts.hpp"
#include "flight_sw/mission/mission.hpp"
#include "flight_sw/mission/shelf_survey.hpp"
#include "flight_sw/mission/target_approach.hpp"
#include "flight_sw/mission/transfer_flight.hpp"
#include "flight_sw/perception/shelf_view.hpp"
#include "shelfcross/sdk_messages.hpp"

namespace shelfcross::flight_sw {

/// What the airborne phases work with besides their own state: the mission's facts (the phase
/// now among them; only the mission changes it, taking their decisions) and the sticks they fly.
struct AirborneTools {
  MissionFacts& facts;
  Sticks& sticks;
};

class AirbornePhases {
 public:
  /// `config` must be valid and outlive this (the mission's one configuration).
  explicit AirbornePhases(const FlightConfig& config)
      : config_(config), survey_(config), approach_(config), crossing_(config) {}

  /// A picture that steers, in the phase now: FindShelf (once the whole shelf is in view:
  /// GoToViewpoint, resumed on the same picture), GoToViewpoint, TakeInventory (then the
  /// target, the transfer, or a landing), Approach. Nothing in the other phases.
  Decision on_picture(const Picture& pic, AirborneTools t);
  /// A state record (after MissionFacts::on_state): the gate's measures; in Transfer the leg
  /// flown (the rc when due); in Cross the cell's height held and the watch that may stop the
  /// crossing (Approach, resumed backing out, the rc now).
  Decision on_state(const StateRecord& s, AirborneTools t);
  /// The airborne phases' timers at each input: the phases' time limits, the approach's
  /// (TargetApproach::supervise), the crossing's end, the transfer leg's limit.
  /// Decision::supervised when the input's supervision ends here (a transition or landing, or
  /// an approach step other than Stay); otherwise the mission's failsafes run next.
  Decision supervise(AirborneTools t);
  /// The rest of the step whose decision said `resume`, once the mission has taken it, in the
  /// phase entered: the viewpoint on the same picture (`pic`, the one the step had; throws
  /// std::logic_error without it), the crossing's line, or the back-off of a stopped crossing.
  /// Nothing when no step waits.
  Decision resume(AirborneTools t, const Picture* pic = nullptr);
  /// A picture that cannot steer (too damaged to fly on, or the target not found in a damaged
  /// one): the last command held briefly, then a hover (Sticks::hold_or_hover). Not while the
  /// corner tags are leaving the view in the approach: there only nearly whole pictures move
  /// the vehicle.
  void hold_or_hover(const MissionFacts& facts, Sticks& sticks) const;
  /// The picture rows `phase`'s decisions rest on, from the last analysis: the front shelf's
  /// tags (finding it, reaching the viewpoint, reading it), the target's tracked box (the
  /// approach). Nothing where no such rows are known.
  std::optional<cv::Rect2d> decision_region_px(Phase phase) const;
  /// Every phase change: the settling, the approach's timers restart.
  void on_phase_change();

  const ShelfSurvey& survey() const { return survey_; }  ///< this shelf's view, its inventory and the finished ones
  const TargetTracker& tracker() const { return approach_.tracker(); }  ///< the target and its record
  int shelf() const { return shelf_; }  ///< the shelf being read or passed, from 0

 private:
  /// The rest of a step, waiting for the mission to take its decision (resume): the viewpoint
  /// on the same picture, the back-off of the crossing stopped, the crossing's line.
  struct ViewpointOnSamePicture {};
  using Pending = std::variant<std::monostate, ViewpointOnSamePicture, CrossingStop, VelocityCommand>;

  Decision find_shelf(const Picture& pic, AirborneTools t);
  Decision go_to_viewpoint(const Picture& pic, bool view_fresh, AirborneTools t);
  /// The inventory taken: the conventional strategies plan their transfer (from the last
  /// visual pose; none, or no state record: land); through the cells, the target is chosen on
  /// the full view just read, or, with no crossable empty cell, it lands.
  Decision take_inventory(const Picture& pic, AirborneTools t);
  /// Flies an approach step and returns the decision it asks for (target_approach.hpp).
  Decision follow(const ApproachStep& step, AirborneTools t);
  /// The next shelf: FindShelf for it, `event` the phase change's.
  Transition next_shelf(const std::string& event, AirborneTools t);
  /// On each state record in Transfer: the next waypoint once within waypoint_tolerance_m,
  /// then the P law toward it, heading held on the shelf normal (guidance.hpp,
  /// transfer_velocity).
  Decision transfer(AirborneTools t);
  bool last_shelf() const { return shelf_ + 1 >= config_.layout.shelf_count; }

  const FlightConfig& config_;
  ShelfSurvey survey_;       ///< FindShelf, GoToViewpoint, TakeInventory; the inventories
  TransferFlight transfer_;  ///< the conventional strategies' waypoints
  TargetApproach approach_;  ///< the target, its approach, the crossing gate
  CellCrossing crossing_;    ///< the crossing's height hold, watch and end
  int shelf_ = 0;
  Pending pending_;
};

}  // namespace shelfcross::flight_sw
