// The pilot loop's watch of the link in the air, passes of the loop every 20 ms by hand: an
// outage shorter than the bound is ridden through (out, then back); a longer one gives up.
#include "flight_sw/tello/link_watch.hpp"

#include <gtest/gtest.h>

#include <map>

#include "flight_sw/tello/pilot_loop.hpp"
#include "flight_sw/tello/sdk_driver_types.hpp"
#include "flight_sw/test/state_clock.hpp"

namespace shelfcross::tello {
namespace {

constexpr TimeNs kPassNs = 20 * kMs;
using flight_sw::testing::kStateRecordNs;

// State records every 0.1 s from 0 to `until_s` except in [gap_from_s, gap_to_s); the
// verdicts of passes every 20 ms, counted, and the time of the first of each.
struct Flight {
  std::map<LinkVerdict, int> count;
  std::map<LinkVerdict, TimeNs> first_ns;
};

Flight fly(LinkWatch& w, double gap_from_s, double gap_to_s, double until_s) {
  Flight f;
  TimeNs last_state_ns = 0;
  for (TimeNs t = 0; t <= seconds_to_ns(until_s); t += kPassNs) {
    const bool in_gap = t >= seconds_to_ns(gap_from_s) && t < seconds_to_ns(gap_to_s);
    if (t % kStateRecordNs == 0 && !in_gap) last_state_ns = t;
    const LinkVerdict v = w.check(t, last_state_ns);
    if (f.count[v]++ == 0) f.first_ns[v] = t;
    if (v == LinkVerdict::GiveUp) break;  // the pilot loop lands
  }
  return f;
}

TEST(LinkWatch, TheBoundIsTheWatchdogLessTheKeepAlive) {
  // The driver's keep-alive (5 s) and the Tello's watchdog (15 s) give the pilot file's limit.
  EXPECT_DOUBLE_EQ(LinkWatch::longest_outage_s(ns_to_seconds(DriverConfig{}.keepalive_ns)), 10.0);
  EXPECT_LE(Failsafes{}.link_outage_s, LinkWatch::longest_outage_s(ns_to_seconds(DriverConfig{}.keepalive_ns)));
  EXPECT_GT(Failsafes{}.link_outage_s, 5.0) << "the longest outage the scenarios draw rides through";
}

TEST(LinkWatch, AThreeSecondOutageIsRiddenThrough) {
  const Failsafes fs;
  LinkWatch w(fs.state_timeout_s, fs.link_outage_s);
  // The last record before the outage at 19.9 s; the first after it at 23.0 s.
  const Flight f = fly(w, 19.95, 22.95, 30.0);
  EXPECT_EQ(f.count.count(LinkVerdict::GiveUp), 0u) << "no landing";
  ASSERT_EQ(f.count.at(LinkVerdict::Lost), 1);
  EXPECT_EQ(f.first_ns.at(LinkVerdict::Lost), seconds_to_ns(19.9 + fs.state_timeout_s) + kPassNs)
      << "out once state_timeout_s has passed without a record";
  EXPECT_GT(f.count.at(LinkVerdict::Out), 0);
  ASSERT_EQ(f.count.at(LinkVerdict::Back), 1);
  EXPECT_EQ(f.first_ns.at(LinkVerdict::Back), seconds_to_ns(23.0)) << "back on the first record";
  EXPECT_NEAR(w.last_outage_s(), 3.1, 1e-9);
  EXPECT_EQ(w.back_ns(), seconds_to_ns(23.0)) << "the video's timers run from here";
  EXPECT_FALSE(w.out());
}

TEST(LinkWatch, AnOutagePastTheBoundGivesUp) {
  const Failsafes fs;
  LinkWatch w(fs.state_timeout_s, fs.link_outage_s);
  const Flight f = fly(w, 19.95, 32.0, 40.0);
  ASSERT_EQ(f.count.count(LinkVerdict::GiveUp), 1u);
  EXPECT_EQ(f.first_ns.at(LinkVerdict::GiveUp), seconds_to_ns(19.9 + fs.link_outage_s) + kPassNs)
      << "land once link_outage_s has passed without a record";
  EXPECT_EQ(f.count.count(LinkVerdict::Back), 0u);
  EXPECT_TRUE(w.out());
}

TEST(LinkWatch, ShortGapsOfTheStateStreamAreNoOutage) {
  const Failsafes fs;
  LinkWatch w(fs.state_timeout_s, fs.link_outage_s);
  // A burst of 1.5 s without records: short of state_timeout_s.
  const Flight f = fly(w, 10.0, 11.5, 15.0);
  EXPECT_EQ(f.count.size(), 1u);
  EXPECT_EQ(f.count.count(LinkVerdict::Live), 1u);
  EXPECT_FALSE(w.back_ns().has_value());
}

}  // namespace
}  // namespace shelfcross::tello
