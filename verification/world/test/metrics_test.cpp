#include "verification/world/metrics.hpp"

#include <cmath>

#include <gtest/gtest.h>

#include "shelfcross/rotation.hpp"

namespace shelfcross::verification {
namespace {

TEST(Metrics, SettlingTimeOfAFirstOrderResponseIsFourTimeConstants) {
  // e(t) = e0 exp(-t / tau): |e| <= 2 % e0 from t = tau ln 50 = 3.912 tau on.
  const double tau = 0.5, e0 = 0.4, dt = 1e-3;
  std::vector<double> t, e;
  for (int i = 0; i <= 5000; ++i) {
    t.push_back(10.0 + i * dt);
    e.push_back(e0 * std::exp(-i * dt / tau));
  }
  const StepResponse r = analyse_step_response(t, e, {.fraction = 0.02, .floor = 0.001});
  ASSERT_TRUE(r.settling_time_s);
  EXPECT_NEAR(*r.settling_time_s, tau * std::log(50.0), 2 * dt);
  EXPECT_DOUBLE_EQ(r.band, 0.02 * e0);
  EXPECT_EQ(r.overshoot, 0.0);
  EXPECT_EQ(r.overshoot_abs, 0.0);
}

TEST(Metrics, FloorOfTheBandAndOvershootOfAnUnderdampedResponse) {
  // Underdamped: e = e0 exp(-z w t) cos(w_d t); first overshoot exp(-pi z / sqrt(1 - z^2)).
  const double z = 0.3, w = 4.0, wd = w * std::sqrt(1 - z * z), e0 = -0.2;
  std::vector<double> t, e;
  for (int i = 0; i <= 20000; ++i) {
    const double ti = i * 1e-3;
    t.push_back(ti);
    e.push_back(e0 * std::exp(-z * w * ti) * (std::cos(wd * ti) + z / std::sqrt(1 - z * z) * std::sin(wd * ti)));
  }
  const StepResponse r = analyse_step_response(t, e, {.fraction = 0.02, .floor = 0.01});
  EXPECT_DOUBLE_EQ(r.band, 0.01);  // 2 % of 0.2 m is 4 mm: the 1 cm floor applies
  ASSERT_TRUE(r.overshoot.has_value());
  EXPECT_NEAR(*r.overshoot, std::exp(-M_PI * z / std::sqrt(1 - z * z)), 1e-3);
  EXPECT_NEAR(r.overshoot_abs, *r.overshoot * std::abs(r.initial_error), 1e-12);
  ASSERT_TRUE(r.settling_time_s);
  // Inside 1 cm for good once the envelope e0 exp(-z w t) / sqrt(1 - z^2) is below it (bound).
  EXPECT_LT(*r.settling_time_s, std::log(0.2 / 0.01 / std::sqrt(1 - z * z)) / (z * w) + 1e-3);
}

TEST(Metrics, NoOvershootRatioWithoutAStepOnlyTheExcursion) {
  // Heading during an approach: starts on the normal (inside the band), swings to -5 deg while
  // the vehicle turns toward its cell, comes back. No step, so no ratio; the excursion is kept.
  const double band_rad = deg_to_rad(0.5);
  std::vector<double> t, e;
  for (int i = 0; i <= 100; ++i) {
    t.push_back(0.1 * i);
    e.push_back(0.001 - 0.0873 * std::sin(M_PI * i / 100.0));
  }
  const StepResponse r = analyse_step_response(t, e, {.fraction = 0.02, .floor = band_rad});
  EXPECT_FALSE(r.overshoot.has_value());
  EXPECT_NEAR(r.overshoot_abs, 0.0873 - 0.001, 1e-4);
  EXPECT_NEAR(r.peak_abs_error, 0.0873 - 0.001, 1e-4);
}

TEST(Metrics, NeverSettledWhenTheLastSampleIsOutside) {
  const StepResponse r = analyse_step_response({0, 1, 2}, {1.0, 0.0, 0.5}, {.fraction = 0.02, .floor = 0.01});
  EXPECT_FALSE(r.settling_time_s);
  EXPECT_DOUBLE_EQ(r.peak_abs_error, 1.0);
}

TEST(Metrics, PathLengthAndInventoryScore) {
  EXPECT_DOUBLE_EQ(path_length_m({{0, 0, 0}, {3, 4, 0}, {3, 4, 2}}), 7.0);
  const std::set<InventoryEntry> truth{{1, 0, 1, 1}, {2, 0, 2, 3}, {3, 0, 4, 4}};
  const InventoryScore s = score_inventory({{1, 0, 1, 1}, {2, 0, 2, 4}}, truth);
  EXPECT_DOUBLE_EQ(s.precision, 0.5);
  EXPECT_DOUBLE_EQ(s.recall, 1.0 / 3.0);
  EXPECT_FALSE(s.exact());
  EXPECT_TRUE(score_inventory(truth, truth).exact());
}

}  // namespace
}  // namespace shelfcross::verification
