// The scenario's link keys mapped to the one fault model both links draw.

#include "verification/cosim/link_faults.hpp"

#include <gtest/gtest.h>

namespace shelfcross::verification {
namespace {

TEST(LinkFaults, EveryKeyMapsToItsChannelInMilliseconds) {
  LinkSettings l;
  l.video_latency_mean_s = 0.25;
  l.video_latency_jitter_s = 0.03;
  l.frame_drop_probability = 0.04;
  l.state_latency_mean_s = 0.015;
  l.state_latency_jitter_s = 0.004;
  l.command_latency_mean_s = 0.03;
  l.command_latency_jitter_s = 0.006;
  l.command_loss_probability = 0.01;
  l.video_datagram_loss = 0.02;
  l.state_loss = 0.03;
  l.reply_loss = 0.05;
  l.duplicate_probability = 0.002;
  l.late_reply_probability = 0.1;
  l.late_reply_s = 8.0;
  l.not_joystick_probability = 0.2;
  l.no_valid_imu_probability = 0.3;
  l.lost_command = "land";
  const EmulatorFaults f = link_faults(l);
  EXPECT_EQ(f.commands, (ChannelFaults{0.01, 30.0, 6.0, 0.002}));
  EXPECT_EQ(f.replies, (ChannelFaults{0.05, 15.0, 4.0, 0.002})) << "replies ride the state channel's latency";
  EXPECT_EQ(f.state, (ChannelFaults{0.03, 15.0, 4.0, 0.002}));
  EXPECT_EQ(f.video, (ChannelFaults{0.02, 250.0, 30.0, 0.0}));
  EXPECT_EQ(f.video_frame_loss, 0.04);
  EXPECT_EQ(f.late_replies, 0.1);
  EXPECT_EQ(f.late_reply_ms, 8000.0);
  EXPECT_EQ(f.not_joystick, 0.2);
  EXPECT_EQ(f.no_valid_imu, 0.3);
  EXPECT_EQ(f.lost_command_prefix, "land");
  EXPECT_FALSE(f.video_stall_start_s.has_value());
}

TEST(LinkFaults, TheVideoStallIsOnOnlyWithAStartAndADuration) {
  LinkSettings l;
  l.spells.video_stall_start_s = 2.0;
  EXPECT_FALSE(link_faults(l).video_stall_start_s.has_value()) << "no duration";
  l.spells.video_stall_duration_s = 1.5;
  const EmulatorFaults f = link_faults(l);
  ASSERT_TRUE(f.video_stall_start_s.has_value());
  EXPECT_EQ(*f.video_stall_start_s, 2.0);
  EXPECT_EQ(f.video_stall_duration_s, 1.5);
  l.spells.video_stall_start_s = -1.0;
  EXPECT_FALSE(link_faults(l).video_stall_start_s.has_value()) << "start < 0: none";
}

TEST(LinkFaults, BurstsAndOutagesMapToTheFaultModelOffByDefault) {
  LinkSettings l;
  EmulatorFaults f = link_faults(l);
  EXPECT_FALSE(f.bursts.on());
  EXPECT_EQ(f.outages, LinkOutages{}) << "no outages unless asked for";
  l.spells.burst_loss = 0.7;
  l.spells.burst_mean_s = 0.4;
  l.spells.burst_interval_s = 12.0;
  l.spells.outage_interval_s = 90.0;
  l.spells.outage_min_s = 1.5;
  l.spells.outage_max_s = 4.5;
  l.spells.outage_start_s = 25.0;
  f = link_faults(l);
  EXPECT_EQ(f.bursts, (BurstLoss{0.7, 0.4, 12.0}));
  EXPECT_EQ(f.outages.interval_mean_s, 90.0);
  EXPECT_EQ(f.outages.min_s, 1.5);
  EXPECT_EQ(f.outages.max_s, 4.5);
  EXPECT_FALSE(f.outages.start_s.has_value()) << "no duration";
  l.spells.outage_duration_s = 3.0;
  f = link_faults(l);
  ASSERT_TRUE(f.outages.start_s.has_value());
  EXPECT_EQ(*f.outages.start_s, 25.0);
  EXPECT_EQ(f.outages.duration_s, 3.0);
}

}  // namespace
}  // namespace shelfcross::verification
