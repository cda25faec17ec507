// The SDK command parser: verbs, arguments, the SDK's ranges and the real reply strings.

#include <gtest/gtest.h>

#include "plant/sdk_command.hpp"

namespace shelfcross::plant::sdk {
namespace {

Command ok(std::string_view text) {
  const auto r = parse(text);
  EXPECT_TRUE(std::holds_alternative<Command>(r)) << text;
  return std::holds_alternative<Command>(r) ? std::get<Command>(r) : Command{};
}

ParseError bad(std::string_view text) {
  const auto r = parse(text);
  EXPECT_TRUE(std::holds_alternative<ParseError>(r)) << text;
  return std::holds_alternative<ParseError>(r) ? std::get<ParseError>(r) : ParseError{};
}

TEST(SdkCommand, ParsesControlCommands) {
  for (auto [text, verb] : {std::pair{"command", Verb::command}, {"takeoff", Verb::takeoff}, {"land", Verb::land},
                            {"emergency", Verb::emergency}, {"stop", Verb::stop}, {"streamon", Verb::streamon},
                            {"streamoff", Verb::streamoff}}) {
    EXPECT_EQ(ok(text).verb, verb);
    EXPECT_EQ(ok(text).arg_count, 0);
    EXPECT_EQ(to_text(ok(text)), text);
  }
  EXPECT_EQ(ok("  takeoff\r\n").verb, Verb::takeoff);  // replies and commands may carry \r\n
}

TEST(SdkCommand, RcTakesFourIntegersInRange) {
  const Command c = ok("rc -100 50 0 100");
  EXPECT_EQ(c.verb, Verb::rc);
  EXPECT_EQ(c.arg_count, 4);
  EXPECT_EQ(c.args[0], -100);
  EXPECT_EQ(c.args[1], 50);
  EXPECT_EQ(c.args[3], 100);
  EXPECT_EQ(to_text(c), "rc -100 50 0 100");
  EXPECT_EQ(bad("rc 0 101 0 0").reply, "out of range");
  EXPECT_EQ(bad("rc 0 0 0").reply, "error");
  EXPECT_EQ(bad("rc 0 0 0 0 0").reply, "error");
  EXPECT_EQ(bad("rc 0 0.5 0 0").reply, "error");
  EXPECT_EQ(bad("rc 0 x 0 0").kind, ParseError::Kind::malformed);
}

TEST(SdkCommand, MovesTurnsAndSpeedHaveTheSdkRanges) {
  EXPECT_EQ(ok("forward 20").args[0], 20);
  EXPECT_EQ(ok("up 500").args[0], 500);
  EXPECT_EQ(bad("forward 19").reply, "out of range");  // the classic: moves under 20 cm
  EXPECT_EQ(bad("back 501").reply, "out of range");
  EXPECT_EQ(ok("cw 1").verb, Verb::cw);
  EXPECT_EQ(ok("ccw 360").args[0], 360);
  EXPECT_EQ(bad("cw 0").reply, "out of range");
  EXPECT_EQ(bad("ccw 361").reply, "out of range");
  EXPECT_EQ(ok("speed 10").args[0], 10);
  EXPECT_EQ(bad("speed 101").reply, "out of range");
  EXPECT_EQ(bad("speed 9").reply, "out of range");
  EXPECT_EQ(bad("forward").reply, "error");
  EXPECT_EQ(bad("left 30 40").reply, "error");
}

TEST(SdkCommand, GoCurveAndFlip) {
  EXPECT_EQ(ok("go 100 -50 30 60").arg_count, 4);
  EXPECT_EQ(bad("go 10 -20 20 60").reply, "out of range");  // all within -20..20
  EXPECT_EQ(bad("go 100 0 0 5").reply, "out of range");
  EXPECT_EQ(bad("go 501 0 0 50").reply, "out of range");
  EXPECT_EQ(ok("curve 100 100 0 200 0 0 30").arg_count, 7);  // radius 1 m
  EXPECT_EQ(bad("curve 100 0 0 200 0 0 30").reply, "out of range");  // collinear
  EXPECT_EQ(bad("curve 100 100 0 200 0 0 61").reply, "out of range");
  EXPECT_EQ(bad("curve 20 20 0 40 0 0 30").reply, "out of range");  // radius 0.2 m
  EXPECT_EQ(ok("flip l").flip_direction, 'l');
  EXPECT_EQ(to_text(ok("flip b")), "flip b");
  EXPECT_EQ(bad("flip x").reply, "out of range");
}

TEST(SdkCommand, ReadCommands) {
  for (auto [text, verb] : {std::pair{"battery?", Verb::battery_q}, {"height?", Verb::height_q}, {"tof?", Verb::tof_q},
                            {"sdk?", Verb::sdk_q}, {"time?", Verb::time_q}, {"speed?", Verb::speed_q},
                            {"attitude?", Verb::attitude_q}, {"sn?", Verb::sn_q}}) {
    const Command c = ok(text);
    EXPECT_EQ(c.verb, verb);
    EXPECT_TRUE(is_read(c.verb));
    EXPECT_FALSE(is_manoeuvre(c.verb));
  }
  EXPECT_EQ(bad("battery? 3").reply, "error");
  EXPECT_TRUE(is_manoeuvre(Verb::takeoff));
  EXPECT_FALSE(is_manoeuvre(Verb::rc));
}

TEST(SdkCommand, UnknownCommandsGetTheRealReply) {
  EXPECT_EQ(bad("hover").reply, "unknown command: hover");
  EXPECT_EQ(bad("TAKEOFF").reply, "unknown command: TAKEOFF");
  EXPECT_EQ(bad("fly 3 4").reply, "unknown command: fly 3 4");
  EXPECT_EQ(bad("hover").kind, ParseError::Kind::unknown_command);
  EXPECT_EQ(bad("").kind, ParseError::Kind::malformed);
  EXPECT_FALSE(bad("hover").reason.empty());
}

}  // namespace
}  // namespace shelfcross::plant::sdk
