// The poses a rolling-shutter capture is rendered between come from the simulated trajectory:
// the readout ends at the capture's tick (its pose X_WC) and starts camera.readout_s before it,
// at the camera pose the world had then (interpolated between the ticks around that instant).
// With a global shutter the two are the same pose, bit for bit.
#include <gtest/gtest.h>

#include <algorithm>
#include <map>

#include "render/ground_truth.hpp"
#include "verification/scenario/scenario.hpp"
#include "verification/world/tello_world.hpp"
#include "verification/world/vehicle_truth.hpp"

namespace shelfcross::verification {
namespace {

const std::string kDefault = std::string(SHELFCROSS_SOURCE_DIR) + "/scenarios/paper_test_shelf.yaml";

// Flies take-off and a turn, ticking every 2 ms; returns the largest heading change over a
// readout seen in the captures, and checks each capture's poses against the trajectory.
double fly_and_check(double readout_s) {
  auto s = std::make_shared<Scenario>(load_scenario(kDefault));
  s->readout_s = readout_s;
  RunSetup setup;
  setup.seed = 7;
  setup.scenario = s;
  setup.believed_camera = s->camera;
  TelloWorld world(setup, 1);
  const TimeNs tick_ns = 2'000'000, readout_ns = seconds_to_ns(readout_s);
  std::map<TimeNs, Eigen::Isometry3d> trajectory;  // the camera pose at every tick
  trajectory[0] = render::camera_pose_W(body_pose(world.tello().state()), s->camera_mount);
  double largest_turn_rad = 0.0;
  int captures = 0;
  for (TimeNs t = tick_ns; t <= seconds_to_ns(9.0); t += tick_ns) {
    if (t == seconds_to_ns(0.1)) world.tello().submit(t, "command");
    if (t == seconds_to_ns(0.2)) world.tello().submit(t, "takeoff");
    if (t == seconds_to_ns(6.0)) world.tello().submit(t, "cw 90");
    EXPECT_EQ(world.tick(t).end, WorldEnd::none);
    world.tello().take_replies();
    trajectory[t] = render::camera_pose_W(body_pose(world.tello().state()), s->camera_mount);
    const auto c = world.capture_due(t);
    if (!c) continue;
    ++captures;
    EXPECT_EQ(c->X_WC.matrix(), trajectory[t].matrix());
    if (readout_ns == 0) {
      EXPECT_EQ(c->X_WC_readout_start.matrix(), c->X_WC.matrix());
      continue;
    }
    // The readout's start falls on a tick here (readout a whole number of ticks).
    const TimeNs t0 = std::max<TimeNs>(0, t - readout_ns);
    const Eigen::Isometry3d& expected = trajectory.at(t0);
    EXPECT_LT((c->X_WC_readout_start.matrix() - expected.matrix()).cwiseAbs().maxCoeff(), 1e-12) << "t " << t;
    const Eigen::AngleAxisd turn(c->X_WC_readout_start.linear().transpose() * c->X_WC.linear());
    largest_turn_rad = std::max(largest_turn_rad, turn.angle());
  }
  EXPECT_GT(captures, 250);
  return largest_turn_rad;
}

TEST(RollingShutterCapture, ReadoutStartIsTheTrajectorysPoseReadoutBefore) {
  // A turn at up to the autopilot's yaw rate: over 30 ms the heading moves by some hundredths.
  EXPECT_GT(fly_and_check(0.030), 0.01);
}

TEST(RollingShutterCapture, GlobalShutterReadsOutAtOnePose) { EXPECT_EQ(fly_and_check(0.0), 0.0); }

}  // namespace
}  // namespace shelfcross::verification
