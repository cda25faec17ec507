// The navigation room's estimators from the state records (odometry.hpp), each alone: records
// and poses in, the estimate out.
#include <gtest/gtest.h>

#include <numbers>

#include "flight_sw/navigation/odometry.hpp"
#include "flight_sw/test/state_clock.hpp"
#include "shelfcross/time.hpp"

namespace shelfcross::flight_sw {
namespace {

using testing::state_record_ns;

StateRecord record(TimeNs t_ns, double vx_H_mps, double vy_H_mps, double yaw_rad, double height_m = 1.0,
                   double vz_H_mps = 0.0) {
  StateRecord s;
  s.t_ns = t_ns;
  s.vx_H_mps = vx_H_mps;
  s.vy_H_mps = vy_H_mps;
  s.vz_H_mps = vz_H_mps;
  s.yaw_rad = yaw_rad;
  s.height_m = height_m;
  return s;
}

TEST(StateOdometry, IntegratesTheHeadingFrameVelocityTurnedByTheYaw) {
  StateOdometry o;
  // Heading 90 deg left: forward in H is +y in O. Ten records 0.1 s apart at 0.5 m/s.
  for (int k = 0; k <= 10; ++k) o.on_state(record(state_record_ns(k), 0.5, 0.0, std::numbers::pi / 2, 1.2));
  EXPECT_NEAR(o.p_O_m().x(), 0.0, 1e-12);
  EXPECT_NEAR(o.p_O_m().y(), 0.5, 1e-12);
  EXPECT_EQ(o.p_O_m().z(), 1.2);  // the state height
}

TEST(StateOdometry, AnOlderRecordMovesNothingAndAGapCountsAtMostOneSecond) {
  StateOdometry o;
  o.on_state(record(0, 1.0, 0.0, 0.0));
  o.on_state(record(5 * kNsPerSecond, 1.0, 0.0, 0.0));  // 5 s of silence: 1 s counted
  EXPECT_NEAR(o.p_O_m().x(), 1.0, 1e-12);
  o.on_state(record(4 * kNsPerSecond, 1.0, 0.0, 0.0));  // out of order: nothing
  EXPECT_NEAR(o.p_O_m().x(), 1.0, 1e-12);
}

TEST(CrossingFlown, ByItsProgressWhereKnownOtherwiseByTime) {
  CrossingEnd end;
  end.timed_ns = 4 * kNsPerSecond;
  end.line_m = 1.5;
  end.start_O_m = {1.0, 1.0};
  end.axis_O = {0.0, 1.0};
  EXPECT_NEAR(crossing_progress_m(end, {1.0, 2.4, 1.0}), 1.4, 1e-12);
  EXPECT_NEAR(crossing_progress_m(end, {3.0, 0.5, 1.0}), -0.5, 1e-12);  // across the line counts nothing
  EXPECT_FALSE(crossing_flown(end, kNsPerSecond, 1.4));
  EXPECT_TRUE(crossing_flown(end, kNsPerSecond, 1.5));
  EXPECT_FALSE(crossing_flown(end, 3 * kNsPerSecond, std::nullopt));
  EXPECT_TRUE(crossing_flown(end, 4 * kNsPerSecond, std::nullopt));
  // A progress that under-reads is bounded: 1.5 times the timed duration ends it.
  EXPECT_FALSE(crossing_flown(end, 5 * kNsPerSecond, 0.0));
  EXPECT_TRUE(crossing_flown(end, 6 * kNsPerSecond, 0.0));
}

TEST(ForwardGainEstimator, TheMeasuredAdvanceOverTheCommandedOneAfterTheLag) {
  ForwardGainEstimator g;
  // Forward 0.25 m/s commanded at scale 1 on every frame (30 per second) for 6 s; the pose
  // advances at 0.2 m/s: a gain of 0.8 once 0.8 m of command has passed the lag.
  const TimeNs frame_ns = kNsPerSecond / 30;
  for (int k = 0; k <= 180; ++k) {
    const TimeNs t = k * frame_ns;
    g.on_command_held(t, 0.25, 1.0);
    g.on_pose(t, -2.0 + 0.2 * ns_to_seconds(t - seconds_to_ns(0.7)) * (t > seconds_to_ns(0.7) ? 1.0 : 0.0));
  }
  EXPECT_NEAR(g.gain(), 0.8, 0.02);
  EXPECT_NEAR(g.speed_gain(), g.gain(), 1e-12);
  g.restart();
  g.on_pose(0, -1.0);
  EXPECT_NEAR(g.gain(), 0.8, 0.02);  // kept until measured anew
}

TEST(ForwardGainEstimator, TooLittleCommandMeasuresNothingAndTheGainIsClamped) {
  ForwardGainEstimator g;
  const TimeNs frame_ns = kNsPerSecond / 30;
  for (int k = 0; k <= 60; ++k) {  // 2 s at 0.25 m/s: 0.5 m commanded, under 0.8 m
    g.on_command_held(k * frame_ns, 0.25, 1.0);
    g.on_pose(k * frame_ns, -2.0 + 0.01 * k);
  }
  EXPECT_EQ(g.gain(), 1.0);
  ForwardGainEstimator fast;
  for (int k = 0; k <= 180; ++k) {
    fast.on_command_held(k * frame_ns, 0.25, 1.0);
    fast.on_pose(k * frame_ns, -2.0 + 0.1 * k);  // 3 m/s: far more than commanded
  }
  EXPECT_EQ(fast.gain(), 2.0);
}

TEST(CellHeightEstimator, TheMedianOfTheLastSamplesOnceThereAreThree) {
  CellHeightEstimator c;
  c.sample(1.0, 0.1);
  c.sample(1.0, 0.2);
  EXPECT_FALSE(c.measured_m());
  c.sample(1.0, -0.5);  // an outlier (1.5 m): the median ignores it
  ASSERT_TRUE(c.measured_m());
  EXPECT_NEAR(*c.measured_m(), 0.9, 1e-12);  // of 0.8, 0.9 and 1.5
  c.clear();
  EXPECT_FALSE(c.measured_m());
}

TEST(CellHeightEstimator, VerticallyStillOnlyLongAfterTheLastVerticalMotion) {
  CellHeightEstimator c;
  EXPECT_TRUE(c.vertically_still_for(0, 0.5));
  c.on_state(record(kNsPerSecond, 0.0, 0.0, 0.0, 1.0, 0.1));
  EXPECT_FALSE(c.vertically_still_for(kNsPerSecond + 400 * kMs, 0.5));
  EXPECT_TRUE(c.vertically_still_for(kNsPerSecond + 500 * kMs, 0.5));
  c.on_state(record(2 * kNsPerSecond, 0.0, 0.0, 0.0, 1.0, 0.0));  // still: not motion
  EXPECT_TRUE(c.vertically_still_for(2 * kNsPerSecond, 0.5));
}

}  // namespace
}  // namespace shelfcross::flight_sw
