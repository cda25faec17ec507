// The driver against a scripted fake drone on loopback: real UDP sockets on 127.0.0.1 with
// ephemeral ports, the fake drone stepped by the test, time stepped with a ManualClock.
#include "flight_sw/tello/sdk_driver.hpp"

#include <gtest/gtest.h>

#include <algorithm>

#include "flight_sw/tello/test/loopback.hpp"
#include "shelfcross/random.hpp"

namespace shelfcross::tello {
namespace {

using testing::pause_ms;
using testing::pump_until;
using testing::receive_within;
using Kind = DriverEvent::Kind;

constexpr const char* kSdk13 =
    "pitch:1;roll:5;yaw:0;vgx:0;vgy:0;vgz:0;templ:43;temph:46;tof:10;h:0;bat:83;baro:150.12;time:0;"
    "agx:15.00;agy:-97.00;agz:-988.00;\r\n";
constexpr const char* kSdk20 =
    "mid:257;x:0;y:0;z:0;mpry:0,0,0;pitch:0;roll:0;yaw:-20;vgx:0;vgy:0;vgz:0;templ:60;temph:62;tof:10;h:0;"
    "bat:67;baro:1687.34;time:16;agx:6.00;agy:0.00;agz:-999.00;\r\n";
constexpr const char* kSdk20NoPad =
    "mid:-1;x:-100;y:-100;z:-100;mpry:-1,-1,-1;pitch:0;roll:0;yaw:0;vgx:0;vgy:0;vgz:0;templ:55;temph:57;"
    "tof:6553;h:0;bat:5;baro:118.26;time:0;agx:-4.00;agy:1.00;agz:-997.00;\r\n";

constexpr TimeNs kS = kNsPerSecond;

// The fake drone: a command socket (the "8889") and a state sender socket, both ephemeral.
struct FakeDrone {
  UdpSocket command{"127.0.0.1", 0};
  UdpSocket state{"127.0.0.1", 0};
  Endpoint driver_command;  // where replies go (learnt from the first command)

  std::optional<std::string> expect_command() {
    auto d = receive_within(command);
    if (!d) return std::nullopt;
    driver_command = d->from;
    return d->bytes;
  }
  /// True when no command waits (the driver is single-threaded and sends inside service(),
  /// and loopback delivery happens inside sendto(), so nothing can still be on its way).
  bool nothing_sent() { return !command.wait_readable(20); }
  void reply(const std::string& text) { ASSERT_TRUE(command.send_to(driver_command, text)); }
};

struct Rig {
  ManualClock clock{0};
  FakeDrone drone;
  std::unique_ptr<SdkDriver> driver;
  std::vector<DriverEvent> events;

