// The mission room's units alone (video_intake.hpp, transfer_flight.hpp, cell_crossing.hpp):
// inputs in, what the unit decides out, with no FlightSoftware around them; then the video's
// stall flown through FlightSoftware against the kinematic vehicle (flight_harness.hpp).
#include <gtest/gtest.h>

#include <cmath>
#include <optional>

#include <opencv2/core.hpp>

#include "flight_sw/config.hpp"
#include "flight_sw/mission/cell_crossing.hpp"
#include "flight_sw/mission/facts.hpp"
#include "flight_sw/mission/test/flight_harness.hpp"
#include "flight_sw/mission/transfer_flight.hpp"
#include "flight_sw/mission/video_intake.hpp"
#include "flight_sw/test/state_clock.hpp"
#include "shelfcross/time.hpp"

namespace shelfcross::flight_sw {
namespace {

using testing::Harness;
using testing::Options;

using testing::state_record_ns;

CameraFrame frame(const FlightConfig& c, int damage_events = 0, std::vector<RowSpan> rows = {}) {
  CameraFrame f;
  f.bgr = cv::Mat(c.camera.height_px, c.camera.width_px, CV_8UC3, cv::Scalar(10, 200, 30));
  f.damaged = damage_events > 0;
  f.damage_events = damage_events;
  f.damaged_rows = std::move(rows);
  return f;
}

const VideoIntake::DecisionRegion kNoRegion = [] { return std::optional<cv::Rect2d>(); };

TEST(VideoIntake, AWholePictureDecidesAndAWrongSizedFrameIsRefused) {
  const FlightConfig c;
  VideoIntake intake(c);
  MissionFacts facts;
  facts.now_ns = kNsPerSecond;
  const CameraFrame whole = frame(c);
  const std::optional<Picture> p = intake.take(whole, facts, kNoRegion);
  ASSERT_TRUE(p);
  EXPECT_TRUE(p->decides);
  EXPECT_TRUE(p->whole());
  EXPECT_EQ(p->t_ns, kNsPerSecond);
  CameraFrame small;
  small.bgr = cv::Mat(10, 10, CV_8UC3);
  EXPECT_FALSE(intake.take(small, facts, kNoRegion));
  EXPECT_EQ(facts.telemetry.link.bad_frames, 1);
}

TEST(VideoIntake, APictureTooDamagedToDecideStillDecidesWhereItsDamageLiesClearOfTheDecision) {
  const FlightConfig c;
  VideoIntake intake(c);
  MissionFacts facts;
  const int events = c.perception.decide_max_damage_events + 1;
  const CameraFrame f = frame(c, events, {{0, 40}});
  EXPECT_FALSE(intake.take(f, facts, kNoRegion)->decides);  // the region unknown: no decision
  const double margin = c.perception.band_margin_px;
  const auto clear = [&] { return std::optional<cv::Rect2d>(cv::Rect2d(0, 40 + margin + 1, 100, 100)); };
  const std::optional<Picture> p = intake.take(f, facts, clear);
  ASSERT_TRUE(p);
  EXPECT_TRUE(p->decides);
  EXPECT_EQ(p->bgr.at<cv::Vec3b>(10, 10), cv::Vec3b(128, 128, 128));  // the damaged rows blanked
  EXPECT_EQ(p->bgr.at<cv::Vec3b>(300, 10), cv::Vec3b(10, 200, 30));
  EXPECT_EQ(facts.telemetry.link.band_decided_frames, 1);
  const auto near = [&] { return std::optional<cv::Rect2d>(cv::Rect2d(0, 40 + margin - 1, 100, 100)); };
  EXPECT_FALSE(intake.take(f, facts, near)->decides);
  EXPECT_EQ(facts.telemetry.link.damaged_frames, 3);
}

TEST(VideoIntake, NoFrameHoversOnceThenLands) {
  const FlightConfig c;
  VideoIntake intake(c);
  MissionFacts facts;
  intake.airborne_from(0);
  facts.now_ns = seconds_to_ns(0.9 * c.timeouts.video_hover_s);
  EXPECT_EQ(intake.stall(facts), VideoStall::None);
  facts.now_ns = seconds_to_ns(1.1 * c.timeouts.video_hover_s);
  EXPECT_EQ(intake.stall(facts), VideoStall::Hover);
  EXPECT_TRUE(intake.stalled());
  EXPECT_EQ(intake.stall(facts), VideoStall::None);  // once per stall
  facts.now_ns = seconds_to_ns(1.1 * c.timeouts.video_land_s);
  EXPECT_EQ(intake.stall(facts), VideoStall::Land);
  const CameraFrame f = frame(c);
  ASSERT_TRUE(intake.take(f, facts, kNoRegion));
  EXPECT_FALSE(intake.stalled());
  EXPECT_EQ(facts.telemetry.event, "video back");
}

// A link outage (a Wi-Fi re-association): the state records stop with the frames. Nothing sent
// reaches the drone before the link returns, so the stall hovers and never lands meanwhile; from
// the first state record after it the video has video_land_s to come back.
TEST(VideoIntake, ALinkOutageOnlyHoversAndTheVideoGetsItsTimeFromTheReturn) {
  const FlightConfig c;
  VideoIntake intake(c);
  MissionFacts facts;
  intake.airborne_from(0);
  StateRecord s;
  s.t_ns = seconds_to_ns(1.0);  // the last record before the outage, the last frame at 0
  facts.state = s;
  facts.now_ns = seconds_to_ns(1.1 * c.timeouts.video_hover_s);
  EXPECT_EQ(intake.stall(facts), VideoStall::Hover);
  const double back_s = 1.0 + 2.0 * c.timeouts.video_land_s;
  for (double t = 1.0; t < back_s; t += 0.05) {
    facts.now_ns = seconds_to_ns(t);
    EXPECT_NE(intake.stall(facts), VideoStall::Land) << t << " s: the link is out, not the video";
  }
  s.t_ns = seconds_to_ns(back_s);  // the link back: the first state record
  facts.state = s;
  facts.now_ns = s.t_ns;
  EXPECT_EQ(intake.stall(facts), VideoStall::None);
  EXPECT_TRUE(intake.stalled()) << "still no frame: the hover holds";
  for (double t = back_s; t < back_s + 0.9 * c.timeouts.video_land_s; t += 0.1) {
    s.t_ns = facts.now_ns = seconds_to_ns(t);
    facts.state = s;
    EXPECT_EQ(intake.stall(facts), VideoStall::None) << t;
  }
  s.t_ns = facts.now_ns = seconds_to_ns(back_s + 1.1 * c.timeouts.video_land_s);
  facts.state = s;
  EXPECT_EQ(intake.stall(facts), VideoStall::Land) << "the state records come, the frames do not: the video is lost";
}

TEST(TransferFlight, FliesItsWaypointsOneLegAtATimeAndArrivesAtTheLast) {
  FlightConfig c;
  c.strategy.mode = Strategy::over_tops;
  c.layout.shelf_count = 2;
  c.layout.shelf_spacing_m = 4.0;
  TransferFlight t;
  PoseEstimate pose_G;  // at the viewpoint, facing the shelf
  pose_G.X_FB.translation() = Eigen::Vector3d(-1.5, 0.0, 0.0);
  t.plan(c, pose_G, 0.0, Eigen::Vector3d(0.0, 0.0, 1.0), Eigen::Vector3d(-1.5, 0.0, 0.0), false, 0);
  EXPECT_EQ(t.waypoint(), 0u);
  EXPECT_EQ(t.hold_yaw_O_rad(), 0.0);
  const double tol = c.strategy.waypoint_tolerance_m;
  // Not there: the error points at the first waypoint, straight up.
  TransferFlight::Progress p = t.on_state(Eigen::Vector3d(0.0, 0.0, 1.0), tol, kNsPerSecond);
  EXPECT_FALSE(p.next_leg);
  EXPECT_FALSE(p.arrived);
  EXPECT_NEAR(p.e_O_m.x(), 0.0, 1e-12);
  EXPECT_GT(p.e_O_m.z(), 0.0);
  // Step onto each waypoint in turn.
  int legs = 0;
  Eigen::Vector3d at(0.0, 0.0, 1.0);
  for (int k = 0; k < 10 && !p.arrived; ++k) {
    at += p.e_O_m;
    p = t.on_state(at, tol, (2 + k) * kNsPerSecond);
    legs += p.next_leg ? 1 : 0;
  }
  EXPECT_TRUE(p.arrived);
  EXPECT_EQ(legs, 2);  // up, across, and down to the next viewpoint
  EXPECT_NEAR(at.x(), c.layout.shelf_spacing_m, 1e-9);
}

// A crossing along +x of O from the origin, 2 m long, stoppable for its first 0.5 m, 5 cm of
// slack either way, holding 1.0 m of state height.
CrossingStart straight_crossing() {
  CrossingStart start;
  start.end.line_m = 2.0;
  start.end.timed_ns = 10 * kNsPerSecond;
  start.watch.stop_before_m = 0.5;
  start.watch.slack_y_m = 0.05;
  start.watch.slack_z_m = 0.05;
  start.height_m = 1.0;
  return start;
}

StateRecord state_at(TimeNs t_ns, double vx_H_mps, double vy_H_mps, double height_m) {
  StateRecord s;
  s.t_ns = t_ns;
  s.vx_H_mps = vx_H_mps;
  s.vy_H_mps = vy_H_mps;
  s.height_m = height_m;
  return s;
}

TEST(CellCrossing, HoldsTheCellsHeightByTheStateHeight) {
  const FlightConfig c;
  CellCrossing crossing(c);
  EXPECT_FALSE(crossing.holding());
  crossing.begin(straight_crossing(), 0);
  ASSERT_TRUE(crossing.holding());
  EXPECT_GT(crossing.vz_mps(0.9), 0.0);
  EXPECT_LT(crossing.vz_mps(1.1), 0.0);
  EXPECT_EQ(crossing.vz_mps(1.0), 0.0);
  crossing.stop();
  EXPECT_FALSE(crossing.holding());
}

TEST(CellCrossing, StopsADriftSeenBeforeTheCellAndFliesOnPastThatPoint) {
  const FlightConfig c;
  CellCrossing crossing(c);
  crossing.begin(straight_crossing(), 0);
  MissionFacts facts;
  // Straight along the line at 0.4 m/s: no stop.
  facts.on_state(state_at(0, 0.4, 0.0, 1.0));
  EXPECT_FALSE(crossing.watch(state_at(0, 0.4, 0.0, 1.0), facts));
  // Drifting sideways at 0.2 m/s: carried 10 cm across within the lag, past the 5 cm slack.
  const StateRecord drifting = state_at(state_record_ns(1), 0.0, 0.2, 1.0);
  facts.on_state(drifting);
  const std::optional<CrossingStop> stop = crossing.watch(drifting, facts);
  ASSERT_TRUE(stop);
  EXPECT_EQ(stop->why.rfind("drift seen before the cell", 0), 0u) << stop->why;
  EXPECT_EQ(facts.telemetry.control.crossings_backed_out, 1);
  // The same drift once the vehicle cannot stop short of the front face: flown on.
  MissionFacts past;
  past.on_state(state_at(0, 1.0, 0.0, 1.0));
  past.on_state(state_at(kNsPerSecond, 1.0, 0.0, 1.0));  // 1 m along the line
  EXPECT_FALSE(crossing.watch(state_at(kNsPerSecond, 0.0, 0.2, 1.0), past));
  EXPECT_EQ(past.telemetry.control.crossings_backed_out, 0);
}

TEST(CellCrossing, EndsWhenTheOdometryHasFlownTheLine) {
  const FlightConfig c;
  CellCrossing crossing(c);
  crossing.begin(straight_crossing(), 0);
  MissionFacts facts;
  for (int k = 0; k <= 19; ++k) facts.on_state(state_at(state_record_ns(k), 1.0, 0.0, 1.0));
  facts.now_ns = 1900 * kMs;
  EXPECT_FALSE(crossing.flown(facts.now_ns, facts));  // 1.9 m of 2
  facts.on_state(state_at(2000 * kMs, 1.0, 0.0, 1.0));
  facts.on_state(state_at(state_record_ns(21), 1.0, 0.0, 1.0));
  facts.now_ns = state_record_ns(21);
  EXPECT_TRUE(crossing.flown(facts.now_ns, facts));  // 2.1 m
}

// A height hold that follows the range: 0.5 s into the crossing the range steps from 1.0 m to
// 0.4 m (the box of the cell below) and the vehicle climbs 5 cm a record, which the range and
// the vertical speed show and h does not. Held at h, the crossing would ask nothing; held at
// h less the offset read, it asks the climb back and more, and the event names the hold.
TEST(CellCrossing, HoldsTheHeightAHoldFollowingTheRangeHidesFromH) {
  const FlightConfig c;
  CellCrossing crossing(c);
  crossing.begin(straight_crossing(), 0);
  MissionFacts facts;
  double climb = 0.0;
  for (int k = 0; k <= 9; ++k) {
    StateRecord s = state_at(state_record_ns(k), 0.4, 0.0, 1.0);
    if (k > 5) climb += 0.05;
    s.vz_H_mps = k > 5 ? 0.5 : 0.0;
    s.tof_m = (k >= 5 ? 0.4 : 1.0) + climb;
    facts.on_state(s);
    crossing.on_state(s, facts);
  }
  EXPECT_LT(crossing.vz_mps(1.0), -c.control.crossing_z_speed_max_mps - 0.1);  // the climb's rate asked back, and its error
  EXPECT_NE(facts.telemetry.event.find("the height hold follows the range"), std::string::npos) << facts.telemetry.event;
  // The same records with a fused hold (the range steps, nothing climbs): held at h.
  CellCrossing fused(c);
  fused.begin(straight_crossing(), 0);
  for (int k = 0; k <= 9; ++k) {
    StateRecord s = state_at(state_record_ns(k), 0.4, 0.0, 1.0);
    s.tof_m = k >= 5 ? 0.4 : 1.0;
    fused.on_state(s, facts);
  }
  EXPECT_EQ(fused.vz_mps(1.0), 0.0);
}

// The VPS lost in the crossing (vgx = vgy = 0 exactly while flying, over the box below its
// range) after 1 s at 0.4 m/s: the odometry stands still at 0.4 m, and the rest of the 2 m
// line is flown blind at the 0.4 m/s the VPS read, 4 s more, neither at the timing from the
// approach's gain (10 s here) nor cut short by it. The watch never stops it on the odometry's
// word. Records late: the time since the last one counts at that speed too.
TEST(CellCrossing, WithTheVpsLostFliesTheRestAtTheSpeedItReadAndIsNeverStopped) {
  const FlightConfig c;
  CellCrossing crossing(c);
  crossing.begin(straight_crossing(), 0);
  MissionFacts facts;
  const auto record = [&](int k) {
    const StateRecord s = state_at(state_record_ns(k), k <= 10 ? 0.4 : 0.0, 0.0, 1.0);
    facts.on_state(s);
    crossing.on_state(s, facts);
    facts.now_ns = s.t_ns;
  };
  for (int k = 0; k <= 12; ++k) record(k);
  EXPECT_NE(facts.telemetry.event.find("VPS lost"), std::string::npos) << facts.telemetry.event;
  EXPECT_FALSE(crossing.watch(state_at(1300 * kMs, 0.0, 0.3, 1.2), facts));
  for (int k = 13; k <= 48; ++k) record(k);
  EXPECT_FALSE(crossing.flown(facts.now_ns, facts));  // 0.4 + 3.8 s x 0.4 = 1.92 m
  for (int k = 49; k <= 51; ++k) record(k);
  EXPECT_TRUE(crossing.flown(facts.now_ns, facts));  // 2.04 m, 5.1 s in
  // The same crossing whose records stop 3 s in (1.2 m flown): flown 2 s after the last one.
  CellCrossing late(c);
  late.begin(straight_crossing(), 0);
  MissionFacts f;
  for (int k = 0; k <= 30; ++k) {
    const StateRecord s = state_at(state_record_ns(k), k <= 10 ? 0.4 : 0.0, 0.0, 1.0);
    f.on_state(s);
    late.on_state(s, f);
  }
  f.now_ns = 4900 * kMs;
  EXPECT_FALSE(late.flown(f.now_ns, f));
  f.now_ns = state_record_ns(51);
  EXPECT_TRUE(late.flown(f.now_ns, f));
}

// The VPS reads nothing from the start of the crossing: no speed read, nothing tells how far
// it has flown, and the crossing ends by its timing (10 s), as with no state at all.
TEST(CellCrossing, WithTheVpsNeverReadEndsByItsTiming) {
  const FlightConfig c;
  CellCrossing crossing(c);
  crossing.begin(straight_crossing(), 0);
  MissionFacts facts;
  for (int k = 0; k <= 99; ++k) {
    const StateRecord s = state_at(state_record_ns(k), 0.0, 0.0, 1.0);
    facts.on_state(s);
    crossing.on_state(s, facts);
  }
  facts.now_ns = 9900 * kMs;
  EXPECT_FALSE(crossing.flown(facts.now_ns, facts));
  facts.on_state(state_at(10 * kNsPerSecond, 0.0, 0.0, 1.0));
  facts.now_ns = 10 * kNsPerSecond;
  EXPECT_TRUE(crossing.flown(facts.now_ns, facts));
}

// ---- Through FlightSoftware: the kinematic vehicle (flight_harness.hpp) ----

TEST(FlightSoftware, VideoStallHoversThenLands) {
  Options o;
  o.blank_frames = true;
  o.frames_on = [](TimeNs t) { return t < 4 * kNsPerSecond; };
  Harness h(o);
  h.run(20.0);
  ASSERT_TRUE(h.fsw().finished());
  EXPECT_EQ(h.fsw().result().reason, "video lost");
  EXPECT_TRUE(h.fsw().result().landed);
  // The last frame came at < 4 s: hover (rc 0 0 0 0) sent from a state record 0.5 s later,
  // land 3 s later, nothing but hover in between.
  TimeNs hover_t = -1, land_t = -1;
  for (const auto& c : h.commands()) {
    if (c.t_ns > 4 * kNsPerSecond && hover_t < 0 && c.text.rfind("rc", 0) == 0) {
      EXPECT_EQ(c.text, "rc 0 0 0 0");
      hover_t = c.t_ns;
    }
    if (c.text == "land") land_t = c.t_ns;
    if (c.t_ns > 4 * kNsPerSecond && c.text.rfind("rc", 0) == 0) {
      EXPECT_EQ(c.text, "rc 0 0 0 0");
    }
  }
  const double last_frame_s = std::floor(4.0 * 15 - 1e-9) / 15.0;
  EXPECT_NEAR(ns_to_seconds(hover_t) - last_frame_s, 0.5, 0.1 + 1e-9);
  EXPECT_NEAR(ns_to_seconds(land_t) - last_frame_s, 3.0, 0.1 + 1e-9);
}

}  // namespace
}  // namespace shelfcross::flight_sw
