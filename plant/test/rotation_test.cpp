// The facts stated once in include/shelfcross/ (rotation.hpp, time.hpp), on their hard cases:
// angles at and past +-pi, rotations near gimbal lock, non-integer clock rates.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include <Eigen/Geometry>

#include "plant/dynamics.hpp"
#include "shelfcross/rotation.hpp"
#include "shelfcross/time.hpp"

namespace shelfcross {
namespace {

constexpr double kPi = std::numbers::pi;

TEST(WrapPi, KeepsAnglesInsideAndWrapsTheRestExactly) {
  EXPECT_EQ(wrap_pi(0.0), 0.0);
  EXPECT_EQ(wrap_pi(1.0), 1.0);
  EXPECT_EQ(wrap_pi(-1.0), -1.0);
  EXPECT_EQ(wrap_pi(1e-300), 1e-300);
  // The remainder itself is exact; what is left is the rounding of 2 pi + 0.25 (< 1e-15).
  EXPECT_NEAR(wrap_pi(2.0 * kPi + 0.25), 0.25, 1e-15);
  EXPECT_NEAR(wrap_pi(-2.0 * kPi - 0.25), -0.25, 1e-15);
  EXPECT_NEAR(std::abs(wrap_pi(3.0 * kPi)), kPi, 1e-15);  // at the boundary, either end
  for (double a = -20.0; a <= 20.0; a += 0.37) {
    const double w = wrap_pi(a);
    EXPECT_LE(std::abs(w), kPi) << a;
    EXPECT_NEAR(std::sin(w), std::sin(a), 1e-12) << a;
    EXPECT_NEAR(std::cos(w), std::cos(a), 1e-12) << a;
  }
  EXPECT_TRUE(std::isnan(wrap_pi(INFINITY)));
}

TEST(EulerZyx, RecoversTheAnglesThatMadeTheRotation) {
  for (double roll : {-3.0, -1.2, 0.0, 1e-9, 0.7, 3.1}) {
    for (double pitch : {-1.5, -0.4, 0.0, 1e-9, 0.9, 1.5}) {
      for (double yaw : {-kPi + 1e-6, -2.0, 0.0, 0.5, kPi - 1e-6}) {
        const Eigen::Matrix3d R = plant::quaternion_from_euler_zyx(roll, pitch, yaw).toRotationMatrix();
        const Eigen::Vector3d rpy = euler_zyx(R);
        EXPECT_NEAR(rpy.x(), roll, 1e-8) << roll << " " << pitch << " " << yaw;
        EXPECT_NEAR(rpy.y(), pitch, 1e-8) << roll << " " << pitch << " " << yaw;
        EXPECT_NEAR(rpy.z(), yaw, 1e-8) << roll << " " << pitch << " " << yaw;
      }
    }
  }
}

TEST(EulerZyx, GimbalLockAndRoundingGiveFiniteAngles) {
  // Pitch +-pi/2: roll and yaw share one angle; nothing is NaN, pitch is exact.
  for (double pitch : {kPi / 2.0, -kPi / 2.0}) {
    const Eigen::Matrix3d R = plant::quaternion_from_euler_zyx(0.3, pitch, 0.2).toRotationMatrix();
    const Eigen::Vector3d rpy = euler_zyx(R);
    EXPECT_TRUE(rpy.allFinite());
    EXPECT_NEAR(rpy.y(), pitch, 1e-7);
  }
  // A matrix whose R20 rounds just past -1 still gives pitch pi/2, not NaN.
  Eigen::Matrix3d R = Eigen::Matrix3d::Zero();
  R(2, 0) = -1.0 - 1e-15;
  R(0, 2) = 1.0;
  R(1, 1) = 1.0;
  EXPECT_DOUBLE_EQ(euler_zyx(R).y(), kPi / 2.0);
}

TEST(EulerZyx, QuaternionFormIsTheMatrixFormOfTheNormalisedQuaternion) {
  // The plant's quaternion entry point is the same fact: bit for bit on a scaled quaternion.
  const Eigen::Quaterniond q = plant::quaternion_from_euler_zyx(0.1, -0.2, 2.9);
  const Eigen::Quaterniond scaled(2.0 * q.w(), 2.0 * q.x(), 2.0 * q.y(), 2.0 * q.z());
  EXPECT_EQ(plant::euler_zyx_from_quaternion(scaled), euler_zyx(scaled.normalized().toRotationMatrix()));
}

TEST(EventClock, IntegerEventTimesForFractionalRates) {
  EXPECT_EQ(millihertz(500.0), 500'000);
  EXPECT_EQ(millihertz(29.97), 29'970);
  EXPECT_EQ(event_time(0, millihertz(29.97)), 0);
  // 1000 events at 29.97 Hz: floor(1000 * 1e12 / 29970) ns, no drift from summing periods.
  EXPECT_EQ(event_time(1000, millihertz(29.97)), 33'366'700'033);
  // An integer rate agrees with tick_time_ns.
  for (std::int64_t k : {1, 7, 500, 123'456}) EXPECT_EQ(event_time(k, millihertz(500.0)), tick_time_ns(k, 500));
  // Event times never decrease and their gaps differ by at most 1 ns.
  const std::int64_t mhz = millihertz(30.0);
  for (std::int64_t k = 1; k < 1000; ++k) {
    const TimeNs gap = event_time(k + 1, mhz) - event_time(k, mhz);
    EXPECT_GE(gap, 33'333'333);
    EXPECT_LE(gap, 33'333'334);
  }
}

}  // namespace
}  // namespace shelfcross
