// The link's one fault model (both links of the co-simulation draw it): each channel kept in
// order, the jitter truncated at +-3 sigma, losses and duplicates at their rates, every effect
// on a stream of its own, the injected command loss after the draws, late replies, the stall;
// losses in bursts and outages at their lengths, on streams of their own that move no other draw.

#include "verification/world/datagram_faults.hpp"

#include <algorithm>
#include <cmath>
#include <string>

#include <gtest/gtest.h>

namespace shelfcross::verification {
namespace {

using Channel = DatagramFaults::Channel;


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
    const DatagramFaults::Fate c = faults.command("rc 0 0 0 0", 0);
    commands_lost += c.lost;
    commands_twice += c.twice;
    const DatagramFaults::Fate r = faults.reply(0);
    replies_lost += r.lost;
    replies_late += r.late;
    const DatagramFaults::Fate s = faults.state(0);
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
    const DatagramFaults::Fate ca = a.command("rc 0 0 0 0", 0), cb = b.command("rc 0 0 0 0", 0);
    EXPECT_EQ(ca.lost, cb.lost);
    EXPECT_EQ(ca.twice, cb.twice);
    EXPECT_EQ(a.due(Channel::command, t), b.due(Channel::command, t));
    const DatagramFaults::Fate sa = a.state(0), sb = b.state(0);
    EXPECT_EQ(sa.lost, sb.lost);
    EXPECT_EQ(sa.twice, sb.twice);
    EXPECT_EQ(a.due(Channel::state, t), b.due(Channel::state, t));
    for (DatagramFaults* faults : {&a, &b}) {  // the other channels, drawn as a run draws them
      faults->frame_lost();
      faults->due(Channel::video, t);
      faults->video_datagram_lost(t);
      faults->reply_due(faults->reply(t), t);
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
    const DatagramFaults::Fate fa = a.command("land", 0), fb = b.command("land", 0);
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
    const DatagramFaults::Fate fa = a.command(text, 0), fb = b.command(text, 0);
    EXPECT_EQ(fb.lost, fa.lost || k % 3 == 0) << text;
    EXPECT_EQ(fa.twice, fb.twice);
  }
  EmulatorFaults only_injected;
  only_injected.lost_command_prefix = "land";
  DatagramFaults c(only_injected, 21);
  EXPECT_TRUE(c.command("land", 0).lost);
  EXPECT_FALSE(c.command("rc 0 0 0 0 land", 0).lost) << "a prefix, not a substring";
}

TEST(DatagramFaults, TheInjectedLossCanTakeOnlyTheFirstCommands) {
  EmulatorFaults f;
  f.lost_command_prefix = "land";
  f.lost_command_count = 2;
  DatagramFaults faults(f, 21);
  EXPECT_FALSE(faults.command("rc 0 0 0 0", 0).lost);
  EXPECT_TRUE(faults.command("land", 0).lost);
  EXPECT_FALSE(faults.command("rc 0 0 0 0", 0).lost) << "only prefixed commands count";
  EXPECT_TRUE(faults.command("land", 0).lost);
  EXPECT_FALSE(faults.command("land", 0).lost);
  EXPECT_FALSE(faults.command("land", 0).lost);
}

TEST(DatagramFaults, ALateReplyIsHeldBackWithoutHoldingBackTheNext) {
  EmulatorFaults f;
  f.replies = {0.0, 20.0, 0.0, 0.0};
  f.late_replies = 1.0;
  f.late_reply_ms = 7500.0;
  DatagramFaults faults(f, 2);
  const DatagramFaults::Fate late = faults.reply(0);
  ASSERT_TRUE(late.late);
  EXPECT_EQ(faults.reply_due(late, 1000 * kMs), (1000 + 20 + 7500) * kMs);
  DatagramFaults::Fate on_time = faults.reply(0);
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


// The spells of a fault: their mean lengths, the share of faulty time, the same answers asked
// in any order, a fixed seed's spells fixed.
TEST(FaultWindows, SpellsHaveTheirMeanLengthsAndAnyQueryOrderGivesTheSameAnswers) {
  const BurstLoss b{1.0, 0.5, 5.0};
  FaultWindows forward = burst_windows(b, RandomStream(42, StreamId::link_bursts));
  FaultWindows backward = burst_windows(b, RandomStream(42, StreamId::link_bursts));
  constexpr double kHorizon_s = 20000.0;
  const TimeNs step = seconds_to_ns(0.01);
  const TimeNs horizon = seconds_to_ns(kHorizon_s);
  std::int64_t faulty = 0, samples = 0;
  for (TimeNs t = 0; t < horizon; t += step, ++samples) faulty += forward.active(t);
  // Asked from the end first (the whole time line is drawn at once), then at every sample again.
  (void)backward.active(horizon - step);
  for (TimeNs t = horizon - step; t >= 0; t -= 997 * step) EXPECT_EQ(backward.active(t), forward.active(t)) << t;
  const std::vector<FaultWindow>& w = forward.windows();
  ASSERT_GT(w.size(), 3000u);
  double burst_s = 0.0, gap_s = 0.0;
  std::size_t n = 0;
  for (std::size_t i = 1; i < w.size() && w[i].end_ns < horizon; ++i, ++n) {
    burst_s += ns_to_seconds(w[i].end_ns - w[i].start_ns);
    gap_s += ns_to_seconds(w[i].start_ns - w[i - 1].end_ns);
  }
  // Exponential spells: the standard error of a mean of n is mean / sqrt(n) (about 1.7 % here).
  EXPECT_NEAR(burst_s / n, 0.5, 4.0 * 0.5 / std::sqrt(double(n)));
  EXPECT_NEAR(gap_s / n, 5.0, 4.0 * 5.0 / std::sqrt(double(n)));
  EXPECT_NEAR(double(faulty) / samples, 0.5 / 5.5, 0.01) << "the stationary share of the bad state";
  FaultWindows other_seed = burst_windows(b, RandomStream(43, StreamId::link_bursts));
  (void)other_seed.active(seconds_to_ns(100.0));
  EXPECT_NE(other_seed.windows().front().start_ns, w.front().start_ns) << "another seed, other spells";
  EXPECT_FALSE(FaultWindows{}.active(seconds_to_ns(1.0))) << "never faulty by default";
  EXPECT_FALSE(burst_windows(BurstLoss{}, RandomStream(42, StreamId::link_bursts)).active(seconds_to_ns(1.0)));
}

// Bursts on the video channel (240 datagrams a second, all lost in a burst, none outside): the
// runs of lost datagrams are r * bad_mean_s long on average, and the long-run loss rate is the
// chain's; the other channels run chains of their own.
TEST(DatagramFaults, LossBurstsLoseRunsOfTheirMeanLengthAtTheChainsRate) {
  EmulatorFaults f;
  f.bursts = {1.0, 0.25, 2.0};
  DatagramFaults faults(f, 7);
  constexpr int kRate = 240;
  constexpr int kSeconds = 4000;
  int lost = 0, runs = 0, both = 0, video_bursts = 0;
  bool last = false;
  for (int k = 0; k < kRate * kSeconds; ++k) {
    const TimeNs t = tick_time_ns(k, kRate);
    const bool l = faults.video_datagram_lost(t);
    lost += l;
    if (l && !last) ++runs;
    last = l;
    if (k % 24 == 0) {  // every 0.1 s: does the state channel share the video's burst?
      const bool video_burst = faults.burst(Channel::video, t);
      video_bursts += video_burst;
      both += video_burst && faults.burst(Channel::state, t);
    }
  }
  const double share = 0.25 / 2.25;
  EXPECT_NEAR(double(lost) / (kRate * kSeconds), share, 0.015);
  ASSERT_GT(runs, 1000);
  EXPECT_NEAR(double(lost) / runs, kRate * 0.25, 0.1 * kRate * 0.25) << "the mean burst of lost datagrams";
  EXPECT_NEAR(double(both) / video_bursts, share, 0.03) << "each channel its own chain";
}

// Outages: every channel lost at once for uniform 1-5 s, a quiet spell of the mean between; the
// fixed outage covers its window only.
TEST(DatagramFaults, OutagesTakeEveryChannelForOneToFiveSeconds) {
  EmulatorFaults f;
  f.outages.interval_mean_s = 30.0;
  DatagramFaults faults(f, 3);
  double down_s = 0.0, longest_s = 0.0, shortest_s = 1e9, sum_s = 0.0;
  int outages = 0;
  bool in_outage = false;
  TimeNs began = 0;
  constexpr int kRate = 100;
  for (int k = 0; k < kRate * 20000; ++k) {
    const TimeNs t = tick_time_ns(k, kRate);
    const bool down = faults.outage(t);
    if (down) {
      down_s += 1.0 / kRate;
      EXPECT_TRUE(faults.command("rc 0 0 0 0", t).lost);
      EXPECT_TRUE(faults.reply(t).lost);
      EXPECT_TRUE(faults.state(t).lost);
      EXPECT_TRUE(faults.video_datagram_lost(t));
    }
    if (down && !in_outage) {
      in_outage = true;
      began = t;
    }
    if (!down && in_outage) {
      const double length_s = ns_to_seconds(t - began);
      longest_s = std::max(longest_s, length_s);
      shortest_s = std::min(shortest_s, length_s);
      sum_s += length_s;
      ++outages;
      in_outage = false;
    }
  }
  ASSERT_GT(outages, 400);
  EXPECT_GE(shortest_s, 1.0 - 1.0 / kRate);
  EXPECT_LE(longest_s, 5.0 + 1.0 / kRate);
  EXPECT_GT(longest_s, 4.9);
  EXPECT_NEAR(sum_s / outages, 3.0, 4.0 * (4.0 / std::sqrt(12.0)) / std::sqrt(double(outages)));
  EXPECT_NEAR(down_s / 20000.0, 3.0 / 33.0, 0.01);

  EmulatorFaults fixed;
  fixed.outages.start_s = 40.0;
  fixed.outages.duration_s = 2.5;
  DatagramFaults once(fixed, 3);
  EXPECT_FALSE(once.outage(seconds_to_ns(40.0) - 1));
  EXPECT_TRUE(once.outage(seconds_to_ns(40.0)));
  EXPECT_TRUE(once.command("land", seconds_to_ns(41.0)).lost);
  EXPECT_TRUE(once.outage(seconds_to_ns(42.5) - 1));
  EXPECT_FALSE(once.outage(seconds_to_ns(42.5)));
  EXPECT_FALSE(once.outage(seconds_to_ns(1000.0))) << "no outage at random";
}

// Bursts and outages draw from streams of their own: outside them every fate is the one drawn
// without them, and the draws after them are the same, so a scenario without them is unchanged.
TEST(DatagramFaults, BurstsAndOutagesShiftNoOtherDraw) {
  EmulatorFaults plain;
  plain.commands = {0.1, 20.0, 5.0, 0.1};
  plain.replies = {0.1, 20.0, 5.0, 0.1};
  plain.state = {0.1, 20.0, 5.0, 0.1};
  plain.video = {0.05, 200.0, 20.0, 0.0};
  EmulatorFaults rough = plain;
  rough.bursts = {0.9, 0.5, 3.0};
  rough.outages.interval_mean_s = 20.0;
  DatagramFaults a(plain, 9), b(rough, 9);
  int differ = 0;
  for (int k = 0; k < 20000; ++k) {
    const TimeNs t = tick_time_ns(k, 50);
    const DatagramFaults::Fate ca = a.command("rc 0 0 0 0", t), cb = b.command("rc 0 0 0 0", t);
    const DatagramFaults::Fate ra = a.reply(t), rb = b.reply(t);
    const DatagramFaults::Fate sa = a.state(t), sb = b.state(t);
    const bool va = a.video_datagram_lost(t), vb = b.video_datagram_lost(t);
    EXPECT_EQ(ca.twice, cb.twice);
    EXPECT_EQ(ra.late, rb.late);
    EXPECT_EQ(sa.twice, sb.twice);
    EXPECT_EQ(a.due(Channel::video, t), b.due(Channel::video, t));
    EXPECT_EQ(a.frame_lost(), b.frame_lost());
    const bool down = b.outage(t);
    if (!down && !b.burst(Channel::command, t)) {
      EXPECT_EQ(ca.lost, cb.lost);
    }
    if (!down && !b.burst(Channel::state, t)) {
      EXPECT_EQ(sa.lost, sb.lost);
    }
    if (!down && !b.burst(Channel::video, t)) {
      EXPECT_EQ(va, vb);
    }
    differ += ca.lost != cb.lost || sa.lost != sb.lost || va != vb || ra.lost != rb.lost;
  }
  EXPECT_GT(differ, 100) << "the bursts and outages did lose datagrams";
}

}  // namespace
}  // namespace shelfcross::verification
