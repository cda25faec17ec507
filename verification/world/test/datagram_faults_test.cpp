// The link's one fault model (both links of the co-simulation draw it): each channel kept in
// order, the jitter truncated at +-3 sigma, losses and duplicates at their rates, every effect
// on a stream of its own, the injected command loss after the draws, late replies, the stall.

#include "verification/world/datagram_faults.hpp"

#include <algorithm>
#include <string>

#include <gtest/gtest.h>

namespace shelfcross::verification {
namespace {

using Channel = DatagramFaults::Channel;

constexpr TimeNs kMs = 1'000'000;

TEST(DatagramFaults, SameSeedSameFatesAndEachChannelKeepsItsOrder) {
  EmulatorFaults f;
  f.video = {0.0, 200.0, 50.0, 0.0};  // a jitter large against the 33 ms between captures
  f.video_frame_loss = 0.02;
  DatagramFaults a(f, 77), b(f, 77);
  TimeNs last = 0;
  int lost = 0, reordered_without_the_rule = 0;
  for (int k = 0; k < 3000; ++k) {
    const TimeNs capture = tick_time_ns(k, 30);
    const bool lost_a = a.frame_lost();
    EXPECT_EQ(lost_a, b.frame_lost());
    if (lost_a) {
      ++lost;
      continue;
    }
    const TimeNs due = a.due(Channel::video, capture);
    EXPECT_EQ(due, b.due(Channel::video, capture));
    EXPECT_GE(due, last) << "a frame never arrives before the one sent before it";
    EXPECT_GE(due, capture + 50 * kMs) << "200 ms - 3 sigma at the least";
    if (due == last) ++reordered_without_the_rule;
    last = due;
  }
  EXPECT_NEAR(lost / 3000.0, f.video_frame_loss, 0.01);
  EXPECT_GT(reordered_without_the_rule, 0) << "the order rule bound at least once";
}

TEST(DatagramFaults, JitterIsTruncatedAtThreeSigmaAndNeverBelowZero) {
  EmulatorFaults f;
  f.state = {0.0, 100.0, 10.0, 0.0};
  f.commands = {0.0, 5.0, 10.0, 0.0};  // mean - 3 sigma < 0: clamped at zero latency
  DatagramFaults faults(f, 3);
  TimeNs min_state = 1'000'000 * kMs, max_state = 0, min_command = 1'000'000 * kMs;
  double sum_state_ms = 0.0;
  constexpr int kSends = 20000;
  for (int k = 0; k < kSends; ++k) {
    const TimeNs t = tick_time_ns(k, 1);  // 1 s apart: the order rule never binds
    const TimeNs state = faults.due(Channel::state, t) - t;
    min_state = std::min(min_state, state);
    max_state = std::max(max_state, state);
    sum_state_ms += static_cast<double>(state) / kMs;
    min_command = std::min(min_command, faults.due(Channel::command, t) - t);
  }
  // About 0.27 % of normal draws fall beyond 3 sigma: some of 20000 land on each bound exactly.
  EXPECT_EQ(min_state, 70 * kMs);
  EXPECT_EQ(max_state, 130 * kMs);
  EXPECT_NEAR(sum_state_ms / kSends, 100.0, 0.3);
  EXPECT_EQ(min_command, 0);
}

TEST(DatagramFaults, LossesDuplicatesAndLateRepliesAtTheirRates) {
  EmulatorFaults f;
  f.commands = {0.1, 0.0, 0.0, 0.05};
  f.replies = {0.2, 20.0, 0.0, 0.0};
  f.late_replies = 0.3;
  f.state = {0.05, 0.0, 0.0, 0.1};
  DatagramFaults faults(f, 11);
  constexpr int kN = 20000;
  int commands_lost = 0, commands_twice = 0, replies_lost = 0, replies_late = 0, state_lost = 0, state_twice = 0;
  for (int k = 0; k < kN; ++k) {
    const DatagramFaults::Fate c = faults.command("rc 0 0 0 0");
    commands_lost += c.lost;
    commands_twice += c.twice;
    const DatagramFaults::Fate r = faults.reply();
    replies_lost += r.lost;
    replies_late += r.late;
    const DatagramFaults::Fate s = faults.state();
    state_lost += s.lost;
    state_twice += s.twice;
  }
  EXPECT_NEAR(commands_lost / double(kN), 0.1, 0.01);
  EXPECT_NEAR(commands_twice / double(kN), 0.05, 0.01);
  EXPECT_NEAR(replies_lost / double(kN), 0.2, 0.01);
  EXPECT_NEAR(replies_late / double(kN), 0.3, 0.01);
  EXPECT_NEAR(state_lost / double(kN), 0.05, 0.01);
  EXPECT_NEAR(state_twice / double(kN), 0.1, 0.01);
}

TEST(DatagramFaults, ChangingOneSettingDoesNotShiftTheOtherStreams) {
  EmulatorFaults f1, f2;
  f1.commands = f2.commands = {0.2, 20.0, 5.0, 0.1};
  f1.state = f2.state = {0.1, 20.0, 5.0, 0.1};
  f2.video_frame_loss = 0.5;
  f2.video = {0.3, 300.0, 50.0, 0.0};
  f2.replies = {0.5, 100.0, 30.0, 0.5};
  f2.late_replies = 0.5;
  DatagramFaults a(f1, 9), b(f2, 9);
  for (int k = 0; k < 200; ++k) {
    const TimeNs t = tick_time_ns(k, 10);
    const DatagramFaults::Fate ca = a.command("rc 0 0 0 0"), cb = b.command("rc 0 0 0 0");
    EXPECT_EQ(ca.lost, cb.lost);
    EXPECT_EQ(ca.twice, cb.twice);
    EXPECT_EQ(a.due(Channel::command, t), b.due(Channel::command, t));
    const DatagramFaults::Fate sa = a.state(), sb = b.state();
    EXPECT_EQ(sa.lost, sb.lost);
    EXPECT_EQ(sa.twice, sb.twice);
    EXPECT_EQ(a.due(Channel::state, t), b.due(Channel::state, t));
    for (DatagramFaults* faults : {&a, &b}) {  // the other channels, drawn as a run draws them
      faults->frame_lost();
      faults->due(Channel::video, t);
      faults->video_datagram_lost();
      faults->reply_due(faults->reply(), t);
    }
  }
}

TEST(DatagramFaults, AFateDrawsTheSameCountWhateverItsProbabilities) {
  // Losing no command or every command: the duplicates that follow are the same draws.
  EmulatorFaults none, all;
  none.commands = {0.0, 0.0, 0.0, 0.3};
  all.commands = {1.0, 0.0, 0.0, 0.3};
  DatagramFaults a(none, 5), b(all, 5);
  for (int k = 0; k < 200; ++k) {
    const DatagramFaults::Fate fa = a.command("land"), fb = b.command("land");
    EXPECT_FALSE(fa.lost);
    EXPECT_TRUE(fb.lost);
    EXPECT_EQ(fa.twice, fb.twice);
  }
}

TEST(DatagramFaults, TheInjectedCommandLossComesAfterTheDraws) {
  EmulatorFaults plain, injected;
  plain.commands = injected.commands = {0.3, 0.0, 0.0, 0.3};
  injected.lost_command_prefix = "land";
  DatagramFaults a(plain, 21), b(injected, 21);
  for (int k = 0; k < 200; ++k) {
    const std::string text = k % 3 == 0 ? "land" : "rc 0 10 0 0";
    const DatagramFaults::Fate fa = a.command(text), fb = b.command(text);
    EXPECT_EQ(fb.lost, fa.lost || k % 3 == 0) << text;
    EXPECT_EQ(fa.twice, fb.twice);
  }
  EmulatorFaults only_injected;
  only_injected.lost_command_prefix = "land";
  DatagramFaults c(only_injected, 21);
  EXPECT_TRUE(c.command("land").lost);
  EXPECT_FALSE(c.command("rc 0 0 0 0 land").lost) << "a prefix, not a substring";
}

TEST(DatagramFaults, TheInjectedLossCanTakeOnlyTheFirstCommands) {
  EmulatorFaults f;
  f.lost_command_prefix = "land";
  f.lost_command_count = 2;
  DatagramFaults faults(f, 21);
  EXPECT_FALSE(faults.command("rc 0 0 0 0").lost);
  EXPECT_TRUE(faults.command("land").lost);
  EXPECT_FALSE(faults.command("rc 0 0 0 0").lost) << "only prefixed commands count";
  EXPECT_TRUE(faults.command("land").lost);
  EXPECT_FALSE(faults.command("land").lost);
  EXPECT_FALSE(faults.command("land").lost);
}

TEST(DatagramFaults, ALateReplyIsHeldBackWithoutHoldingBackTheNext) {
  EmulatorFaults f;
  f.replies = {0.0, 20.0, 0.0, 0.0};
  f.late_replies = 1.0;
  f.late_reply_ms = 7500.0;
  DatagramFaults faults(f, 2);
  const DatagramFaults::Fate late = faults.reply();
  ASSERT_TRUE(late.late);
  EXPECT_EQ(faults.reply_due(late, 1000 * kMs), (1000 + 20 + 7500) * kMs);
  DatagramFaults::Fate on_time = faults.reply();
  on_time.late = false;
  EXPECT_EQ(faults.reply_due(on_time, 1100 * kMs), (1100 + 20) * kMs) << "the hold is not the channel's order";
}

TEST(DatagramFaults, TheVideoStallCoversItsWindowOnly) {
  EmulatorFaults f;
  DatagramFaults off(f, 1);
  EXPECT_FALSE(off.video_stalled(seconds_to_ns(3.0)));
  f.video_stall_start_s = 2.0;
  f.video_stall_duration_s = 1.5;
  DatagramFaults on(f, 1);
  EXPECT_FALSE(on.video_stalled(seconds_to_ns(2.0) - 1));
  EXPECT_TRUE(on.video_stalled(seconds_to_ns(2.0)));
  EXPECT_TRUE(on.video_stalled(seconds_to_ns(3.5) - 1));
  EXPECT_FALSE(on.video_stalled(seconds_to_ns(3.5)));
}

}  // namespace
}  // namespace shelfcross::verification
