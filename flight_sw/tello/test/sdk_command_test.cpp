#include "flight_sw/tello/sdk_command.hpp"

#include <gtest/gtest.h>

namespace shelfcross::tello {
namespace {

TEST(SdkCommand, AcceptsEveryCommandOfTheTableInRange) {
  EXPECT_EQ(classify_command("command"), CommandKind::Control);
  EXPECT_EQ(classify_command("streamon"), CommandKind::Control);
  EXPECT_EQ(classify_command("streamoff"), CommandKind::Control);
  EXPECT_EQ(classify_command("battery?"), CommandKind::Read);
  EXPECT_EQ(classify_command("sn?"), CommandKind::Read);
  for (const char* c : {"takeoff", "land", "emergency", "stop", "up 20", "down 500", "left 20",
                        "right 33", "forward 500", "back 20", "cw 1", "ccw 360", "flip l",
                        "flip b", "speed 10", "speed 100", "go 21 0 0 10", "go -500 500 -500 100",
                        "curve 100 100 0 200 0 0 60"}) {
    EXPECT_EQ(classify_command(c), CommandKind::Motion) << c;
  }
  EXPECT_EQ(classify_command("rc 0 0 0 0"), CommandKind::Rc);
  EXPECT_EQ(classify_command("rc -100 100 -100 100"), CommandKind::Rc);
  EXPECT_EQ(rc_text(-5, 0, 100, -100), "rc -5 0 100 -100");
}

TEST(SdkCommand, RefusesOutOfRangeAndMalformedCommands) {
  for (const char* c : {"", "rc 101 0 0 0", "rc 0 0 0 -101", "rc 1.5 0 0 0", "rc 0 0 0", "rc 0 0 0 0 0",
                        "rc +1 0 0 0", "rc 01 0 0 0", "rc -0 0 0 0", "rc  0 0 0 0", "rc 0 0 0 0 ",
                        " takeoff", "takeoff now", "forward 19", "forward 501", "up", "cw 0",
                        "ccw 361", "flip x", "speed 9", "speed 101", "go 10 10 10 50",
                        "go 100 0 0 9", "go 501 0 0 50", "curve 10 0 0 20 0 0 30",
                        "curve 100 100 0 200 0 0 61", "curve 20 20 0 40 0 0 30", "fly",
                        "takeoff\n", "rc 0 0 0 0\r\n", "rc 99999999 0 0 0"}) {
    std::string why;
    EXPECT_FALSE(classify_command(c, &why)) << "'" << c << "'";
    EXPECT_FALSE(why.empty()) << c;
  }
}

TEST(SdkCommand, ReplyTimeoutsFollowTheProtocol) {
  const ReplyTimeouts t;
  EXPECT_EQ(t.timeout_for("takeoff"), 20 * kNsPerSecond);
  EXPECT_EQ(t.timeout_for("command"), 7 * kNsPerSecond);
  EXPECT_EQ(t.timeout_for("battery?"), 7 * kNsPerSecond);
}

}  // namespace
}  // namespace shelfcross::tello
