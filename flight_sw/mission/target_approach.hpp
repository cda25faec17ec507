#pragma once
// The approach of the target cell (flight_software.hpp, phase Approach): the target chosen on
// the full view, followed, measured, re-acquired and its identity judged (target_tracker.hpp);
// the laws of eq. 10-15 and Fig. 19 on its pose (guidance.hpp); when to hold short, back off,
// re-read the shelf, give up or cross (the gate: crossing_gate.hpp). Each step says what to fly
// and what happens next; AirbornePhases (airborne_phases.hpp) flies it and has the mission
// take the transition.

#include <optional>
#include <string>

#include <opencv2/core.hpp>

#include "flight_sw/config.hpp"
#include "flight_sw/control/control.hpp"
#include "flight_sw/control/sticks.hpp"
#include "flight_sw/mission/cell_crossing.hpp"
#include "flight_sw/mission/crossing_gate.hpp"
#include "flight_sw/mission/facts.hpp"
#include "flight_sw/mission/shelf_survey.hpp"
#include "flight_sw/navigation/target_tracker.hpp"
#include "flight_sw/perception/shelf_view.hpp"

namespace shelfcross::flight_sw {

/// What a step of the approach asks of the mission: what to fly (in this order: the velocity,
/// the PI loops restarted, a hover, a hold over a picture that cannot steer) and what follows.
struct ApproachStep {
  enum class Next {
    Stay,    ///< the approach goes on
    GiveUp,  ///< given up: backing out (the velocity) to land clear of the shelf later
    Reread,  ///< the target in doubt: re-read the shelf (FindShelf), `event` the phase change's
    Land,    ///< land here, aborted, `event` the reason
    Cross    ///< the gate passed: fly `crossing`
  };
  Next next = Next::Stay;
  std::optional<VelocityCommand> velocity;  ///< flown when set
  bool restart_loops = false;               ///< the PI loops restarted, the command kept
  bool hover = false;                       ///< zero velocity, the PI loops restarted
  bool hold_or_hover = false;               ///< a picture that cannot steer (Sticks::hold_or_hover)
  std::string event;
  std::optional<CrossingStart> crossing;
};

/// What an approach step works with besides its own state: the mission's facts (telemetry
/// written), the PI loops it steers (Sticks::steer; what to fly it returns), and the shelf
/// survey (its detectors, view and inventory).
struct ApproachTools {
  MissionFacts& facts;
  Sticks& sticks;
  ShelfSurvey& survey;
};

class TargetApproach {
 public:
  /// `config` must be valid and outlive this (the mission's one configuration).
  explicit TargetApproach(const FlightConfig& config) : config_(config), tracker_(config), gate_(config) {}

  /// The target chosen on the full view just read (survey): the empty cell the vehicle fits
  /// through nearest the image centre, or with a shelf after this one (`last_shelf` false)
  /// nearest the next shelf's viewpoint. False: no crossable empty cell.
  bool choose_target(const cv::Mat& bgr, ApproachTools tools, bool last_shelf);
  /// The approach on a picture (phase Approach).
  ApproachStep step(const Picture& pic, ApproachTools tools);
  /// The approach's timers at each input (phase Approach), `in_phase_s` into it: a declined
  /// crossing backing out, then landing; the approach's time limit, or the mission's
  /// (`out_of_time`), backing out the same way; the target lost too long or an off-centre
  /// back-off too long (re-read). Nothing when none acts.
  std::optional<ApproachStep> supervise(MissionFacts& facts, const ShelfSurvey& survey, double in_phase_s,
                                        bool out_of_time);
  /// The in-crossing watch stopped the crossing (the mission is back in the approach, backing
  /// off): a refusal of the crossing; at the crossing_attempts-th the approach gives up.
  ApproachStep crossing_stopped(const CrossingStop& stop, MissionFacts& facts);
  /// Each state record: the level check's window and the gate's measures (`approaching`: in
  /// phase Approach).
  void on_state(const StateRecord& s, bool approaching) {
    states_.on_state(s);
    gate_.on_state(s, approaching);
  }
  /// Every phase change: the loss, back-off, rough-air and give-up timers end.
  void on_phase_change();
  /// The next shelf: the target forgotten, its measures and off-centre arrivals with it.
  void next_shelf(Telemetry& telemetry);

  const TargetTracker& tracker() const { return tracker_; }  ///< the target, its corner tags, poses and identity
  /// A re-read from close backs straight out until then (FindShelf).
  const std::optional<TimeNs>& reread_back_until_ns() const { return reread_back_until_ns_; }

 private:
  /// The approach's timers (each empty while it does not run).
  struct Timers {
    std::optional<TimeNs> hold_since_ns;  ///< holding short of the shelf to settle
    std::optional<TimeNs> lost_since_ns;
    std::optional<TimeNs> back_off_since_ns;
    /// The target's loss begins (once).
    void start_losing(TimeNs now_ns) {
      if (!lost_since_ns) lost_since_ns = now_ns;
    }
  };
  /// A declined crossing backs out until then, then lands with the reason.
  struct Retreat {
    std::optional<TimeNs> until_ns;
    std::string reason;
  };

  ApproachStep found(const Picture& pic, const TargetTracker::Prediction& predicted, double dt, ApproachTools tools);
  ApproachStep unseen(double dt, ApproachTools tools);
  ApproachStep without_target(const Picture& pic, ApproachTools tools);
  /// The target's identity on a picture where it is not confirmed: empty (confirmed, or kept
  /// unknown), or the re-read that ends the approach.
  std::optional<ApproachStep> check_identity(const Picture& pic, const PoseEstimate& pose_K, ApproachTools tools);
  /// The target is in doubt: forget it and re-read the shelf from the optimal viewpoint, or,
  /// after mission.identity_rereads re-reads in the mission, give up with `give_up_reason`
  /// (default: "target cell not identified: " + why).
  ApproachStep reread(const std::string& why, const std::optional<std::string>& give_up_reason, MissionFacts& facts,
                      const ShelfSurvey& survey);
  /// Gives the approach up for good: backs out to give_up_clearance_m in front of the shelf (by
  /// the last pose, plus `flown_in_m` flown toward it since), then lands there (supervise).
  ApproachStep give_up(const std::string& reason, double flown_in_m, MissionFacts& facts);

  const FlightConfig& config_;
  TargetTracker tracker_;  ///< the cell, its corner tags tracked, its pose, its identity
  RecentStates states_;    ///< the state records of the last second (the level check's window)
  CrossingGate gate_;      ///< stillness, line hold, cell height, forward gain; the gate
  Timers timers_;
  Retreat retreat_;
  std::optional<TimeNs> reread_back_until_ns_;
  int crossing_refusals_ = 0;  ///< off-centre arrivals at the cell so far
  int rereads_ = 0;            ///< re-reads of the shelf in the mission
};

}  // namespace shelfcross::flight_sw
