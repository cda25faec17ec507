// The command phases alone (command_phases.hpp): the SDK's replies, their loss and the state
// height in, the transition each step decides out, with no FlightSoftware around them; then
// the same decisions flown through FlightSoftware against the kinematic vehicle
// (flight_harness.hpp): the takeoff's and the landing's replies refused or lost.
#include <gtest/gtest.h>

#include <algorithm>
#include <optional>
#include <string>
#include <vector>

#include "flight_sw/config.hpp"
#include "flight_sw/mission/command_phases.hpp"
#include "flight_sw/mission/facts.hpp"
#include "flight_sw/mission/test/flight_harness.hpp"
#include "shelfcross/time.hpp"

namespace shelfcross::flight_sw {
namespace {

using testing::FrameStep;
using testing::Harness;
using testing::Options;

// A CommandPhases in a phase, with the clock of its inputs: `ask` sends the phase's command
// at once, `reply` answers it, `later` moves the clock without an input.
class CommandPhasesTest : public ::testing::Test {
 protected:
  CommandPhasesTest() : phases_(config_) { facts_.now_ns = kNsPerSecond; }

  /// The phase becomes `p` (through the table's path from Idle), and its command goes out.
  void in_phase(std::vector<Phase> path, const std::string& command, double timeout_s) {
    for (Phase p : path) facts_.phase.enter(p, facts_.now_ns);
    phases_.ask(command, timeout_s);
    sent_ = poll();
  }
  std::vector<std::string> poll() {
    std::vector<SdkCommand> out;
    phases_.poll(facts_.now_ns, out);
    std::vector<std::string> text;
    for (const SdkCommand& c : out) text.push_back(c.text);
    return text;
  }
  std::optional<Transition> reply(const std::string& text) {
    facts_.now_ns += 50 * kMs;
    return phases_.on_reply({facts_.now_ns, text}, facts_);
  }
  void later(double s) { facts_.now_ns += seconds_to_ns(s); }
  /// The outstanding command and each of its retries refused with `text`.
  void refuse_every_attempt(const std::string& text) {
    for (int attempt = 0; attempt <= config_.timeouts.command_retries; ++attempt) {
      EXPECT_EQ(reply(text), std::nullopt) << attempt;
      later(config_.timeouts.command_gap_s);
      poll();
    }
  }
  void state(double height_m, double vz_mps = 0.0, int battery_pct = 80) {
    StateRecord s;
    s.t_ns = facts_.now_ns;
    s.height_m = height_m;
    s.vz_H_mps = vz_mps;
    s.battery_pct = battery_pct;
    facts_.on_state(s);
  }

