// The command phases alone (command_phases.hpp): the SDK's replies, their loss and the state
// height in, the transition each step decides out, with no FlightSoftware around them.
#include <gtest/gtest.h>

#include <optional>
#include <string>
#include <vector>

#include "flight_sw/config.hpp"
#include "flight_sw/mission/command_phases.hpp"
#include "flight_sw/mission/facts.hpp"
#include "shelfcross/time.hpp"

namespace shelfcross::flight_sw {
namespace {

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

}  // namespace
}  // namespace shelfcross::flight_sw
