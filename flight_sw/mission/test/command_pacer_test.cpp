// The SDK's command rules (CommandPacer): one command outstanding, the gap between sends, the
// reply timeout; the reply that accepts a command (is_ok_reply).
#include "flight_sw/mission/command_pacer.hpp"

#include <gtest/gtest.h>

#include <string>

namespace shelfcross::flight_sw {
namespace {


TEST(CommandPacer, OneOutstandingAGapBetweenSendsAndATimeoutPerCommand) {
  CommandPacer<std::string> pacer(100 * kMs);
  EXPECT_TRUE(pacer.may_send(0));
  pacer.send(0, "command", 500 * kMs);
  EXPECT_FALSE(pacer.may_send(200 * kMs));  // outstanding
  EXPECT_FALSE(pacer.overdue(499 * kMs));
  EXPECT_TRUE(pacer.overdue(500 * kMs));
  pacer.resent(500 * kMs);  // the timeout starts anew
  EXPECT_FALSE(pacer.overdue(999 * kMs));
  EXPECT_EQ(*pacer.complete(), "command");
  EXPECT_EQ(pacer.outstanding(), nullptr);
  EXPECT_FALSE(pacer.complete());
  EXPECT_FALSE(pacer.may_send(599 * kMs));  // the gap runs from the re-send
  EXPECT_TRUE(pacer.may_send(600 * kMs));
}

TEST(IsOkReply, AnyCaseBlanksAroundIgnored) {
  EXPECT_TRUE(is_ok_reply(" OK\r\n"));
  EXPECT_TRUE(is_ok_reply("oK"));
  EXPECT_FALSE(is_ok_reply("error"));
  EXPECT_FALSE(is_ok_reply("o k"));
}

}  // namespace
}  // namespace shelfcross::flight_sw
