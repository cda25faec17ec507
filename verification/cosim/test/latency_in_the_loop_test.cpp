// Latency in the loop: the co-simulation's compute latency defaults to the measured
// median step time, the dispersion compute_latency_quantile draws it from the measured
// distribution, and the latency-sweep scenario loads.

#include <gtest/gtest.h>

#include "verification/scenario/dispersion.hpp"
#include "verification/scenario/scenario.hpp"

namespace shelfcross::verification {
namespace {

TEST(MeasuredStepLatency, InverseCdfThroughTheMeasuredQuantiles) {
  EXPECT_EQ(CosimSettings{}.link.compute_latency_s, kMeasuredStepLatencyP50_s);
  EXPECT_DOUBLE_EQ(measured_step_latency_s(0.5), kMeasuredStepLatencyP50_s);
  EXPECT_DOUBLE_EQ(measured_step_latency_s(0.0), kMeasuredStepLatency.front().seconds);
  EXPECT_DOUBLE_EQ(measured_step_latency_s(1.0), kMeasuredStepLatency.back().seconds);
  EXPECT_DOUBLE_EQ(measured_step_latency_s(-3.0), kMeasuredStepLatency.front().seconds);
  // Linear between quantiles, increasing throughout.
  const StepLatencyQuantile& a = kMeasuredStepLatency[3];
  const StepLatencyQuantile& b = kMeasuredStepLatency[4];
  EXPECT_DOUBLE_EQ(measured_step_latency_s(0.5 * (a.probability + b.probability)), 0.5 * (a.seconds + b.seconds));
  for (int i = 1; i <= 100; ++i) EXPECT_GE(measured_step_latency_s(0.01 * i), measured_step_latency_s(0.01 * (i - 1)));
  // A default scenario (no compute_latency_s key) runs at the measured median.
  const Scenario s = load_scenario(SHELFCROSS_SOURCE_DIR "/scenarios/paper_test_shelf.yaml");
  EXPECT_EQ(s.cosim.link.compute_latency_s, kMeasuredStepLatencyP50_s);
}

TEST(MeasuredStepLatency, QuantileDispersionDrawsFromTheMeasuredDistribution) {
  const Scenario sweep = load_scenario(SHELFCROSS_SOURCE_DIR "/scenarios/latency_sweep.yaml");
  ASSERT_TRUE(sweep.dispersions.count("compute_latency_quantile"));
  ASSERT_TRUE(sweep.dispersions.count("video_latency_mean_s"));
  double lowest = 1.0, highest = 0.0, video_lowest = 1.0, video_highest = 0.0;
  for (std::uint64_t seed = 1; seed <= 200; ++seed) {
    const RunSetup setup = disperse(sweep, seed);
    const double q = setup.drawn.at("compute_latency_quantile");
    const LinkSettings& link = setup.scenario->cosim.link;
    EXPECT_DOUBLE_EQ(link.compute_latency_s, measured_step_latency_s(q));
    lowest = std::min(lowest, link.compute_latency_s);
    highest = std::max(highest, link.compute_latency_s);
    video_lowest = std::min(video_lowest, link.video_latency_mean_s);
    video_highest = std::max(video_highest, link.video_latency_mean_s);
  }
  // Over 200 runs the draws span most of the measured range and the 0-600 ms sweep.
  EXPECT_LT(lowest, measured_step_latency_s(0.05));
  EXPECT_GT(highest, measured_step_latency_s(0.95));
  EXPECT_LT(video_lowest, 0.02);
  EXPECT_GT(video_highest, 0.58);
  EXPECT_LE(video_highest, 0.6);
}

}  // namespace
}  // namespace shelfcross::verification
