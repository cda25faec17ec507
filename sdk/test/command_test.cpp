// The SDK's one command grammar: the firmware's parser (verbs, arguments, the SDK's ranges and
// the real reply strings) and the driver's check of what it sends (classify_command: the
// same parser, in canonical form), and that the two sides agree.

#include <gtest/gtest.h>

#include "sdk/command.hpp"

namespace shelfcross::sdk {
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

TEST(SdkCommandParse, ParsesControlCommands) {
  for (auto [text, verb] : {std::pair{"command", Verb::command}, {"takeoff", Verb::takeoff}, {"land", Verb::land},
                            {"emergency", Verb::emergency}, {"stop", Verb::stop}, {"streamon", Verb::streamon},
                            {"streamoff", Verb::streamoff}}) {
    EXPECT_EQ(ok(text).verb, verb);
    EXPECT_EQ(ok(text).arg_count, 0);
    EXPECT_EQ(to_text(ok(text)), text);
  }
  EXPECT_EQ(ok("  takeoff\r\n").verb, Verb::takeoff);  // replies and commands may carry \r\n
}

TEST(SdkCommandParse, RcTakesFourIntegersInRange) {
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

TEST(SdkCommandParse, MovesTurnsAndSpeedHaveTheSdkRanges) {
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

TEST(SdkCommandParse, GoCurveAndFlip) {
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

TEST(SdkCommandParse, ReadCommands) {
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

TEST(SdkCommandParse, UnknownCommandsGetTheRealReply) {
  EXPECT_EQ(bad("hover").reply, "unknown command: hover");
  EXPECT_EQ(bad("TAKEOFF").reply, "unknown command: TAKEOFF");
  EXPECT_EQ(bad("fly 3 4").reply, "unknown command: fly 3 4");
  EXPECT_EQ(bad("hover").kind, ParseError::Kind::unknown_command);
  EXPECT_EQ(bad("").kind, ParseError::Kind::malformed);
  EXPECT_FALSE(bad("hover").reason.empty());
}

TEST(SdkCommandClassify, AcceptsEveryCommandOfTheTableInRange) {
  EXPECT_EQ(classify_command("command"), CommandKind::Control);
  EXPECT_EQ(classify_command("streamon"), CommandKind::Control);
  EXPECT_EQ(classify_command("streamoff"), CommandKind::Control);
  EXPECT_EQ(classify_command("battery?"), CommandKind::Read);
  EXPECT_EQ(classify_command("sn?"), CommandKind::Read);
  EXPECT_EQ(classify_command("acceleration?"), CommandKind::Read);  // the firmware answers it too
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

TEST(SdkCommandClassify, AnRcDatagramIsKnownByItsVerbEvenWhenItsArgumentsDoNotParse) {
  for (const char* c : {"rc", "rc 0 0 0 0", "rc -100 100 -100 100", "rc 101 0 0 0", "rc 0 0 0", "rc x"}) {
    EXPECT_TRUE(is_rc_text(c)) << c;
  }
  for (const char* c : {"", "r", "rcx 0 0 0 0", "rc0 0 0 0", " rc 0 0 0 0", "command", "speed 10"}) {
    EXPECT_FALSE(is_rc_text(c)) << c;
  }
}

TEST(SdkCommandClassify, RefusesOutOfRangeAndMalformedCommands) {
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

TEST(SdkCommandClassify, ReplyTimeoutsFollowTheProtocol) {
  const ReplyTimeouts t;
  EXPECT_EQ(t.timeout_for("takeoff"), 20 * kNsPerSecond);
  EXPECT_EQ(t.timeout_for("command"), 7 * kNsPerSecond);
  EXPECT_EQ(t.timeout_for("battery?"), 7 * kNsPerSecond);
  EXPECT_EQ(t.timeout_for("land"), 10 * kNsPerSecond);
}


// Every verb the grammar knows, with arguments in range, in canonical form.
const char* const kCanonicalTexts[] = {
    "command", "takeoff", "land", "emergency", "stop", "streamon", "streamoff",
    "up 20", "down 500", "left 20", "right 33", "forward 500", "back 20", "cw 1", "ccw 360",
    "flip l", "flip r", "flip f", "flip b", "go 21 0 0 10", "go -500 500 -500 100",
    "curve 100 100 0 200 0 0 60", "speed 10", "speed 100", "rc 0 0 0 0", "rc -100 100 -100 100",
    "speed?", "battery?", "time?", "height?", "temp?", "attitude?", "baro?", "tof?", "wifi?",
    "sdk?", "sn?", "acceleration?"};

TEST(SdkCommandAgreement, EveryVerbHasACanonicalTextBothSidesAccept) {
  // Each verb of the grammar appears in kCanonicalTexts, so the two lists cannot drift.
  for (int v = 0; v <= static_cast<int>(Verb::acceleration_q); ++v) {
    const std::string_view verb = verb_text(static_cast<Verb>(v));
    bool found = false;
    for (const char* text : kCanonicalTexts) {
      const std::string_view t(text);
      found = found || t == verb || t.starts_with(std::string(verb) + " ");
    }
    EXPECT_TRUE(found) << verb;
  }
}

TEST(SdkCommandAgreement, WhatTheDriverMaySendTheFirmwareAccepts) {
  // The driver sends only texts classify_command accepts; the firmware must parse each of them
  // to the same command, and its canonical text is the text sent.
  for (const char* text : kCanonicalTexts) {
    std::string why;
    const auto kind = classify_command(text, &why);
    ASSERT_TRUE(kind) << text << ": " << why;
    const auto parsed = parse(text);
    ASSERT_TRUE(std::holds_alternative<Command>(parsed)) << text;
    EXPECT_EQ(to_text(std::get<Command>(parsed)), text);
    EXPECT_EQ(*kind, kind_of(std::get<Command>(parsed).verb)) << text;
    EXPECT_EQ(*kind == CommandKind::Read, is_read(std::get<Command>(parsed).verb)) << text;
  }
  // rc_text makes canonical rc texts.
  for (int a : {-100, -1, 0, 7, 100}) {
    const std::string text = rc_text(a, -a, 0, a);
    EXPECT_EQ(classify_command(text), CommandKind::Rc) << text;
    EXPECT_TRUE(std::holds_alternative<Command>(parse(text))) << text;
  }
}

TEST(SdkCommandAgreement, WhatTheFirmwareAcceptsInCanonicalFormTheDriverMaySend) {
  // The other way round: every text the firmware parses whose canonical form it is, the
  // driver accepts; a text the firmware parses in another form (what a lenient client may
  // send: '+', leading zeros, extra spaces, a line end) the driver refuses, and its canonical
  // form it accepts. A text the firmware refuses, the driver refuses too.
  const char* const kFirmwareOnly[] = {"  takeoff\r\n", "rc +1 0 0 0", "rc 01 0 0 0", "rc -0 0 0 0",
                                       "rc  0 0 0 0", "rc 0 0 0 0 ", " takeoff", "takeoff\n",
                                       "rc 0 0 0 0\r\n", "acceleration?\r\n", "forward\t50"};
  for (const char* text : kFirmwareOnly) {
    const auto parsed = parse(text);
    ASSERT_TRUE(std::holds_alternative<Command>(parsed)) << text;
    std::string why;
    EXPECT_FALSE(classify_command(text, &why)) << text;
    EXPECT_FALSE(why.empty()) << text;
    const std::string canonical = to_text(std::get<Command>(parsed));
    EXPECT_TRUE(classify_command(canonical)) << canonical;
  }
  const char* const kRefusedByBoth[] = {"", "fly", "TAKEOFF", "forward 19", "rc 101 0 0 0", "rc 0 0 0",
                                        "go 10 10 10 50", "curve 100 0 0 200 0 0 30", "flip x",
                                        "battery? 3", "rc 99999999 0 0 0", "rc 99999999999 0 0 0"};
  for (const char* text : kRefusedByBoth) {
    EXPECT_TRUE(std::holds_alternative<ParseError>(parse(text))) << text;
    EXPECT_FALSE(classify_command(text)) << text;
  }
  // The driver's reason is the firmware's.
  std::string why;
  EXPECT_FALSE(classify_command("forward 19", &why));
  EXPECT_EQ(why, std::get<ParseError>(parse("forward 19")).reason);
}

}  // namespace
}  // namespace shelfcross::sdk
