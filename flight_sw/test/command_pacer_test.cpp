// The SDK's command rules (CommandPacer) and the flight software's link that keeps them
// (SdkLink): one command outstanding, the gap between sends, the reply timeout.
#include "flight_sw/command_pacer.hpp"

#include <gtest/gtest.h>

#include "flight_sw/sdk_link.hpp"

namespace shelfcross::flight_sw {
namespace {

constexpr TimeNs kMsNs = 1'000'000;

TEST(CommandPacer, OneOutstandingAGapBetweenSendsAndATimeoutPerCommand) {
  CommandPacer<std::string> pacer(100 * kMsNs);
  EXPECT_TRUE(pacer.may_send(0));
  pacer.send(0, "command", 500 * kMsNs);
  EXPECT_FALSE(pacer.may_send(200 * kMsNs));  // outstanding
  EXPECT_FALSE(pacer.overdue(499 * kMsNs));
  EXPECT_TRUE(pacer.overdue(500 * kMsNs));
  pacer.resent(500 * kMsNs);  // the timeout starts anew
  EXPECT_FALSE(pacer.overdue(999 * kMsNs));
  EXPECT_EQ(*pacer.complete(), "command");
  EXPECT_EQ(pacer.outstanding(), nullptr);
  EXPECT_FALSE(pacer.complete());
  EXPECT_FALSE(pacer.may_send(599 * kMsNs));  // the gap runs from the re-send
  EXPECT_TRUE(pacer.may_send(600 * kMsNs));
}

TEST(SdkLink, SendsTheNewestRequestAfterTheGapAndCompletesItByReplyOrTimeout) {
  SdkLink link(0.1);
  std::vector<SdkCommand> out;
  link.request("command", 1.0);
  link.request("streamon", 1.0);  // replaces the queued one
  link.poll(0, out);
  ASSERT_EQ(out.size(), 1u);
  EXPECT_EQ(out[0].text, "streamon");
  EXPECT_FALSE(link.on_reply({10, "ok"}) == std::nullopt);
  EXPECT_FALSE(link.on_reply({20, "ok"}));  // nothing outstanding: stale
  EXPECT_EQ(link.stale_replies(), 1);
  link.request("takeoff", 0.5);
  link.poll(50 * kMsNs, out);  // inside the gap
  EXPECT_EQ(out.size(), 1u);
  link.poll(100 * kMsNs, out);
  ASSERT_EQ(out.size(), 2u);
  EXPECT_FALSE(link.check_timeout(599 * kMsNs));
  const auto c = link.check_timeout(600 * kMsNs);
  ASSERT_TRUE(c);
  EXPECT_TRUE(c->timed_out);
  EXPECT_EQ(c->command, "takeoff");
  EXPECT_TRUE(link.idle());
}

TEST(IsOkReply, AnyCaseBlanksAroundIgnored) {
  EXPECT_TRUE(is_ok_reply(" OK\r\n"));
  EXPECT_TRUE(is_ok_reply("oK"));
  EXPECT_FALSE(is_ok_reply("error"));
  EXPECT_FALSE(is_ok_reply("o k"));
}

}  // namespace
}  // namespace shelfcross::flight_sw
