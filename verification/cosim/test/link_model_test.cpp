#include "verification/cosim/link_model.hpp"

#include <gtest/gtest.h>

namespace shelfcross::verification {
namespace {

TEST(LinkModel, SameSeedSameDeliveriesAndOrderIsKept) {
  LinkSettings s;
  s.video_latency_jitter_s = 0.05;  // large jitter relative to the 33 ms frame spacing
  LinkModel a(s, 77), b(s, 77);
  TimeNs last = 0;
  int dropped = 0;
  for (int k = 0; k < 3000; ++k) {
    const TimeNs capture = tick_time_ns(k, 30);
    const auto ta = a.video_arrival(capture);
    EXPECT_EQ(ta, b.video_arrival(capture));
    if (!ta) {
      ++dropped;
      continue;
    }
    EXPECT_GE(*ta, last);
    EXPECT_GE(*ta, capture);
    last = *ta;
  }
  EXPECT_NEAR(dropped / 3000.0, s.frame_drop_probability, 0.01);
}

TEST(LinkModel, LatencyMeanComputeTimeAndLosses) {
  LinkSettings s;
  s.command_loss_probability = 0.1;
  s.compute_latency_s = 0.004;
  LinkModel link(s, 3);
  double sum_s = 0.0;
  int delivered = 0;
  for (int k = 0; k < 20000; ++k) {
    const TimeNs t = tick_time_ns(k, 10);  // 100 ms apart: ordering never binds
    if (const auto arrival = link.command_arrival(t)) {
      sum_s += ns_to_seconds(*arrival - t);
      ++delivered;
    }
  }
  EXPECT_NEAR(delivered / 20000.0, 0.9, 0.01);
  EXPECT_NEAR(sum_s / delivered, s.compute_latency_s + s.command_latency_mean_s, 2e-4);
}

TEST(LinkModel, ChangingOneSettingDoesNotShiftTheOtherStreams) {
  LinkSettings s1, s2;
  s2.frame_drop_probability = 0.5;
  LinkModel a(s1, 9), b(s2, 9);
  for (int k = 0; k < 100; ++k) {
    const TimeNs t = tick_time_ns(k, 10);
    EXPECT_EQ(a.command_arrival(t), b.command_arrival(t));
    EXPECT_EQ(a.state_arrival(t), b.state_arrival(t));
    a.video_arrival(t);
    b.video_arrival(t);
  }
}

}  // namespace
}  // namespace shelfcross::verification