  explicit Rig(DriverConfig config = {}) {
    config.drone_ip = "127.0.0.1";
    config.drone_command_port = drone.command.local_port();
    config.local_ip = "127.0.0.1";
    config.local_command_port = 0;
    config.local_state_port = 0;
    config.state_source_port = drone.state.local_port();
    driver = std::make_unique<SdkDriver>(config, clock);
  }
  void service() {
    driver->service();
    for (auto& e : driver->take_events()) events.push_back(std::move(e));
  }
  /// Lets `dt` pass, then services the driver once.
  void elapse(TimeNs dt) {
    clock.advance(dt);
    service();
  }
  int count(Kind k) const {
    return static_cast<int>(std::count_if(events.begin(), events.end(), [&](const DriverEvent& e) { return e.kind == k; }));
  }
  const DriverEvent* last(Kind k) const {
    for (auto it = events.rbegin(); it != events.rend(); ++it) {
      if (it->kind == k) return &*it;
    }
    return nullptr;
  }
  bool pump_until_event(Kind k, int n = 1) {
    return pump_until([&] { service(); }, [&] { return count(k) >= n; });
  }
  void send_state(const std::string& text) {
    ASSERT_TRUE(drone.state.send_to({"127.0.0.1", driver->local_state_port()}, text));
  }
};

TEST(SdkDriver, SendsACommandAndTakesItsReply) {
  Rig rig;
  ASSERT_TRUE(rig.driver->submit("command", {.tag = 7}));
  rig.service();
  EXPECT_EQ(rig.drone.expect_command(), "command");
  EXPECT_TRUE(rig.driver->outstanding());
  rig.drone.reply("ok\r\n");
  ASSERT_TRUE(rig.pump_until_event(Kind::Reply));
  const DriverEvent* r = rig.last(Kind::Reply);
  EXPECT_EQ(r->command, "command");
  EXPECT_EQ(r->reply, "ok");  // "\r\n" removed
  EXPECT_EQ(r->attempt, 1);
  EXPECT_EQ(r->tag, 7);
  EXPECT_FALSE(rig.driver->outstanding());
  EXPECT_EQ(rig.driver->counters().replies, 1);
}

TEST(SdkDriver, RetriesWhenRepliesAreLostAndTakesALateReply) {
  DriverConfig config;
  config.keepalive_ns = 0;  // the keep-alive rc is tested on its own
  Rig rig(config);
  ASSERT_TRUE(rig.driver->submit("takeoff"));
  rig.service();
  EXPECT_EQ(rig.drone.expect_command(), "takeoff");
  // The takeoff timeout is 20 s: nothing is re-sent a nanosecond before.
  rig.elapse(20 * kS - 1);
  EXPECT_TRUE(rig.drone.nothing_sent());
  rig.elapse(1);
  EXPECT_EQ(rig.drone.expect_command(), "takeoff");  // attempt 2 (the reply was lost)
  rig.elapse(20 * kS);
  EXPECT_EQ(rig.drone.expect_command(), "takeoff");  // attempt 3
  rig.clock.advance(3 * kS);  // late, but within attempt 3's timeout
  rig.drone.reply("ok");
  ASSERT_TRUE(rig.pump_until_event(Kind::Reply));
  EXPECT_EQ(rig.last(Kind::Reply)->attempt, 3);
  EXPECT_EQ(rig.count(Kind::Retry), 2);
  EXPECT_EQ(rig.driver->counters().retries, 2);
  EXPECT_EQ(rig.driver->counters().commands_sent, 3);
  EXPECT_EQ(rig.count(Kind::Failed), 0);
}

TEST(SdkDriver, FailsAfterTheLastRetry) {
  DriverConfig config;
  config.retries = 3;
  config.keepalive_ns = 0;
  Rig rig(config);
  ASSERT_TRUE(rig.driver->submit("streamon"));
  rig.service();
  for (int attempt = 1; attempt <= 4; ++attempt) {
    EXPECT_EQ(rig.drone.expect_command(), "streamon") << attempt;
    rig.elapse(7 * kS);
  }
  EXPECT_TRUE(rig.drone.nothing_sent());
  EXPECT_EQ(rig.count(Kind::Failed), 1);
  EXPECT_EQ(rig.last(Kind::Failed)->attempt, 4);
  EXPECT_EQ(rig.driver->counters().commands_sent, 4);
  EXPECT_EQ(rig.driver->counters().retries, 3);
  EXPECT_FALSE(rig.driver->outstanding());
}

TEST(SdkDriver, LateReplyToThePreviousCommandIsNotTakenForTheNext) {
  DriverConfig config;
  config.keepalive_ns = 0;  // the keep-alive rc is tested on its own
  Rig rig(config);
  ASSERT_TRUE(rig.driver->submit("battery?", {.retries = 0}));
  rig.service();
  EXPECT_EQ(rig.drone.expect_command(), "battery?");
  rig.elapse(7 * kS);
  ASSERT_EQ(rig.count(Kind::Failed), 1);
  // The next command waits out the stale guard; meanwhile the old reply arrives.
  ASSERT_TRUE(rig.driver->submit("height?"));
  rig.service();
  EXPECT_TRUE(rig.drone.nothing_sent());
  rig.drone.reply("87");          // battery?'s answer, late
  rig.clock.advance(300 * kMs);   // guard over: drained before the send
  rig.service();
  EXPECT_EQ(rig.drone.expect_command(), "height?");
  rig.drone.reply("3dm");
  ASSERT_TRUE(rig.pump_until_event(Kind::Reply));
  EXPECT_EQ(rig.last(Kind::Reply)->command, "height?");
  EXPECT_EQ(rig.last(Kind::Reply)->reply, "3dm");
  EXPECT_EQ(rig.count(Kind::Reply), 1);
  EXPECT_EQ(rig.driver->counters().stale_replies, 1);
  EXPECT_EQ(rig.last(Kind::StaleReply)->reply, "87");
}

TEST(SdkDriver, ReplyWithNothingOutstandingIsStale) {
  Rig rig;
  ASSERT_TRUE(rig.driver->submit("command"));
  rig.service();
  ASSERT_TRUE(rig.drone.expect_command());
  rig.drone.reply("ok");
  ASSERT_TRUE(rig.pump_until_event(Kind::Reply));
  rig.drone.reply("ok");  // a duplicate
  ASSERT_TRUE(rig.pump_until_event(Kind::StaleReply));
  EXPECT_EQ(rig.driver->counters().stale_replies, 1);
  EXPECT_EQ(rig.driver->counters().replies, 1);
}

TEST(SdkDriver, DropsAndCountsSpoofedDatagramsFromAnotherPort) {
  Rig rig;
  UdpSocket spoofer("127.0.0.1", 0);
  ASSERT_TRUE(rig.driver->submit("land"));
  rig.service();
  ASSERT_TRUE(rig.drone.expect_command());
  ASSERT_TRUE(spoofer.send_to(rig.drone.driver_command, "ok"));
  ASSERT_TRUE(spoofer.send_to({"127.0.0.1", rig.driver->local_state_port()}, kSdk13));
  ASSERT_TRUE(rig.pump_until_event(Kind::Foreign, 2));
  EXPECT_TRUE(rig.driver->outstanding());  // the spoofed "ok" answered nothing
  EXPECT_EQ(rig.driver->counters().foreign_command_datagrams, 1);
  EXPECT_EQ(rig.driver->counters().foreign_state_datagrams, 1);
  EXPECT_EQ(rig.count(Kind::State), 0);
  rig.drone.reply("ok");
  ASSERT_TRUE(rig.pump_until_event(Kind::Reply));
  EXPECT_EQ(rig.last(Kind::Reply)->command, "land");
}

TEST(SdkDriver, ParsesEveryStateSampleOfTheProtocol) {
  Rig rig;
  rig.clock.set(5 * kS);
  for (const char* s : {kSdk13, kSdk20, kSdk20NoPad}) rig.send_state(s);
  ASSERT_TRUE(rig.pump_until_event(Kind::State, 3));
  std::vector<int> battery;
  for (const auto& e : rig.events) {
    if (e.kind != Kind::State) continue;
    ASSERT_TRUE(e.state);
    EXPECT_EQ(e.state->t_ns, 5 * kS);
    battery.push_back(e.state->battery_pct);
  }
  EXPECT_EQ(battery, (std::vector<int>{83, 67, 5}));
  const DriverEvent* last = rig.last(Kind::State);
  EXPECT_FALSE(last->state->tof_m);  // 6553: invalid
  EXPECT_EQ(rig.driver->counters().states, 3);
  EXPECT_EQ(rig.driver->counters().bad_states, 0);
  EXPECT_EQ(rig.driver->last_state_ns(), 5 * kS);
}

TEST(SdkDriver, DropsAndCountsMalformedStateDatagrams) {
  Rig rig;
  const std::vector<std::string> bad = {"ok", "ok\r\n", "Ok", "garbage", "pitch:abc;roll:1;",
                                        std::string("\x00\xff\x13:;;", 6), ""};
  for (const auto& b : bad) rig.send_state(b);
  rig.send_state(kSdk20);
  ASSERT_TRUE(rig.pump_until_event(Kind::State));
  ASSERT_TRUE(pump_until([&] { rig.service(); },
                         [&] { return rig.driver->counters().bad_states == static_cast<int>(bad.size()); }));
  EXPECT_EQ(rig.driver->counters().stray_ok_states, 3);  // "ok" in any case (is_ok_reply)
  EXPECT_EQ(rig.driver->counters().states, 1);
}

TEST(SdkDriver, NeverWaitsForRcAndRepeatsItAtASteadyRateWhileFresh) {
  Rig rig;
  ASSERT_TRUE(rig.driver->submit("rc 0 30 0 -10"));
  rig.service();
  EXPECT_EQ(rig.drone.expect_command(), "rc 0 30 0 -10");
  EXPECT_FALSE(rig.driver->outstanding());
  // A non-rc command right after goes out at once: nobody waits for an rc reply.
  ASSERT_TRUE(rig.driver->submit("battery?"));
  rig.service();
  EXPECT_EQ(rig.drone.expect_command(), "battery?");
  rig.drone.reply("80");
  ASSERT_TRUE(rig.pump_until_event(Kind::Reply));
  // Repeats every rc_period (100 ms) while fresh.
  rig.elapse(99 * kMs);
  EXPECT_TRUE(rig.drone.nothing_sent());
  rig.elapse(1 * kMs);
  EXPECT_EQ(rig.drone.expect_command(), "rc 0 30 0 -10");
  // Not renewed for rc_hold (1.5 s): falls back to hover.
  rig.clock.set(1500 * kMs);
  rig.service();
  EXPECT_EQ(rig.drone.expect_command(), "rc 0 0 0 0");
  EXPECT_TRUE(rig.drone.nothing_sent());
}

// The drone flies the last sticks it got: a `land` lost on the way after "rc 0 30 0 0" would
// leave it flying forward until the retry. The sticks are centred on the wire first, twice.
TEST(SdkDriver, CentresDeflectedSticksTwiceBeforeAManoeuvre) {
  Rig rig;
  ASSERT_TRUE(rig.driver->submit("rc 0 30 0 0"));
  rig.service();
  EXPECT_EQ(rig.drone.expect_command(), "rc 0 30 0 0");
  ASSERT_TRUE(rig.driver->submit("rc 0 0 0 0"));
  ASSERT_TRUE(rig.driver->submit("land"));
  rig.elapse(5 * kMs);
  EXPECT_TRUE(rig.drone.nothing_sent());  // within rc_min_gap (20 ms) of the last rc
  rig.elapse(15 * kMs);
  EXPECT_EQ(rig.drone.expect_command(), "rc 0 0 0 0");
  EXPECT_TRUE(rig.drone.nothing_sent());
  rig.elapse(20 * kMs);
  EXPECT_EQ(rig.drone.expect_command(), "rc 0 0 0 0");
  rig.elapse(20 * kMs);
  EXPECT_EQ(rig.drone.expect_command(), "land");
  EXPECT_TRUE(rig.drone.nothing_sent());
  rig.drone.reply("ok");
  ASSERT_TRUE(rig.pump_until_event(Kind::Reply));
  // Centred sticks stay centred: the next manoeuvre goes out without them.
  ASSERT_TRUE(rig.driver->submit("takeoff"));
  rig.elapse(100 * kMs);
  EXPECT_EQ(rig.drone.expect_command(), "takeoff");
  EXPECT_EQ(rig.driver->counters().rc_sent, 3);
}

TEST(SdkDriver, EmergencyNeverWaitsForTheSticks) {
  Rig rig;
  ASSERT_TRUE(rig.driver->submit("rc 40 0 0 0"));
  rig.service();
  EXPECT_EQ(rig.drone.expect_command(), "rc 40 0 0 0");
  ASSERT_TRUE(rig.driver->submit("emergency", {.urgent = true}));
  rig.service();
  EXPECT_EQ(rig.drone.expect_command(), "emergency");
}

TEST(SdkDriver, KeepAliveGoesOutWhileALongCommandIsOutstanding) {
  Rig rig;
  ASSERT_TRUE(rig.driver->submit("takeoff"));
  rig.service();
  EXPECT_EQ(rig.drone.expect_command(), "takeoff");
  rig.elapse(5 * kS - 1);
  EXPECT_TRUE(rig.drone.nothing_sent());
  rig.elapse(1);
  EXPECT_EQ(rig.drone.expect_command(), "rc 0 0 0 0");  // under the 15 s watchdog
  EXPECT_TRUE(rig.driver->outstanding());
  rig.elapse(5 * kS);
  EXPECT_EQ(rig.drone.expect_command(), "rc 0 0 0 0");
  rig.drone.reply("ok");
  ASSERT_TRUE(rig.pump_until_event(Kind::Reply));
  EXPECT_EQ(rig.last(Kind::Reply)->command, "takeoff");
  EXPECT_EQ(rig.driver->counters().keepalives, 2);
}

TEST(SdkDriver, KeepsTheGapBetweenNonRcCommands) {
  Rig rig;
  ASSERT_TRUE(rig.driver->submit("command"));
  ASSERT_TRUE(rig.driver->submit("streamon"));
  rig.service();
  EXPECT_EQ(rig.drone.expect_command(), "command");
  rig.drone.reply("ok");
  ASSERT_TRUE(rig.pump_until_event(Kind::Reply));
  rig.elapse(100 * kMs - 1);
  EXPECT_TRUE(rig.drone.nothing_sent());
  rig.elapse(1);
  EXPECT_EQ(rig.drone.expect_command(), "streamon");
}

TEST(SdkDriver, NeverSendsAnOutOfRangeCommand) {
  Rig rig;
  for (const char* c : {"rc 101 0 0 0", "rc 0 0 0 -150", "forward 10", "go 10 10 10 50", "cw 0",
                        "rc 1.5 0 0 0", "takeoff now", "land\r\n", "rc 0 0 0 0 0"}) {
    EXPECT_FALSE(rig.driver->submit(c)) << c;
  }
  rig.elapse(kS);
  EXPECT_TRUE(rig.drone.nothing_sent());
  EXPECT_EQ(rig.driver->counters().rejected, 9);
  EXPECT_EQ(rig.count(Kind::Rejected), 9);
  EXPECT_EQ(rig.driver->counters().commands_sent + rig.driver->counters().rc_sent, 0);
}

TEST(SdkDriver, DryRunNeverSendsAMotionCommand) {
  DriverConfig config;
  config.dry_run = true;
  Rig rig(config);
  ASSERT_TRUE(rig.driver->submit("command"));
  rig.service();
  EXPECT_EQ(rig.drone.expect_command(), "command");
  rig.drone.reply("ok");
  ASSERT_TRUE(rig.pump_until_event(Kind::Reply));
  for (const char* c : {"takeoff", "rc 0 50 0 0", "forward 50", "land", "emergency"}) {
    EXPECT_FALSE(rig.driver->submit(c)) << c;
  }
  for (int i = 0; i < 10; ++i) {
    rig.elapse(2 * kS);
  }
  EXPECT_TRUE(rig.drone.nothing_sent());  // no keep-alive rc either
  EXPECT_EQ(rig.count(Kind::Filtered), 5);
  // The flight software gets a synthetic "ok" for the non-rc ones, marked as such.
  int synthetic = 0;
  for (const auto& e : rig.events) synthetic += e.kind == Kind::Reply && e.synthetic;
  EXPECT_EQ(synthetic, 4);
}

TEST(SdkDriver, UrgentLandDisplacesTheOutstandingCommand) {
  Rig rig;
  ASSERT_TRUE(rig.driver->submit("takeoff"));
  ASSERT_TRUE(rig.driver->submit("battery?"));
  ASSERT_TRUE(rig.driver->submit("rc 0 20 0 0"));
  rig.service();
  EXPECT_EQ(rig.drone.expect_command(), "takeoff");
  ASSERT_TRUE(rig.driver->submit("land", {.tag = 2, .urgent = true}));
  rig.service();
  EXPECT_TRUE(rig.drone.nothing_sent());  // the 0.1 s gap still holds
  rig.elapse(100 * kMs);
  EXPECT_EQ(rig.drone.expect_command(), "land");
  rig.drone.reply("ok");
  ASSERT_TRUE(rig.pump_until_event(Kind::Reply));
  EXPECT_EQ(rig.last(Kind::Reply)->command, "land");
  EXPECT_EQ(rig.last(Kind::Reply)->tag, 2);
  EXPECT_EQ(rig.driver->counters().abandoned, 2);  // takeoff and battery?
  rig.elapse(kS);
  EXPECT_TRUE(rig.drone.nothing_sent());  // the rc setpoint was cleared too
}

TEST(SdkDriver, ResendsAnUnheardCommandAtOnceWhileRetriesRemain) {
  DriverConfig config;
  config.keepalive_ns = 0;
  Rig rig(config);
  ASSERT_TRUE(rig.driver->submit("land", {.timeout_ns = 5 * kS, .retries = 1}));
  rig.service();
  EXPECT_EQ(rig.drone.expect_command(), "land");
  rig.elapse(1500 * kMs);
  EXPECT_FALSE(rig.driver->resend_unheard("takeoff")) << "not the outstanding command";
  EXPECT_TRUE(rig.driver->resend_unheard("land"));
  rig.service();
  EXPECT_EQ(rig.drone.expect_command(), "land");  // attempt 2, long before the 5 s timeout
  EXPECT_EQ(rig.last(Kind::Retry)->attempt, 2);
  EXPECT_FALSE(rig.driver->resend_unheard("land")) << "its one retry is spent";
  // The re-send restarts the timeout: nothing more until 5 s after it, then it fails.
  rig.elapse(5 * kS - 1);
  EXPECT_TRUE(rig.drone.nothing_sent());
  EXPECT_EQ(rig.count(Kind::Failed), 0);
  rig.elapse(1);
  EXPECT_EQ(rig.count(Kind::Failed), 1);
  EXPECT_FALSE(rig.driver->resend_unheard("land")) << "nothing outstanding";
}

TEST(SdkDriver, SurvivesRandomDatagramsOnBothSockets) {
  Rig rig;
  RandomStream rng(42, StreamId::link_faults);
  const int n = 400;
  int on_state = 0;
  ASSERT_TRUE(rig.driver->submit("command"));
  rig.service();
  ASSERT_TRUE(rig.drone.expect_command());
  for (int i = 0; i < n; ++i) {
    std::string bytes(rng.below(300), '\0');
    for (char& c : bytes) c = static_cast<char>(rng.below(256));
    if (rng.bernoulli(0.3)) bytes = "pitch:" + bytes;  // half-plausible records
    if (rng.bernoulli(0.5)) {
      rig.send_state(bytes);
      ++on_state;
    } else {
      rig.drone.reply(bytes);
    }
    if (i % 20 == 0) rig.service();
  }
  const DriverCounters& c = rig.driver->counters();
  ASSERT_TRUE(pump_until([&] { rig.service(); }, [&] {
    return c.states + c.bad_states == on_state &&
           c.replies + c.stale_replies + c.bad_replies == n - on_state;
  }));
  EXPECT_LE(c.replies, 1);
  EXPECT_EQ(c.foreign_command_datagrams + c.foreign_state_datagrams, 0);
}

// rc_new_copies: new sticks go out that many times, rc_min_gap (20 ms) apart, then repeat every
// rc_period (100 ms) from the last copy; the same sticks renewed send no extra copy.
TEST(SdkDriver, SendsNewSticksAsManyTimesAsAskedThenRepeatsAtTheSteadyRate) {
  DriverConfig config;
  config.rc_new_copies = 3;
  Rig rig(config);
  ASSERT_TRUE(rig.driver->submit("rc 0 30 0 0"));
  rig.service();
  EXPECT_EQ(rig.drone.expect_command(), "rc 0 30 0 0");
  rig.clock.set(10 * kMs);
  ASSERT_TRUE(rig.driver->submit("rc 0 30 0 0"));
  rig.service();
  EXPECT_TRUE(rig.drone.nothing_sent());  // within rc_min_gap of the last rc
  for (int ms : {20, 40}) {
    rig.clock.set(ms * kMs);
    rig.service();
    EXPECT_EQ(rig.drone.expect_command(), "rc 0 30 0 0") << ms;
  }
  rig.clock.set(139 * kMs);
  rig.service();
  EXPECT_TRUE(rig.drone.nothing_sent());
  rig.clock.set(140 * kMs);
  rig.service();
  EXPECT_EQ(rig.drone.expect_command(), "rc 0 30 0 0");
  rig.clock.set(150 * kMs);  // other sticks: three copies again, the first as soon as the gap allows
  ASSERT_TRUE(rig.driver->submit("rc 0 0 0 0"));
  rig.service();
  EXPECT_TRUE(rig.drone.nothing_sent());
  for (int ms : {160, 180, 200}) {
    rig.clock.set(ms * kMs);
    rig.service();
    EXPECT_EQ(rig.drone.expect_command(), "rc 0 0 0 0") << ms;
  }
  rig.clock.set(299 * kMs);
  rig.service();
  EXPECT_TRUE(rig.drone.nothing_sent());
  EXPECT_EQ(rig.driver->counters().rc_sent, 7);
}

}  // namespace
}  // namespace shelfcross::tello

