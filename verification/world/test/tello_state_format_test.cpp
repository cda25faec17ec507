// The simulated Tello's state datagram, read back by the SDK's one parser.

#include "verification/world/tello_state_format.hpp"

#include <cmath>

#include <gtest/gtest.h>

#include "sdk/state_record.hpp"
#include "shelfcross/rotation.hpp"

namespace shelfcross::verification {
namespace {

constexpr double kDeg = deg_to_rad(1.0);  // one degree

TEST(TelloStateFormat, FormatThenParseKeepsTheDronesResolution) {
  StateRecord truth;
  truth.roll_rad = 3.4 * kDeg;
  truth.pitch_rad = -7.6 * kDeg;
  truth.yaw_rad = 123.2 * kDeg;
  truth.vx_H_mps = 0.47;
  truth.vy_H_mps = -0.12;
  truth.vz_H_mps = 0.04;
  truth.height_m = 0.987;
  truth.tof_m = 1.013;
  truth.baro_m = 101.234;
  truth.battery_pct = 77;
  truth.az_B_mps2 = 9.80665;
  const std::string text = format_state_record(truth);
  EXPECT_EQ(text.substr(0, 42), "mid:-1;x:-100;y:-100;z:-100;mpry:-1,-1,-1;");
  EXPECT_EQ(text.substr(text.size() - 2), "\r\n");
  const auto s = sdk::parse_state_record(text, 5);
  ASSERT_TRUE(s);
  EXPECT_NEAR(s->roll_rad, 3 * kDeg, 1e-12);
  EXPECT_NEAR(s->pitch_rad, -8 * kDeg, 1e-12);
  EXPECT_NEAR(s->yaw_rad, 123 * kDeg, 1e-12);
  EXPECT_NEAR(s->vx_H_mps, 0.5, 1e-12);
  EXPECT_NEAR(s->vy_H_mps, -0.1, 1e-12);
  EXPECT_NEAR(s->vz_H_mps, 0.0, 1e-12);
  EXPECT_NEAR(s->height_m, 0.99, 1e-12);
  EXPECT_NEAR(*s->tof_m, 1.01, 1e-12);
  EXPECT_EQ(s->battery_pct, 77);
  EXPECT_NEAR(s->az_B_mps2, 9.80665, 1e-9);
}

}  // namespace
}  // namespace shelfcross::verification
