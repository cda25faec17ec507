// TelloWorld's tick contract (tello_world.hpp), step by step: what a tick observes and when,
// how a contact or the arena ends the world, and the frame and state clocks both callers share.
#include "verification/world/tello_world.hpp"

#include <gtest/gtest.h>

#include <memory>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "render/ground_truth.hpp"
#include "shelfcross/random.hpp"
#include "verification/scenario/scenario.hpp"
#include "verification/world/vehicle_truth.hpp"

namespace shelfcross::verification {
namespace {

const std::string kDefault = std::string(SHELFCROSS_SOURCE_DIR) + "/scenarios/paper_test_shelf.yaml";
constexpr TimeNs kTick_ns = 2'000'000;  // the autopilot's 500 Hz

RunSetup setup_of(std::shared_ptr<Scenario> s) {
  RunSetup setup;
  setup.seed = 7;
  setup.scenario = s;
  setup.believed_camera = s->camera;
  return setup;
}

std::shared_ptr<Scenario> default_scenario() { return std::make_shared<Scenario>(load_scenario(kDefault)); }

struct Flight {
  TickReport last;              ///< the tick that ended the world, or the last one
  double path_m = 0.0;          ///< the sum of |p(t) - p(t_prev)| over the observed ticks
  int observed = 0;
};

// Ticks every kTick_ns up to t_end_s, submitting each command at its instant; stops at the
// first tick that ends the world.
Flight fly(TelloWorld& world, const std::vector<std::pair<double, std::string>>& commands, double t_end_s) {
  Flight f;
  Eigen::Vector3d p_prev = world.tello().state().p_WB_m;
  for (TimeNs t = world.tello().time_ns() + kTick_ns; t <= seconds_to_ns(t_end_s); t += kTick_ns) {
    for (const auto& [t_s, text] : commands)
      if (seconds_to_ns(t_s) == t) world.tello().submit(t, text);
    f.last = world.tick(t);
    world.tello().take_replies();
    if (f.last.end != WorldEnd::none) break;
    if (f.last.observed) {
      ++f.observed;
      f.path_m += (world.tello().state().p_WB_m - p_prev).norm();
      p_prev = world.tello().state().p_WB_m;
    }
  }
  return f;
}

const std::vector<std::pair<double, std::string>> kTakeoff = {{0.1, "command"}, {0.2, "takeoff"}};

TEST(TelloWorld, RefusesAStartNotLandedAndMonitoredShelvesOutOfRange) {
  auto s = default_scenario();
  EXPECT_THROW(TelloWorld(setup_of(s), 0), std::invalid_argument);
  EXPECT_THROW(TelloWorld(setup_of(s), 2), std::invalid_argument);  // one shelf
  s->start.landed = false;
  EXPECT_THROW(TelloWorld(setup_of(s), 1), std::invalid_argument);
  EXPECT_THROW(TelloWorld(RunSetup{}, 1), std::invalid_argument);
}

TEST(TelloWorld, ATickAtOrBeforeTheLastObservedTimeObservesNothing) {
  TelloWorld world(setup_of(default_scenario()), 1);
  const TickReport first = world.tick(kTick_ns);
  EXPECT_TRUE(first.observed);
  EXPECT_EQ(first.end, WorldEnd::none);
  ASSERT_EQ(first.faces.size(), 1u);  // one per monitored shelf
  EXPECT_EQ(world.t_last_ns(), kTick_ns);
  const TickReport again = world.tick(kTick_ns);
  EXPECT_FALSE(again.observed);
  EXPECT_TRUE(again.faces.empty());
  EXPECT_EQ(world.t_last_ns(), kTick_ns);
}

TEST(TelloWorld, ThePathIsTheSumOfTheObservedTicksSteps) {
  TelloWorld world(setup_of(default_scenario()), 1);
  const Flight f = fly(world, kTakeoff, 6.0);
  ASSERT_EQ(f.last.end, WorldEnd::none);
  EXPECT_TRUE(world.flew());
  EXPECT_EQ(f.observed, 3000);  // every 2 ms tick of 6 s moved time on
  EXPECT_NEAR(world.truth().path_length_m, f.path_m, 1e-9);
  EXPECT_GT(f.path_m, 0.8);  // the climb to the take-off height
  EXPECT_EQ(world.truth().floor_touches, 0);
  EXPECT_FALSE(world.truth().crossed);
}

TEST(TelloWorld, AShelfContactEndsTheWorldAtItsTick) {
  TelloWorld world(setup_of(default_scenario()), 1);
  std::vector<std::pair<double, std::string>> commands = kTakeoff;
  commands.emplace_back(6.0, "forward 500");  // into the shelf's face 3 m ahead, at 1 m
  const Flight f = fly(world, commands, 20.0);
  ASSERT_EQ(f.last.end, WorldEnd::collision) << f.last.detail;
  ASSERT_TRUE(f.last.contact.has_value());
  EXPECT_TRUE(plant::is_shelf_part(f.last.contact->element.kind));
  EXPECT_EQ(f.last.detail, f.last.contact->element.name);
  EXPECT_FALSE(f.last.observed);
  ASSERT_TRUE(world.truth().contact.has_value());
  EXPECT_EQ(world.t_last_ns(), f.last.t_ns);  // the contact's tick is the flight's last instant
  // The body origin is within half the vehicle's length (and its margin) of the front face.
  EXPECT_NEAR(world.tello().state().p_WB_m.x(), 3.0, 0.1);
}

TEST(TelloWorld, AWallEndsTheWorldAsLeavingTheArena) {
  TelloWorld world(setup_of(default_scenario()), 1);
  std::vector<std::pair<double, std::string>> commands = kTakeoff;
  commands.emplace_back(6.0, "back 500");  // the wall is 2 m behind the start
  const Flight f = fly(world, commands, 20.0);
  ASSERT_EQ(f.last.end, WorldEnd::left_arena) << f.last.detail;
  EXPECT_FALSE(world.truth().min_clearance_m.has_value());  // never near the shelf
  EXPECT_NEAR(world.tello().state().p_WB_m.x(), -2.0, 0.1);
}

// With ticks that do not divide the clocks' periods, a capture (a state record) is due at the
// first tick at or after each scheduled instant, carries that instant, and draws one noise seed
// from the run's render-noise stream; a tick past several instants takes one capture and skips
// the others. A global shutter (the default scenario's rolling shutter off), so that each
// capture's readout starts at its own pose.
TEST(TelloWorld, CapturesAndStateRecordsAreDueAtTheFirstTickAtOrAfterTheirInstants) {
  auto s = default_scenario();
  s->readout_s = 0.0;
  TelloWorld world(setup_of(s), 1);
  const std::int64_t frame_mhz = millihertz(s->frame_rate_hz), state_mhz = millihertz(s->cosim.state_rate_hz);
  RandomStream noise(7, StreamId::render_noise);
  std::int64_t k_frame = 0, k_state = 0, captures = 0, states = 0;
  Eigen::Isometry3d X_WC_prev = render::camera_pose_W(body_pose(world.tello().state()), s->camera_mount);
  const TimeNs step_ns = 7'000'000;
  for (TimeNs t = step_ns; t <= seconds_to_ns(2.0); t += step_ns) {
    ASSERT_EQ(world.tick(t).end, WorldEnd::none);
    const auto c = world.capture_due(t);
    const bool frame_due = event_time(k_frame, frame_mhz) <= t;
    ASSERT_EQ(c.has_value(), frame_due) << "t " << t;
    if (c) {
      ++captures;
      EXPECT_EQ(c->index, k_frame);
      EXPECT_EQ(c->t_ns, event_time(k_frame, frame_mhz));
      EXPECT_EQ(c->period_ns, event_time(k_frame + 1, frame_mhz) - c->t_ns);
      EXPECT_EQ(c->noise_seed, noise.next_u64());
      EXPECT_EQ(c->X_WC_prev.matrix(), X_WC_prev.matrix());
      EXPECT_EQ(c->X_WC_readout_start.matrix(), c->X_WC.matrix());  // a global shutter
      X_WC_prev = c->X_WC;
      while (event_time(k_frame, frame_mhz) <= t) ++k_frame;
    }
    EXPECT_EQ(world.next_capture_ns(), event_time(k_frame, frame_mhz));
    const bool state_due = event_time(k_state, state_mhz) <= t;
    ASSERT_EQ(world.state_due(t), state_due) << "t " << t;
    if (state_due) {
      ++states;
      while (event_time(k_state, state_mhz) <= t) ++k_state;
    }
    EXPECT_EQ(world.next_state_ns(), event_time(k_state, state_mhz));
  }
  // 2 s at 30 frames a second, each instant taken by the 7 ms tick after it.
  EXPECT_EQ(captures, 60);
  EXPECT_GT(states, 0);
}

}  // namespace
}  // namespace shelfcross::verification
