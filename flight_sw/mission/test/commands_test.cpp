// The mission's non-rc commands (MissionCommands) over the SDK's command rules: the newest
// command asked for goes out after the gap, completes by its reply or its timeout, stale
// replies are counted; retries while they remain; a re-ask at a later time.
#include "flight_sw/mission/commands.hpp"

#include <gtest/gtest.h>

namespace shelfcross::flight_sw {
namespace {


Timeouts timeouts(int retries) {
  Timeouts t;
  t.command_gap_s = 0.1;
  t.command_retries = retries;
  return t;
}

TEST(MissionCommands, SendsTheNewestAskAfterTheGapAndCompletesItByReplyOrTimeout) {
  MissionCommands commands(timeouts(3));
  std::vector<SdkCommand> out;
  commands.ask("command", 1.0);
  commands.ask("streamon", 1.0);  // replaces the one waiting
  commands.poll(0, out);
  ASSERT_EQ(out.size(), 1u);
  EXPECT_EQ(out[0].text, "streamon");
  EXPECT_TRUE(commands.outstanding());
  const auto replied = commands.on_reply({10, " OK\r\n"});
  ASSERT_TRUE(replied);
  EXPECT_EQ(replied->command, "streamon");
  EXPECT_TRUE(replied->ok);
  EXPECT_FALSE(replied->timed_out);
  EXPECT_FALSE(commands.on_reply({20, "ok"}));  // nothing outstanding: stale
  EXPECT_EQ(commands.stale_replies(), 1);
  commands.ask("takeoff", 0.5);
  commands.poll(50 * kMs, out);  // inside the gap
  EXPECT_EQ(out.size(), 1u);
  commands.poll(100 * kMs, out);
  ASSERT_EQ(out.size(), 2u);
  EXPECT_EQ(out[1].t_ns, 100 * kMs);
  commands.poll(700 * kMs, out);  // outstanding: nothing more goes
  EXPECT_EQ(out.size(), 2u);
  EXPECT_FALSE(commands.check_timeout(599 * kMs));
  const auto c = commands.check_timeout(600 * kMs);
  ASSERT_TRUE(c);
  EXPECT_TRUE(c->timed_out);
  EXPECT_FALSE(c->ok);
  EXPECT_EQ(c->reply, "");
  EXPECT_EQ(c->command, "takeoff");
  EXPECT_FALSE(commands.outstanding());
  EXPECT_FALSE(commands.check_timeout(700 * kMs));
}

TEST(MissionCommands, RetriesWhileRetriesRemainAndANewAskStartsTheCountAgain) {
  MissionCommands commands(timeouts(1));
  std::vector<SdkCommand> out;
  commands.ask("command", 1.0);
  commands.poll(0, out);
  const auto refused = commands.on_reply({10, "error"});
  ASSERT_TRUE(refused);
  EXPECT_FALSE(refused->ok);
  EXPECT_TRUE(commands.retry(refused->command, 1.0));
  EXPECT_EQ(commands.attempts(), 1);
  commands.poll(100 * kMs, out);
  ASSERT_EQ(out.size(), 2u);
  EXPECT_EQ(out[1].text, "command");
  ASSERT_TRUE(commands.on_reply({110 * kMs, "error"}));
  EXPECT_FALSE(commands.retry("command", 1.0));  // retries spent: nothing asked
  commands.poll(300 * kMs, out);
  EXPECT_EQ(out.size(), 2u);
  commands.ask("streamon", 1.0);
  EXPECT_EQ(commands.attempts(), 0);
}

TEST(MissionCommands, AReAskGoesAtItsTimeUnlessDroppedOrReplacedByANewAsk) {
  MissionCommands commands(timeouts(3));
  std::vector<SdkCommand> out;
  commands.ask_again_at("land", 10.0, 2000 * kMs);
  EXPECT_TRUE(commands.waiting());
  commands.poll(1999 * kMs, out);
  EXPECT_TRUE(out.empty());
  commands.poll(2000 * kMs, out);
  ASSERT_EQ(out.size(), 1u);
  EXPECT_EQ(out[0].text, "land");
  EXPECT_FALSE(commands.waiting());
  EXPECT_FALSE(commands.check_timeout(11'999 * kMs));
  EXPECT_TRUE(commands.check_timeout(12'000 * kMs));  // its own reply timeout

  commands.ask_again_at("land", 10.0, 20'000 * kMs);
  commands.cancel_wait();
  EXPECT_FALSE(commands.waiting());
  commands.ask_again_at("land", 10.0, 20'000 * kMs);
  commands.ask("command", 1.0);  // drops the re-ask
  EXPECT_FALSE(commands.waiting());
  commands.poll(30'000 * kMs, out);
  ASSERT_EQ(out.size(), 2u);
  EXPECT_EQ(out[1].text, "command");
}

}  // namespace
}  // namespace shelfcross::flight_sw