  const FlightConfig config_;
  MissionFacts facts_;
  CommandPhases phases_;
  std::vector<std::string> sent_;
};

const std::vector<Phase> kToSdk{Phase::EnterSdk};
const std::vector<Phase> kToTakeOff{Phase::EnterSdk, Phase::StartVideo, Phase::WaitVideo, Phase::TakeOff};

TEST_F(CommandPhasesTest, SdkModeThenVideoOnEachAnOk) {
  in_phase(kToSdk, "command", config_.timeouts.command_reply_s);
  EXPECT_EQ(sent_, std::vector<std::string>{"command"});
  EXPECT_EQ(reply("ok"), (Transition{Phase::StartVideo, "SDK mode; starting video"}));
  facts_.phase.enter(Phase::StartVideo, facts_.now_ns);
  later(0.2);
  phases_.ask("streamon", config_.timeouts.command_reply_s);
  EXPECT_EQ(poll(), std::vector<std::string>{"streamon"});
  EXPECT_EQ(reply(" OK "), (Transition{Phase::WaitVideo, "video on; waiting for the first frame"}));
}

TEST_F(CommandPhasesTest, ALostReplyIsAskedAgainUntilTheRetriesAreSpentThenTheMissionEndsOnTheGround) {
  in_phase(kToSdk, "command", config_.timeouts.command_reply_s);
  for (int attempt = 1; attempt <= config_.timeouts.command_retries; ++attempt) {
    later(config_.timeouts.command_reply_s + 0.01);
    EXPECT_EQ(phases_.check_timeout(facts_), std::nullopt) << attempt;
    EXPECT_EQ(facts_.telemetry.event, "'command' timed out, retry " + std::to_string(attempt));
    later(config_.timeouts.command_gap_s);
    EXPECT_EQ(poll(), std::vector<std::string>{"command"}) << attempt;
  }
  later(config_.timeouts.command_reply_s + 0.01);
  EXPECT_EQ(phases_.check_timeout(facts_), (Transition{Phase::Done, "gave up on the ground: 'command' failed: no reply"}));
  EXPECT_EQ(phases_.result().outcome, Outcome::Aborted);
  EXPECT_FALSE(phases_.result().landed);
}

TEST_F(CommandPhasesTest, TakesOffOnTheFirstPictureUnlessTheBatteryIsBelowTheTakeOffMinimum) {
  for (Phase p : {Phase::EnterSdk, Phase::StartVideo, Phase::WaitVideo}) facts_.phase.enter(p, facts_.now_ns);
  state(0.0, 0.0, config_.mission.takeoff_min_battery_pct);
  EXPECT_EQ(phases_.take_off_if_ready(facts_), (Transition{Phase::TakeOff, "taking off"}));
  state(0.0, 0.0, config_.mission.takeoff_min_battery_pct - 1);
  const std::string why = "battery " + std::to_string(config_.mission.takeoff_min_battery_pct - 1) +
                          "% below the take-off minimum";
  EXPECT_EQ(phases_.take_off_if_ready(facts_), (Transition{Phase::Done, "gave up on the ground: " + why}));
  EXPECT_EQ(phases_.result().reason, why);
  EXPECT_EQ(phases_.result().outcome, Outcome::Aborted);
}

TEST_F(CommandPhasesTest, NoVideoAfterStreamonEndsOnTheGroundOnlyPastItsTimeout) {
  for (Phase p : {Phase::EnterSdk, Phase::StartVideo, Phase::WaitVideo}) facts_.phase.enter(p, facts_.now_ns);
  later(config_.timeouts.video_start_s - 0.1);
  EXPECT_EQ(phases_.supervise(facts_), std::nullopt);
  later(0.2);
  EXPECT_EQ(phases_.supervise(facts_), (Transition{Phase::Done, "gave up on the ground: no video after streamon"}));
}

TEST_F(CommandPhasesTest, ALostTakeoffReplyWithTheStateHeightUpIsAirborne) {
  in_phase(kToTakeOff, "takeoff", config_.timeouts.takeoff_reply_s);
  EXPECT_EQ(sent_, std::vector<std::string>{"takeoff"});
  later(config_.timeouts.takeoff_reply_s + 0.01);
  state(config_.mission.airborne_height_m + 0.05);
  EXPECT_EQ(phases_.check_timeout(facts_), (Transition{Phase::FindShelf, "airborne (takeoff reply lost)"}));
}

TEST_F(CommandPhasesTest, EveryTakeoffRefusedThenUpAndStillIsAirborne) {
  in_phase(kToTakeOff, "takeoff", config_.timeouts.takeoff_reply_s);
  refuse_every_attempt("error");
  EXPECT_EQ(phases_.supervise(facts_), std::nullopt);  // no state record yet
  state(config_.mission.airborne_height_m + 0.2, 0.3);  // still climbing
  EXPECT_EQ(phases_.supervise(facts_), std::nullopt);
  later(0.1);
  state(config_.mission.airborne_height_m + 0.5, 0.0);
  const std::optional<Transition> up = phases_.supervise(facts_);
  ASSERT_TRUE(up);
  EXPECT_EQ(up->phase, Phase::FindShelf);
}

TEST_F(CommandPhasesTest, EveryTakeoffRefusedAndStillLowAfterTheWaitStayedOnTheGround) {
  in_phase(kToTakeOff, "takeoff", config_.timeouts.takeoff_reply_s);
  refuse_every_attempt("error Motor stop");
  state(0.0);
  EXPECT_EQ(phases_.supervise(facts_), std::nullopt);
  later(3.1);
  EXPECT_EQ(phases_.supervise(facts_), (Transition{Phase::Done, "gave up on the ground: takeoff failed: error Motor stop"}));
}

TEST_F(CommandPhasesTest, LandOkEndsTheMissionInThePendingOutcome) {
  in_phase({Phase::EnterSdk, Phase::StartVideo, Phase::WaitVideo, Phase::TakeOff, Phase::FindShelf, Phase::Land},
           "land", config_.timeouts.land_reply_s);
  phases_.landing(Outcome::Crossed, "crossed cell L2 C2");
  EXPECT_EQ(reply("ok"), (Transition{Phase::Done, "landed"}));
  EXPECT_EQ(phases_.result().outcome, Outcome::Crossed);
  EXPECT_EQ(phases_.result().reason, "crossed cell L2 C2");
  EXPECT_TRUE(phases_.result().landed);
}

TEST_F(CommandPhasesTest, LandRefusedInTheAirIsAskedAgainAfterAWaitAndEndsOnTheStateHeight) {
  in_phase({Phase::EnterSdk, Phase::StartVideo, Phase::WaitVideo, Phase::TakeOff, Phase::FindShelf, Phase::Land},
           "land", config_.timeouts.land_reply_s);
  phases_.landing(Outcome::Aborted, "video lost");
  state(0.8);
  EXPECT_EQ(reply("error Not joystick"), std::nullopt);
  EXPECT_EQ(facts_.telemetry.event, "'land' refused in the air (error Not joystick): waiting for the state height");
  later(0.3);  // past the gap between commands, within the wait
  EXPECT_TRUE(poll().empty());
  later(0.3);
  EXPECT_EQ(poll(), std::vector<std::string>{"land"});
  // Coming down, then low and still on a fresh record: down without the `ok`.
  state(0.5, -0.4);
  EXPECT_EQ(phases_.supervise(facts_), std::nullopt);
  later(1.0);
  state(config_.mission.airborne_height_m - 0.1, 0.0);
  EXPECT_EQ(phases_.supervise(facts_), (Transition{Phase::Done, "landed (no `ok` yet: the state height says on the ground)"}));
  EXPECT_EQ(phases_.result().outcome, Outcome::Aborted);
  EXPECT_TRUE(phases_.result().landed);
}

// ---- Through FlightSoftware: the kinematic vehicle (flight_harness.hpp) ----

TEST(FlightSoftware, TakeoffRefusedIsRetriedThenGivenUpOnTheGround) {
  Options o;
  o.takeoff_replies = {"error No valid imu"};
  o.blank_frames = true;
  Harness h(o);
  h.run(60.0);
  const auto cmds = h.non_rc();
  EXPECT_EQ(std::count(cmds.begin(), cmds.end(), "takeoff"), 4);  // 1 + 3 retries
  EXPECT_EQ(std::count(cmds.begin(), cmds.end(), "land"), 0);
  ASSERT_TRUE(h.fsw().finished());
  EXPECT_EQ(h.fsw().result().outcome, Outcome::Aborted);
  EXPECT_FALSE(h.fsw().result().landed);
  EXPECT_NE(h.fsw().result().reason.find("takeoff failed"), std::string::npos);
  // ... once the state height has stayed low 3 s after the last refusal (no takeoff under way).
  EXPECT_GT(h.now(), h.sent("takeoff").back() + 3 * kNsPerSecond);
}

// Every `takeoff` refused while the drone climbs (a duplicated datagram took off): the flight
// software watches the state height instead of saying it stayed on the ground, and flies on
// once the climb has ended, not in it.
TEST(FlightSoftware, TakeoffRefusedWhileTakingOffIsSeenInTheStateHeight) {
  Options o;
  o.takeoff_duplicated = true;
  o.blank_frames = true;
  o.start_W_m.z() = 0.0;
  Harness h(o);
  h.run(10.0);
  const auto cmds = h.non_rc();
  EXPECT_EQ(std::count(cmds.begin(), cmds.end(), "takeoff"), 4);  // 1 + 3 retries, all refused
  EXPECT_EQ(std::count(cmds.begin(), cmds.end(), "land"), 0);
  EXPECT_FALSE(h.fsw().finished());
  EXPECT_EQ(h.fsw().phase(), Phase::FindShelf);
  // Up at 1 m only 1 s + 1 m / 0.45 m/s after the first `takeoff`: no phase of flight before.
  const TimeNs up_ns = h.sent("takeoff").front() + 1000 * kMs + seconds_to_ns(1.0 / 0.45);
  for (const FrameStep& st : h.frame_steps()) {
    if (st.t_ns < up_ns) {
      EXPECT_EQ(st.after, Phase::TakeOff) << "at " << ns_to_seconds(st.t_ns) << " s";
    }
  }
}

TEST(FlightSoftware, TakeoffRetriedAfterAnErrorThenFlies) {
  Options o;
  o.takeoff_replies = {"error", "ok"};
  o.blank_frames = true;
  Harness h(o);
  h.run(8.0);
  const auto cmds = h.non_rc();
  EXPECT_EQ(std::count(cmds.begin(), cmds.end(), "takeoff"), 2);
  EXPECT_EQ(h.fsw().phase(), Phase::FindShelf);
}

TEST(FlightSoftware, LostTakeoffReplyCountsWhenTheHeightSaysAirborne) {
  Options o;
  o.takeoff_replies = {""};  // the drone took off but the reply never came
  o.blank_frames = true;
  Harness h(o);
  h.run(1.0);
  // Airborne in the harness only with an "ok": set the height by hand through a state record.
  FlightSoftware& fsw = h.fsw();
  EXPECT_EQ(fsw.phase(), Phase::TakeOff);
  StateRecord s;
  s.t_ns = h.now() + 19 * kNsPerSecond;
  s.height_m = 0.9;
  fsw.step(s);
  s.t_ns += 2 * kNsPerSecond;  // past the 20 s reply timeout
  fsw.step(s);
  EXPECT_EQ(fsw.phase(), Phase::FindShelf);
}

// The `ok` of `land` is lost; the repeated `land` finds the drone on the ground and gets
// `error` (one run in 100 of the default sdk campaign ended "land not
// acknowledged" this way, counted an abort though the drone had crossed and landed). The state
// height says it is down: landed, the mission's outcome kept.
/// A whole mission whose `land` reply goes wrong as `o` says: it crossed, and it ends landed
/// (on the ground, the outcome kept, nothing "not acknowledged").
void expect_crossed_and_landed(Harness& h) {
  h.run(90.0);
  FlightSoftware& fsw = h.fsw();
  ASSERT_TRUE(fsw.finished()) << phase_name(fsw.phase()) << ": " << fsw.telemetry().event;
  EXPECT_EQ(fsw.result().outcome, Outcome::Crossed) << fsw.result().reason;
  EXPECT_TRUE(fsw.result().landed);
  EXPECT_EQ(fsw.result().reason.find("not acknowledged"), std::string::npos) << fsw.result().reason;
  EXPECT_DOUBLE_EQ(h.position().z(), 0.0);
}

// The `ok` of `land` lost: the first fresh state record on the ground ends the landing, not
// the reply's timeout (land_reply_s, 10 s). The drone here comes down at 1 m/s from about 1 m.
TEST(FlightSoftware, LostLandReplyCountsWhenTheHeightSaysLanded) {
  Options o;
  o.land_reply = "";
  Harness h(o);
  expect_crossed_and_landed(h);
  const std::vector<TimeNs> lands = h.sent("land");
  ASSERT_EQ(lands.size(), 1u);
  EXPECT_LT(ns_to_seconds(h.now() - lands[0]), 2.0);
  EXPECT_EQ(h.fsw().telemetry().event, "landed (no `ok` yet: the state height says on the ground)");
}

// A duplicated `land`: the drone lands,
// but the reply heard is the duplicate's `error`. Retrying at once spent the three retries in
// 0.4 s, each refused by the landing drone, and the flight software ended "land not
// acknowledged" in the air (tello_pilot's failsafe took over; the run counted an abort). The
// refusal is waited out by the state height: landed, the crossing's outcome kept, and `land`
// asked again no faster than every 0.5 s meanwhile.
TEST(FlightSoftware, LandRefusedWhileLandingWaitsForTheStateHeight) {
  Options o;
  o.land_duplicated = true;
  Harness h(o);
  expect_crossed_and_landed(h);
  const std::vector<TimeNs> lands = h.sent("land");
  ASSERT_GE(lands.size(), 1u);
  for (size_t i = 1; i < lands.size(); ++i) EXPECT_GE(lands[i] - lands[i - 1], 500 * kMs);
}

TEST(FlightSoftware, LowBatteryBeforeTakeoffStaysOnTheGround) {
  Options o;
  o.battery = [](TimeNs) { return 20; };
  Harness h(o);
  h.run(5.0);
  ASSERT_TRUE(h.fsw().finished());
  EXPECT_EQ(h.non_rc(), (std::vector<std::string>{"command", "streamon"}));
  EXPECT_EQ(h.fsw().result().outcome, Outcome::Aborted);
}

}  // namespace
}  // namespace shelfcross::flight_sw
