// The approach of the target cell alone (target_approach.hpp): the target chosen on the
// inventory read from a drawn shelf, then pictures (from where the test puts the vehicle, not
// where the steps would fly it), state records, the clock and the crossing's stops in, the step
// each call returns out (what to fly, and Stay, GiveUp, Reread, Land or Cross), with no
// FlightSoftware around it. Then the approach's decisions flown through FlightSoftware against
// the kinematic vehicle (flight_harness.hpp): the target lost, the time limits, the gate's
// refusals and give-ups, the re-reads, the target's identity, the still heading, gusty air.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <optional>
#include <string>

#include "flight_sw/config.hpp"
#include "flight_sw/control/sticks.hpp"
#include "flight_sw/guidance/guidance.hpp"
#include "flight_sw/guidance/line_hold.hpp"
#include "flight_sw/mission/facts.hpp"
#include "flight_sw/mission/shelf_survey.hpp"
#include "flight_sw/mission/target_approach.hpp"
#include "flight_sw/mission/test/flight_harness.hpp"
#include "flight_sw/mission/test/mission_scene.hpp"
#include "flight_sw/test/state_clock.hpp"
#include "flight_sw/text.hpp"
#include "shelfcross/time.hpp"

namespace shelfcross::flight_sw {
namespace {

using testing::FrameStep;
using testing::Harness;
using testing::Options;
using testing::expect_backed_out_and_landed_clear;
using testing::expect_through_cell_2_3;
using testing::position_at_land;

using testing::kInFront_W_m;
using testing::state_record_ns;

class TargetApproachTest : public ::testing::Test {
 protected:
  TargetApproachTest() : sticks_(config_), survey_(config_), approach_(config_), camera_(config_, testing::mission_scene()) {
    facts_.now_ns = state_record_ns(1);
    for (Phase p : {Phase::EnterSdk, Phase::StartVideo, Phase::WaitVideo, Phase::TakeOff, Phase::FindShelf,
                    Phase::GoToViewpoint, Phase::TakeInventory, Phase::Approach}) {
      facts_.phase.enter(p, facts_.now_ns);
    }
  }

  ApproachTools tools() { return {facts_, sticks_, survey_}; }
  /// The inventory read from kInFront_W_m and the target chosen on its last full view.
  bool target_chosen() {
    for (int k = 0; k < 3 * config_.perception.inventory_frames; ++k) {
      facts_.now_ns += seconds_to_ns(1.0 / 30.0);
      bgr_ = camera_.draw(kInFront_W_m);
      if (survey_.take_inventory(testing::whole_picture(bgr_, facts_.now_ns), facts_.telemetry).next ==
          SurveyStep::Next::InventoryTaken) {
        return approach_.choose_target(bgr_, tools(), true);
      }
    }
    return false;
  }
  /// The approach's step on `bgr`, 1/30 s after the last input.
  ApproachStep step(const cv::Mat& bgr) {
    facts_.now_ns += seconds_to_ns(1.0 / 30.0);
    bgr_ = bgr;
    return approach_.step(testing::whole_picture(bgr_, facts_.now_ns), tools());
  }
  /// The approach's timers `s` later, `in_phase_s` into the phase.
  std::optional<ApproachStep> later(double s, double in_phase_s = 1.0) {
    facts_.now_ns += seconds_to_ns(s);
    return approach_.supervise(facts_, survey_, in_phase_s, false);
  }
  /// A state record now of a level vehicle at p_W_m heading along x_W (the heading frame's
  /// axes the world's), having flown v_W_mps since the last: to the facts and the approach.
  void state(const Eigen::Vector3d& p_W_m, const Eigen::Vector3d& v_W_mps) {
    StateRecord s;
    s.t_ns = facts_.now_ns;
    s.height_m = p_W_m.z();
    s.vx_H_mps = v_W_mps.x();
    s.vy_H_mps = v_W_mps.y();
    s.vz_H_mps = v_W_mps.z();
    s.battery_pct = 80;
    facts_.on_state(s);
    approach_.on_state(s, true);
  }
  /// The vehicle moved from p_W_ straight to `to_W_m` at speed_mps, whatever the approach asks:
  /// a picture every 1/30 s, a state record with every third. The first step that does not go
  /// on, or the last.
  ApproachStep fly_to(const Eigen::Vector3d& to_W_m, double speed_mps) {
    const Eigen::Vector3d from_W_m = p_W_;
    const double move_s = (to_W_m - from_W_m).norm() / speed_mps;
    const Eigen::Vector3d v_W_mps = (to_W_m - from_W_m) / move_s;
    ApproachStep s;
    for (int k = 1; k <= static_cast<int>(std::ceil(move_s * 30.0)); ++k) {
      p_W_ = k / 30.0 < move_s ? Eigen::Vector3d(from_W_m + k / 30.0 * v_W_mps) : to_W_m;
      if (k % 3 == 0) state(p_W_, v_W_mps);
      s = step(camera_.draw(p_W_));
      if (s.next != ApproachStep::Next::Stay) return s;
    }
    return s;
  }
  bool flies_back_off(const ApproachStep& s) const {
    return s.velocity && s.velocity->vx_B_mps == back_off_velocity(config_.control).vx_B_mps && s.velocity->vx_B_mps < 0.0;
  }

