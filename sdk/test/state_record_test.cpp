// The state record parser: the SDK's samples, sign conventions, what is refused.

#include "sdk/state_record.hpp"
#include "shelfcross/rotation.hpp"

#include <cmath>

#include <gtest/gtest.h>

namespace shelfcross::sdk {
namespace {

constexpr double kDeg = deg_to_rad(1.0);  // one degree

// The three real samples of docs/tello_sdk.md.
constexpr const char* kSdk13 =
    "pitch:1;roll:5;yaw:0;vgx:0;vgy:0;vgz:0;templ:43;temph:46;tof:10;h:0;bat:83;baro:150.12;time:0;"
    "agx:15.00;agy:-97.00;agz:-988.00;";
constexpr const char* kSdk20 =
    "mid:257;x:0;y:0;z:0;mpry:0,0,0;pitch:0;roll:0;yaw:-20;vgx:0;vgy:0;vgz:0;templ:60;temph:62;tof:10;h:0;"
    "bat:67;baro:1687.34;time:16;agx:6.00;agy:0.00;agz:-999.00;";
constexpr const char* kSdk20NoPad =
    "mid:-1;x:-100;y:-100;z:-100;mpry:-1,-1,-1;pitch:0;roll:0;yaw:0;vgx:0;vgy:0;vgz:0;templ:55;temph:57;"
    "tof:6553;h:0;bat:5;baro:118.26;time:0;agx:-4.00;agy:1.00;agz:-997.00;";

TEST(SdkState, ParsesTheSdk13Sample) {
  StateParseReport report;
  const auto s = parse_state_record(std::string(kSdk13) + "\r\n", 123, &report);
  ASSERT_TRUE(s);
  EXPECT_EQ(s->t_ns, 123);
  EXPECT_NEAR(s->pitch_rad, -1 * kDeg, 1e-12);  // nose up 1 deg in the drone's convention
  EXPECT_NEAR(s->roll_rad, 5 * kDeg, 1e-12);
  EXPECT_EQ(s->battery_pct, 83);
  ASSERT_TRUE(s->tof_m);
  EXPECT_NEAR(*s->tof_m, 0.10, 1e-12);
  ASSERT_TRUE(s->baro_m);
  EXPECT_NEAR(*s->baro_m, 150.12, 1e-12);
  EXPECT_NEAR(s->az_B_mps2, 0.988 * kStandardGravity_mps2, 1e-9);  // at rest: specific force up
  EXPECT_NEAR(s->ay_B_mps2, 0.097 * kStandardGravity_mps2, 1e-9);
  EXPECT_EQ(report.missing_keys, 0);
  EXPECT_EQ(report.unknown_keys, 0);
  EXPECT_FALSE(report.mission_pad);
}

TEST(SdkState, ParsesSdk20WithMissionPadFieldsAndSentinels) {
  StateParseReport report;
  const auto s = parse_state_record(kSdk20, 0, &report);
  ASSERT_TRUE(s);
  EXPECT_TRUE(report.mission_pad);
  EXPECT_NEAR(s->yaw_rad, 20 * kDeg, 1e-12);  // yaw -20 (counter-clockwise) is +20 deg here
  EXPECT_EQ(s->motor_time_s, 16);
  const auto no_pad = parse_state_record(kSdk20NoPad, 0, &report);
  ASSERT_TRUE(no_pad);
  EXPECT_FALSE(no_pad->tof_m);  // 6553: invalid
  EXPECT_EQ(no_pad->battery_pct, 5);
}

TEST(SdkState, RefusesWhatIsNotAStateRecord) {
  EXPECT_FALSE(parse_state_record("ok", 0));
  EXPECT_FALSE(parse_state_record("ok\r\n", 0));
  EXPECT_FALSE(parse_state_record("", 0));
  EXPECT_FALSE(parse_state_record("pitch:abc;roll:0;", 0));
  EXPECT_FALSE(parse_state_record("pitch:1e999;roll:0;", 0));
  EXPECT_FALSE(parse_state_record("templ:40;temph:41;", 0));  // no core key at all
  EXPECT_FALSE(parse_state_record(std::string("pitch:1;\0roll", 12), 0));
}

TEST(SdkState, ToleratesUnknownAndMissingKeys) {
  StateParseReport report;
  const auto s = parse_state_record("pitch:2;yaw:10;wifi:90;bat:50;;", 0, &report);
  ASSERT_TRUE(s);
  EXPECT_EQ(report.unknown_keys, 1);
  EXPECT_EQ(report.missing_keys, 5);  // roll vgx vgy vgz h
  EXPECT_EQ(s->battery_pct, 50);
  EXPECT_EQ(s->vx_H_mps, 0.0);
}

}  // namespace
}  // namespace shelfcross::sdk