namespace shelfcross::tello {
namespace {

TEST(SdkDriver, RenewingTheSameSticksKeepsTheSteadyRate) {
  Rig rig;
  ASSERT_TRUE(rig.driver->submit("rc 10 0 0 0"));
  rig.service();
  EXPECT_EQ(rig.drone.expect_command(), "rc 10 0 0 0");
  for (int ms = 10; ms < 100; ms += 10) {  // renewed every 10 ms: still one rc per 100 ms
    rig.clock.set(ms * kMs);
    ASSERT_TRUE(rig.driver->submit("rc 10 0 0 0"));
    rig.service();
    EXPECT_TRUE(rig.drone.nothing_sent()) << ms;
  }
  rig.clock.set(100 * kMs);
  rig.service();
  EXPECT_EQ(rig.drone.expect_command(), "rc 10 0 0 0");
  rig.clock.set(120 * kMs);  // new sticks go out at once (20 ms after the last rc)
  ASSERT_TRUE(rig.driver->submit("rc 0 0 0 0"));
  rig.service();
  EXPECT_EQ(rig.drone.expect_command(), "rc 0 0 0 0");
  EXPECT_EQ(rig.driver->counters().rc_sent, 3);
}

}  // namespace
}  // namespace shelfcross::tello

namespace shelfcross::tello {
namespace {

using Kind = DriverEvent::Kind;
using testing::pump_until;
constexpr TimeNs kSec = kNsPerSecond;

// A real Tello refuses manoeuvres with "error Not joystick" or "error No valid imu". By
// default a refusal is the command's reply (the submitter decides: the flight software
// retries a refused takeoff itself); with retry_unless_ok the driver re-sends after
// refusal_retry_ns while retries remain, and reports each refusal.
TEST(SdkDriver, ARefusalIsTheReplyUnlessRetryUnlessOk) {
  DriverConfig config;
  config.keepalive_ns = 0;
  Rig rig(config);
  ASSERT_TRUE(rig.driver->submit("takeoff"));
  rig.service();
  EXPECT_EQ(rig.drone.expect_command(), "takeoff");
  rig.drone.reply("error No valid imu\r\n");
  ASSERT_TRUE(rig.pump_until_event(Kind::Reply));
  EXPECT_EQ(rig.last(Kind::Reply)->reply, "error No valid imu");
  EXPECT_EQ(rig.count(Kind::Refused), 0);
  EXPECT_FALSE(rig.driver->outstanding());
  rig.elapse(kSec);
  EXPECT_TRUE(rig.drone.nothing_sent());  // not re-sent by the driver
}

TEST(SdkDriver, RetriesARefusedLandAfterTheRefusalDelayUntilOk) {
  DriverConfig config;
  config.keepalive_ns = 0;
  Rig rig(config);
  ASSERT_TRUE(rig.driver->submit("land", {.retries = 3, .tag = 2, .urgent = true, .retry_unless_ok = true}));
  rig.service();
  EXPECT_EQ(rig.drone.expect_command(), "land");
  for (int refusal = 1; refusal <= 2; ++refusal) {
    rig.drone.reply(refusal == 1 ? "error Not joystick\r\n" : "error No valid imu\r\n");
    ASSERT_TRUE(rig.pump_until_event(Kind::Refused, refusal));
    EXPECT_EQ(rig.last(Kind::Refused)->attempt, refusal);
    EXPECT_EQ(rig.count(Kind::Reply), 0);
    // A duplicate of the refusal while waiting to re-send answers nothing: stale.
    rig.drone.reply("error Not joystick");
    ASSERT_TRUE(rig.pump_until_event(Kind::StaleReply, refusal));
    rig.elapse(config.refusal_retry_ns - 1);
    EXPECT_TRUE(rig.drone.nothing_sent());
    rig.elapse(1);
    EXPECT_EQ(rig.drone.expect_command(), "land");
    EXPECT_EQ(rig.last(Kind::Sent)->attempt, refusal + 1);
  }
  rig.drone.reply("ok");
  ASSERT_TRUE(rig.pump_until_event(Kind::Reply));
  EXPECT_EQ(rig.last(Kind::Reply)->reply, "ok");
  EXPECT_EQ(rig.last(Kind::Reply)->attempt, 3);
  EXPECT_EQ(rig.last(Kind::Reply)->tag, 2);
  EXPECT_EQ(rig.driver->counters().refusals, 2);
  EXPECT_EQ(rig.count(Kind::Failed), 0);
}

TEST(SdkDriver, GivesTheLastRefusalAsTheReplyWhenRetriesRunOut) {
  DriverConfig config;
  config.keepalive_ns = 0;
  Rig rig(config);
  ASSERT_TRUE(rig.driver->submit("land", {.retries = 2, .retry_unless_ok = true}));
  rig.service();
  for (int attempt = 1; attempt <= 3; ++attempt) {
    ASSERT_EQ(rig.drone.expect_command(), "land") << attempt;
    rig.drone.reply("error Not joystick");
    if (attempt < 3) {
      ASSERT_TRUE(rig.pump_until_event(Kind::Refused, attempt));
      rig.elapse(config.refusal_retry_ns);
    }
  }
  ASSERT_TRUE(rig.pump_until_event(Kind::Reply));
  EXPECT_EQ(rig.last(Kind::Reply)->reply, "error Not joystick");
  EXPECT_EQ(rig.last(Kind::Reply)->attempt, 3);
  EXPECT_FALSE(rig.driver->outstanding());
  // Nothing but the three lands went out, and nothing is refused as out of range.
  rig.elapse(10 * kSec);
  EXPECT_TRUE(rig.drone.nothing_sent());
  EXPECT_EQ(rig.driver->counters().rejected, 0);
  EXPECT_EQ(rig.driver->counters().commands_sent, 3);
}

}  // namespace
}  // namespace shelfcross::tello