  const FlightConfig config_;
  MissionFacts facts_;
  Sticks sticks_;
  ShelfSurvey survey_;
  TargetApproach approach_;
  testing::SceneCamera camera_;
  cv::Mat bgr_;
  Eigen::Vector3d p_W_ = kInFront_W_m;  ///< where the vehicle is (fly_to moves it)
};

TEST_F(TargetApproachTest, ACrossingStoppedCrossingAttemptsTimesGivesUpBacksOutThenLands) {
  const CrossingStop stop{"drifting toward the left post", 0.1};
  const int attempts = config_.mission.crossing.crossing_attempts;
  for (int k = 1; k < attempts; ++k) {
    const ApproachStep s = approach_.crossing_stopped(stop, facts_);
    EXPECT_EQ(s.next, ApproachStep::Next::Stay) << "refusal " << k << ": backing off to try again";
    EXPECT_FALSE(s.velocity) << k;
  }
  const ApproachStep given_up = approach_.crossing_stopped(stop, facts_);
  EXPECT_EQ(given_up.next, ApproachStep::Next::GiveUp);
  EXPECT_TRUE(flies_back_off(given_up));
  EXPECT_TRUE(given_up.restart_loops);
  // Backing out by give_up_clearance_m plus what it had flown in (no pose: from there), then landing.
  const double back_s = (config_.mission.line_hold.give_up_clearance_m + stop.flown_in_m) / config_.control.back_off_speed_mps;
  const std::optional<ApproachStep> backing = later(back_s - 0.1);
  ASSERT_TRUE(backing);
  EXPECT_EQ(backing->next, ApproachStep::Next::Stay);
  EXPECT_TRUE(flies_back_off(*backing));
  const std::optional<ApproachStep> down = later(0.1);
  ASSERT_TRUE(down);
  EXPECT_EQ(down->next, ApproachStep::Next::Land);
  EXPECT_EQ(down->event, std::string(kCrossingDeclined) + kLineCannotBeHeld + ": " + stop.why);
}

TEST_F(TargetApproachTest, TheApproachOutOfTimeBacksOutThenLands) {
  EXPECT_FALSE(later(0.1, config_.timeouts.approach_s - 0.1)) << "in time, nothing to do";
  const std::optional<ApproachStep> given_up = later(0.1, config_.timeouts.approach_s + 0.1);
  ASSERT_TRUE(given_up);
  EXPECT_EQ(given_up->next, ApproachStep::Next::GiveUp);
  EXPECT_TRUE(flies_back_off(*given_up));
  const std::optional<ApproachStep> down = later(config_.mission.line_hold.give_up_clearance_m / config_.control.back_off_speed_mps);
  ASSERT_TRUE(down);
  EXPECT_EQ(down->next, ApproachStep::Next::Land);
  EXPECT_EQ(down->event, "approach timed out");
}

TEST_F(TargetApproachTest, ATargetLostTooLongRereadsTheShelfUntilTheRereadsAreSpent) {
  const int rereads = config_.mission.target.identity_rereads;
  for (int k = 0; k <= rereads; ++k) {
    ASSERT_TRUE(target_chosen()) << k;
    approach_.on_phase_change();  // the approach entered
    const ApproachStep lost = step(camera_.wall());
    EXPECT_TRUE(lost.hover) << "hovering to re-acquire";
    EXPECT_EQ(lost.next, ApproachStep::Next::Stay);
    EXPECT_FALSE(later(config_.timeouts.target_lost_s - 0.1)) << k;
    const std::optional<ApproachStep> doubt = later(0.2);
    ASSERT_TRUE(doubt) << k;
    if (k < rereads) {
      EXPECT_EQ(doubt->next, ApproachStep::Next::Reread) << k;
      EXPECT_EQ(doubt->event, "target lost: re-reading the shelf from the viewpoint");
      EXPECT_TRUE(doubt->hover);
      EXPECT_FALSE(approach_.tracker().target()) << "forgotten, to be chosen anew";
    } else {
      EXPECT_EQ(doubt->next, ApproachStep::Next::GiveUp) << "the identity_rereads+1-th doubt gives up";
      EXPECT_TRUE(flies_back_off(*doubt));
    }
  }
}

TEST_F(TargetApproachTest, ACrossingStoppedBacksOffAndBackingOffTooLongRereadsTheShelf) {
  ASSERT_TRUE(target_chosen());
  approach_.on_phase_change();
  const ApproachStep stopped = approach_.crossing_stopped({"drifting toward the left post", 0.05}, facts_);
  EXPECT_EQ(stopped.next, ApproachStep::Next::Stay) << "the first refusal backs off";
  EXPECT_FALSE(later(config_.timeouts.back_off_s - 0.1)) << "backing off, within back_off_s";
  const std::optional<ApproachStep> doubt = later(0.2);
  ASSERT_TRUE(doubt);
  EXPECT_EQ(doubt->next, ApproachStep::Next::Reread);
  EXPECT_EQ(doubt->event, std::string(kCouldNotCentre) + ": re-reading the shelf from the viewpoint");
  EXPECT_TRUE(doubt->hover);
  EXPECT_FALSE(approach_.tracker().target());
}

// Continuity broken (no picture for identity_continuity_s and a frame), the target's identity
// is judged on the next whole picture. Seen from where it was chosen, a known marker confirms it
// and the approach goes on. Seen after the same gap 0.41 m to the left, the box where the target
// was in the picture sits on L2 C2 (box 4's cell), and the check (cell_identity.hpp)
// contradicts the target there: the shelf is re-read, the target forgotten.
TEST_F(TargetApproachTest, AnIdentityContradictedAfterAGapRereadsTheShelf) {
  ASSERT_TRUE(target_chosen());
  approach_.on_phase_change();
  const double gap_s = config_.mission.target.identity_continuity_s;
  facts_.now_ns += seconds_to_ns(gap_s);
  const ApproachStep confirmed = step(camera_.draw(kInFront_W_m));
  EXPECT_EQ(confirmed.next, ApproachStep::Next::Stay);
  EXPECT_TRUE(approach_.tracker().identification().continuity_lost());
  EXPECT_EQ(approach_.tracker().identification().identity(), CellIdentity::Confirmed);
  EXPECT_EQ(facts_.telemetry.event.rfind("target identity confirmed: ", 0), 0u) << facts_.telemetry.event;

  facts_.now_ns += seconds_to_ns(gap_s);
  const ApproachStep doubt = step(camera_.draw(kInFront_W_m + Eigen::Vector3d(0.0, 0.41, 0.0)));
  EXPECT_EQ(doubt.next, ApproachStep::Next::Reread);
  EXPECT_EQ(doubt.event.rfind("target identity contradicted (", 0), 0u) << doubt.event;
  EXPECT_NE(doubt.event.find(": re-reading the shelf from the viewpoint"), std::string::npos) << doubt.event;
  EXPECT_TRUE(doubt.hover);
  EXPECT_FALSE(doubt.crossing);
  EXPECT_EQ(facts_.telemetry.tracking.identity_contradictions, 1);
  EXPECT_EQ(facts_.telemetry.tracking.shelf_rereads, 1);
  EXPECT_FALSE(approach_.tracker().target()) << "forgotten, to be chosen anew";
}

// The vehicle lined up on L2 C3 (centre y -0.17 m, z 0.81 m) far out, then flown straight in at
// 0.2 m/s, level, heading along the cell's normal: no sideways command, a still heading, the line
// hold measured quiet, the cell height sampled against the state height. The approach goes on
// until a corner tag reaches the picture's border inside cross_range_max_m; the gate is open on
// that picture and the step is the crossing of L2 C3, holding the cell centre's height.
TEST_F(TargetApproachTest, TheGateOpenOnACentredStillApproachCrossesTheTarget) {
  ASSERT_TRUE(target_chosen());
  approach_.on_phase_change();
  const Eigen::Vector3d lined_up_W_m(kInFront_W_m.x(), -0.17, 0.81);
  EXPECT_EQ(fly_to(lined_up_W_m, 0.1).next, ApproachStep::Next::Stay) << "lining up, far out";
  const ApproachStep s = fly_to(lined_up_W_m + Eigen::Vector3d(1.7, 0.0, 0.0), 0.2);
  ASSERT_EQ(s.next, ApproachStep::Next::Cross) << "at x " << p_W_.x() << ": " << facts_.telemetry.event;
  ASSERT_TRUE(s.crossing);
  EXPECT_EQ(s.crossing->event.rfind("corner tags leaving the view: crossing L2 C3 ", 0), 0u) << s.crossing->event;
  EXPECT_TRUE(approach_.tracker().corners().near_edge());
  ASSERT_TRUE(approach_.tracker().poses().pose_K());
  EXPECT_LE(-approach_.tracker().poses().pose_K()->p_FB_m().x(), config_.mission.approach.cross_range_max_m);
  EXPECT_EQ(approach_.tracker().identification().identity(), CellIdentity::Confirmed);
  EXPECT_TRUE(facts_.telemetry.control.line_hold.measured);
  EXPECT_NEAR(s.crossing->height_m, lined_up_W_m.z(), 0.03) << "the cell centre's height by the state height";
  EXPECT_GT(s.crossing->velocity.vx_B_mps, 0.0) << "into the cell";
  EXPECT_FALSE(s.hover);
}

// ---- Through FlightSoftware: the kinematic vehicle (flight_harness.hpp) ----

TEST(FlightSoftware, TargetLostHoversThenBacksOutToReread) {
  // The pictures go blank 4 s into the approach, closer than the viewpoint (nothing in view,
  // not even the grid): the vehicle hovers target_lost_s to re-acquire, then backs straight
  // out to re-read the shelf (never landing where it hovered, close to the shelf); with
  // nothing ever in view again the shelf is not found and it lands there, out from the shelf.
  Options o;
  o.blank_after_approach_s = 4.0;
  Harness h(o);
  h.run(90.0);
  ASSERT_TRUE(h.fsw().finished());
  EXPECT_EQ(h.fsw().result().reason, "shelf not found");
  EXPECT_TRUE(h.fsw().result().landed);
  // Approach, then FindShelf again (the re-read), never Cross.
  const std::vector<FrameStep>& steps = h.frame_steps();
  const auto in_approach = std::find_if(steps.begin(), steps.end(), [](const FrameStep& s) { return s.before == Phase::Approach; });
  ASSERT_NE(in_approach, steps.end());
  const auto reread = std::find_if(in_approach, steps.end(), [](const FrameStep& s) { return s.after == Phase::FindShelf; });
  ASSERT_NE(reread, steps.end()) << "no re-read after the target was lost";
  EXPECT_FALSE(h.saw_phase(Phase::Cross));
  // The 3 s before the re-read: hover only; then backing straight out (b < 0, the rest 0).
  const TimeNs reread_ns = reread->t_ns;
  int hovers = 0;
  std::optional<std::string> first_move;
  for (const SdkCommand& c : h.commands()) {
    if (c.text.rfind("rc ", 0) != 0) continue;
    if (c.t_ns < reread_ns && reread_ns - c.t_ns < 3 * kNsPerSecond) {
      EXPECT_EQ(c.text, "rc 0 0 0 0");
      ++hovers;
    }
    if (c.t_ns >= reread_ns && !first_move && c.text != "rc 0 0 0 0") first_move = c.text;
  }
  EXPECT_GT(hovers, 20);
  ASSERT_TRUE(first_move.has_value());
  int a = 0, b = 0, c = 0, d = 0;
  ASSERT_EQ(std::sscanf(first_move->c_str(), "rc %d %d %d %d", &a, &b, &c, &d), 4) << *first_move;
  EXPECT_LT(b, 0) << *first_move;
  EXPECT_EQ(a, 0) << *first_move;
  EXPECT_EQ(d, 0) << *first_move;
}

// A link that stops giving a picture to fly on late in the approach, closer to the shelf than
// give_up_clearance_m: the vehicle hovers short of the cell until the approach's time limit,
// then backs straight out and lands clear of the shelf (not where it hovered), the mission
// aborted with the reason.
TEST(FlightSoftware, ApproachTimedOutBacksOutAndLandsClearOfTheShelf) {
  Options o;
  o.ruin_after_approach_s = 7.0;
  Harness h(o);
  const FlightConfig& c = h.fsw().config();
  h.run(c.timeouts.approach_s + 40.0);
  ASSERT_TRUE(h.fsw().finished()) << phase_name(h.fsw().phase()) << ": " << h.fsw().telemetry().event;
  EXPECT_EQ(h.fsw().result().outcome, Outcome::Aborted);
  EXPECT_EQ(h.fsw().result().reason, "approach timed out");
  EXPECT_TRUE(h.fsw().result().landed);
  EXPECT_FALSE(h.saw_phase(Phase::Cross));
  ASSERT_TRUE(h.ruin_W_m().has_value());
  const double clear_x_m = 3.0 - c.mission.line_hold.give_up_clearance_m;  // the shelf's face at x 3 m
  EXPECT_GT(h.ruin_W_m()->x(), clear_x_m) << "the link should fail inside the clearance: x " << h.ruin_W_m()->x();
  expect_backed_out_and_landed_clear(h, c);
}

// The mission's time budget spent in the approach: backed out and landed clear of the shelf,
// like the approach's own limit, with its own reason; spent before the shelf is reached: landed
// where it is, well in front of the shelf.
TEST(FlightSoftware, MissionOutOfTimeGivesUpClearOfTheShelf) {
  Options o;
  o.ruin_after_approach_s = 7.0;
  FlightConfig c;
  c.timeouts.mission_s = 40.0;  // inside the approach's 70 s of pictures that cannot decide
  Harness h(o, c);
  h.run(c.timeouts.mission_s + 30.0);
  ASSERT_TRUE(h.fsw().finished()) << phase_name(h.fsw().phase()) << ": " << h.fsw().telemetry().event;
  EXPECT_EQ(h.fsw().result().outcome, Outcome::Aborted);
  EXPECT_EQ(h.fsw().result().reason, kMissionTimeSpent);
  EXPECT_TRUE(h.fsw().result().landed);
  EXPECT_FALSE(h.saw_phase(Phase::Cross));
  expect_backed_out_and_landed_clear(h, c);

  FlightConfig early;
  early.timeouts.mission_s = 1.0;  // spent by the end of the take-off
  Harness e(Options{}, early);
  e.run(30.0);
  ASSERT_TRUE(e.fsw().finished()) << phase_name(e.fsw().phase()) << ": " << e.fsw().telemetry().event;
  EXPECT_EQ(e.fsw().result().reason, kMissionTimeSpent);
  EXPECT_TRUE(e.fsw().result().landed);
  EXPECT_FALSE(e.saw_phase(Phase::Approach));
}

// The budget spent just after a re-read from close began (the target lost 4 s into the
// approach, pictures blank from then): the re-read's straight back-out is flown to its end
// before the landing, not cut off close in front of the shelf.
TEST(FlightSoftware, MissionOutOfTimeInAReReadFromCloseBacksOutFirst) {
  Options o;
  o.blank_after_approach_s = 4.0;
  // The re-read begins on a timer (the target lost too long): the first picture after the
  // approach that finds the mission in FindShelf dates it to within a frame.
  const auto reread_step = [](const std::vector<FrameStep>& steps) {
    const auto in_approach = std::find_if(steps.begin(), steps.end(), [](const FrameStep& s) { return s.before == Phase::Approach; });
    return std::find_if(in_approach, steps.end(), [](const FrameStep& s) { return s.after == Phase::FindShelf; });
  };
  Harness first(o);
  first.run(60.0, [&](const Harness& f) { return reread_step(f.frame_steps()) != f.frame_steps().end(); });  // flown to the re-read
  const std::vector<FrameStep>& steps = first.frame_steps();
  const auto reread = reread_step(steps);
  ASSERT_NE(reread, steps.end()) << first.fsw().result().reason;
  const std::optional<double> t_reread_s = ns_to_seconds(reread->t_ns);
  double x_reread_m = 0.0;
  for (const auto& p : first.track()) {
    if (p[0] <= *t_reread_s) x_reread_m = p[1];
  }
  FlightConfig c;
  c.timeouts.mission_s = *t_reread_s + 0.3;
  Harness h(o, c);
  h.run(60.0);
  ASSERT_TRUE(h.fsw().finished()) << phase_name(h.fsw().phase()) << ": " << h.fsw().telemetry().event;
  EXPECT_EQ(h.fsw().result().reason, kMissionTimeSpent);
  EXPECT_TRUE(h.fsw().result().landed);
  EXPECT_FALSE(h.saw_phase(Phase::Cross));
  // Backed out by the range to the viewpoint (at the back-off speed) before landing.
  EXPECT_LT(h.position().x(), x_reread_m - 0.3) << "from x " << x_reread_m;
  EXPECT_LT(h.position().x(), 3.0 - c.mission.line_hold.give_up_clearance_m + 0.1) << "landed clear of the shelf";
}

TEST(FlightSoftware, NeverCrossesWithoutRoomBacksOutAndGivesUp) {
  FlightConfig c;
  // Leave 0.25 mm of lateral tolerance in the 32 cm opening (less than the pose's own
  // scatter and the footprint growth of any heading error). No hover holds a line that close:
  // the line-hold gate holds the vehicle short of the cell, and after calm_wait_s declines the
  // crossing, backs out to give_up_clearance_m and lands there.
  c.mission.crossing_margin_m = 0.1135;
  c.mission.target.identity_rereads = 0;
  Harness h(Options{}, c);
  h.run(60.0);
  ASSERT_TRUE(h.fsw().finished()) << phase_name(h.fsw().phase()) << ": " << h.fsw().telemetry().event;
  EXPECT_FALSE(h.saw_phase(Phase::Cross));
  EXPECT_EQ(h.fsw().result().reason.rfind(std::string(kCrossingDeclined) + kLineCannotBeHeld, 0), 0u)
      << h.fsw().result().reason;
  expect_backed_out_and_landed_clear(h, c);
}

// The gate's off-centre refusals: with the line-hold's hold short switched off by a calm wait
// longer than the approach, the vehicle arrives off-centre (0.25 mm of tolerance), backs off
// and comes again, crossing_attempts times; then the re-read that is one too many gives up,
// backing out to land clear of the shelf.
TEST(FlightSoftware, NeverCrossesOffCentreBacksOffAndGivesUp) {
  FlightConfig c;
  c.mission.crossing_margin_m = 0.1135;
  c.mission.line_hold.calm_wait_s = 1000.0;
  c.mission.approach.settle_hold_s = 0.0;  // held short only to settle; the rough air's hold is given up with it
  // No re-read: with them, one of the later arrivals may fall inside the 0.25 mm and cross.
  c.mission.target.identity_rereads = 0;
  Harness h(Options{}, c);
  h.run(60.0);
  ASSERT_TRUE(h.fsw().finished()) << phase_name(h.fsw().phase()) << ": " << h.fsw().telemetry().event;
  EXPECT_FALSE(h.saw_phase(Phase::Cross));
  EXPECT_EQ(h.fsw().result().reason, "could not centre on the target cell");
  EXPECT_EQ(h.fsw().telemetry().tracking.shelf_rereads, 1);
  expect_backed_out_and_landed_clear(h, c);
}

// A re-read from close that sees nothing (the approach gave up 0.6 m out, the picture showed the inside of a cell, and FindShelf
// turned on the spot for 30 s until "shelf not found"): it backs straight out toward the
// viewpoint's range instead, heading unchanged, and finds the shelf again.
TEST(FlightSoftware, ARereadFromCloseBacksOutBeforeLooking) {
  FlightConfig c;
  c.mission.crossing_margin_m = 0.1135;  // never centred: could not centre, re-read (above)
  c.mission.line_hold.calm_wait_s = 1000.0;        // and arriving there: no hold short for the air (above)
  c.mission.approach.settle_hold_s = 0.0;
  c.mission.target.identity_rereads = 1;
  Options o;
  o.blank_after_reread_s = 4.0;
  Harness h(o, c);
  h.run(90.0);
  const Eigen::Vector3d start = h.reread_W_m(), end = h.reread_end_W_m();
  ASSERT_GT(start.x(), 1.5) << "no re-read from close";
  const double viewpoint_x_m = 3.0 - 1.86;  // the shelf's front at x = 3 m; range about 1.9 m
  // Backed out: the re-read started within 1.5 m of the shelf, and 4 s at 0.2 m/s later it is
  // at least 0.6 m farther, heading still toward the shelf (no search turn).
  EXPECT_LT(end.x(), start.x() - 0.6) << "start " << start.transpose() << " end " << end.transpose();
  EXPECT_GT(end.x(), viewpoint_x_m - 0.3);
  EXPECT_NEAR(h.reread_end_yaw_rad(), 0.0, 0.1);
  EXPECT_GE(h.fsw().telemetry().tracking.shelf_rereads, 1);
  EXPECT_TRUE(h.fsw().finished());
}

// The crossing flies open loop on the heading it starts with, judged on a picture a video
// latency old. With the yaw rate lagging the stick by 0.6 s and the video 0.35 s late, the
// heading law still turned the vehicle as the corner tags left the view (0.013 rad in the
// latency before the commit, 0.014 rad in the 1.5 s after it: 2.7 cm across at the back
// face, a third of a 34 cm column's tolerance). The approach now waits until the state's yaw
// has held within settle_heading_band_rad for settle_s: from the picture's capture to 1.5 s
// into the crossing the heading turns by less than 0.012 rad.
TEST(FlightSoftware, CrossesOnlyOnAStillHeading) {
  Options o;
  o.start_W_m = Eigen::Vector3d(0.3, 0.3, 0.0);
  o.start_yaw_rad = -0.2;
  o.video_latency_s = 0.35;
  o.velocity_time_constant_s = 0.7;
  o.yaw_time_constant_s = 0.6;
  Harness h(o);
  h.run(80.0);
  ASSERT_TRUE(h.fsw().finished()) << phase_name(h.fsw().phase()) << ": " << h.fsw().telemetry().event;
  EXPECT_EQ(h.fsw().result().outcome, Outcome::Crossed) << h.fsw().result().reason;
  std::optional<double> t_cross_s;
  for (const FrameStep& st : h.frame_steps()) {
    if (st.after == Phase::Cross) {
      t_cross_s = ns_to_seconds(st.t_ns);
      break;
    }
  }
  ASSERT_TRUE(t_cross_s);
  const auto yaw_at = [&](double t_s) {
    double yaw = 0.0;
    for (size_t i = 0; i < h.track().size() && h.track()[i][0] <= t_s; ++i) yaw = h.yaw_track()[i];
    return yaw;
  };
  EXPECT_LT(std::abs(yaw_at(*t_cross_s + 1.5) - yaw_at(*t_cross_s - o.video_latency_s)), 0.012);
  expect_through_cell_2_3(h);
}

// The vehicle is carried one column aside (to the wide column L2 C2, which holds box
// 4) while the video is blank during the approach; the target's box is re-acquired where it
// was in the picture, i.e. on the neighbouring cell, whose corner tags give a plausible pose of
// the right level. The flight software must not settle on it: the target is unidentified, the
// vehicle backs off until a picture contradicts it, re-reads the shelf from the viewpoint and
// crosses the true target, L2 C3.
TEST(FlightSoftware, ReacquisitionOnTheNeighbouringColumnIsNeverCrossed) {
  Options o;
  o.slide_after_approach_s = 3.0;
  o.slide_blank_s = 1.0;
  o.slide_W_m = Eigen::Vector3d(0.0, 0.41, 0.0);  // L2 C3's centre (y -0.17 m) to L2 C2's (0.24 m)
  Harness h(o);
  h.run(120.0);
  FlightSoftware& fsw = h.fsw();
  ASSERT_TRUE(h.slid());
  ASSERT_TRUE(fsw.finished()) << phase_name(fsw.phase()) << ": " << fsw.telemetry().event;
  EXPECT_GE(fsw.telemetry().tracking.counts.identity_checks, 1);
  EXPECT_GE(fsw.telemetry().tracking.shelf_rereads, 1);
  EXPECT_EQ(fsw.result().outcome, Outcome::Crossed) << fsw.result().reason;
  ASSERT_TRUE(fsw.telemetry().tracking.target);
  EXPECT_EQ(*fsw.telemetry().tracking.target, (CellIndex{2, 3}));
  expect_through_cell_2_3(h);
}

// The vehicle is carried one level up (a gust, an altitude step the video never showed) while
// the video is blank during the approach. A box looked for where it was in the picture would sit
// on L3 C3, the cell above the target, which holds box 17, and its corner tags give a plausible
// pose. The state height saw the climb, and the tracker looks for the target where the
// vehicle's own motion since the last pose puts it (TargetTracker::predict): on the target,
// one row lower in the picture, found without a re-read, and crossed.
Options carried_one_level_up() {
  Options o;
  o.slide_after_approach_s = 3.0;
  o.slide_blank_s = 1.0;
  o.slide_W_m = Eigen::Vector3d(0.0, 0.0, 0.34);  // one row pitch: L2's centre (0.81 m) to L3's (1.15 m)
  return o;
}

TEST(FlightSoftware, CarriedOneLevelUpTheTargetIsLookedForWhereTheStateHeightPutsIt) {
  Harness h(carried_one_level_up());
  h.run(120.0);
  FlightSoftware& fsw = h.fsw();
  ASSERT_TRUE(h.slid());
  ASSERT_TRUE(fsw.finished()) << phase_name(fsw.phase()) << ": " << fsw.telemetry().event;
  EXPECT_EQ(fsw.telemetry().tracking.shelf_rereads, 0);
  EXPECT_EQ(fsw.telemetry().tracking.identity_contradictions, 0);
  EXPECT_EQ(fsw.result().outcome, Outcome::Crossed) << fsw.result().reason;
  ASSERT_TRUE(fsw.telemetry().tracking.target);
  EXPECT_EQ(*fsw.telemetry().tracking.target, (CellIndex{2, 3}));
  expect_through_cell_2_3(h);
}

// The same climb, missed by the state height too (its time-of-flight sensor over a raised
// floor): nothing the vehicle measures of itself saw it, the box is found where it was in the
// picture, on L3 C3, and the level check cannot tell (the height it compares is as wrong as
// the odometry). The identity check (the cell's place in the grid and its neighbours' boxes)
// contradicts it once continuity is lost; the shelf is re-read and the crossing is through
// L2 C3, the target.
TEST(FlightSoftware, AClimbTheStateHeightMissedIsCaughtByTheIdentityCheck) {
  Options o = carried_one_level_up();
  o.slide_seen_by_height = false;
  Harness h(o);
  h.run(120.0);
  FlightSoftware& fsw = h.fsw();
  ASSERT_TRUE(h.slid());
  ASSERT_TRUE(fsw.finished()) << phase_name(fsw.phase()) << ": " << fsw.telemetry().event;
  EXPECT_GE(fsw.telemetry().tracking.identity_contradictions, 1);
  EXPECT_EQ(fsw.result().outcome, Outcome::Crossed) << fsw.result().reason;
  ASSERT_TRUE(fsw.telemetry().tracking.target);
  EXPECT_EQ(*fsw.telemetry().tracking.target, (CellIndex{2, 3}));
  expect_through_cell_2_3(h);
}

// Strong gusts: from the approach on, the air sways the vehicle 2.5 cm either way at 1 Hz
// (0.16 m/s at its fastest: the state record reads up to 0.2 m/s), too little for the lateral
// law to chase at the commit range, too much for the blind crossing of a 34 cm cell (8.4 cm of
// tolerance). The flight software holds
// short of the cell, waits calm_wait_s for the air to calm, then declines the crossing: it
// backs out to give_up_clearance_m in front of the shelf and lands there, the reason named. Its
// front never reaches the shelf.
TEST(FlightSoftware, GustyHoverDeclinesTheCrossingAndLandsClear) {
  Options o;
  o.push_W_mps = [](double t, Phase p) -> Eigen::Vector2d {
    if (p != Phase::Approach && p != Phase::Cross) return Eigen::Vector2d::Zero();
    const double w = 2.0 * std::numbers::pi * 1.0;
    return {0.0, 0.025 * w * std::cos(w * t)};
  };
  Harness h(o);
  h.run(120.0);
  FlightSoftware& fsw = h.fsw();
  ASSERT_TRUE(fsw.finished()) << phase_name(fsw.phase()) << ": " << fsw.telemetry().event;
  EXPECT_EQ(fsw.result().outcome, Outcome::Aborted);
  EXPECT_EQ(fsw.result().reason.rfind(std::string(kCrossingDeclined) + kLineCannotBeHeld, 0), 0u) << fsw.result().reason;
  EXPECT_TRUE(fsw.result().landed);
  EXPECT_FALSE(h.saw_phase(Phase::Cross));
  const FlightConfig config;
  for (const auto& s : h.track()) {
    EXPECT_LT(s[1] + 0.5 * config.mission.vehicle_size_m.x(), 3.0 - config.shelf.tag_offset_m) << "t " << s[0];
  }
  const std::optional<Eigen::Vector3d> p_land = position_at_land(h);
  ASSERT_TRUE(p_land);
  EXPECT_NEAR(p_land->x(), 3.0 - config.mission.line_hold.give_up_clearance_m, 0.1) << "landed clear of the shelf";
}

}  // namespace
}  // namespace shelfcross::flight_sw
