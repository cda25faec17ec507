// The Tello SDK emulator against a raw UDP client on loopback (tello::UdpSocket), in process.
// The test owns time: it calls advance() with simulated times of its own, so every assertion
// is about simulated time and datagram contents; wall-clock waits are only failure guards.

#include "verification/world/tello_emulator.hpp"

#include <gtest/gtest.h>

#include <cctype>
#include <memory>
#include <string>
#include <vector>

#include "flight_sw/tello/h264_decoder.hpp"
#include "sdk/state_record.hpp"
#include "sdk/video_framing.hpp"
#include "verification/scenario/senses_dispersion.hpp"
#include "verification/world/mission_setup.hpp"

namespace shelfcross::verification {
namespace {

using tello::Datagram;
using tello::Endpoint;
using tello::UdpSocket;


const Scenario& default_scenario() {
  static const Scenario s = load_scenario(std::string(SHELFCROSS_SOURCE_DIR) + "/" + kDefaultScenarioFile);
  return s;
}

// The default scenario in the world of the truth (every sense at the identity): readings without
// noise and a height hold that ignores the range, for the tests of what a reading measures.
const Scenario& truth_scenario() {
  static const Scenario s = without_senses(default_scenario());
  return s;
}

bool all_digits(const std::string& s) {
  return !s.empty() && std::all_of(s.begin(), s.end(), [](unsigned char c) { return std::isdigit(c); });
}

class TelloEmulatorTest : public ::testing::Test {
 protected:
  void start(EmulatorConfig c = {}, const Scenario& scenario = default_scenario()) {
    c.bind_ip = "127.0.0.1";
    c.command_port = 0;
    c.state_source_port = 0;
    c.video_source_port = 0;
    c.client_state_port = state_.local_port();
    c.client_video_port = video_.local_port();
    emu_ = std::make_unique<TelloEmulator>(scenario, c);
  }
  Endpoint drone() const { return {"127.0.0.1", emu_->ports().command}; }
  void send(const std::string& text, UdpSocket* from = nullptr) {
    ASSERT_TRUE((from ? *from : client_).send_to(drone(), text));
  }
  void step(TimeNs dt_ns) {
    t_ns_ += dt_ns;
    emu_->advance(t_ns_);
  }
  /// Advances in 10 ms steps for up to `within_ns` of simulated time until `socket` has a
  /// datagram; the simulated time it appeared at is t_ns_ afterwards.
  std::optional<Datagram> next(UdpSocket& socket, TimeNs within_ns) {
    const TimeNs end = t_ns_ + within_ns;
    for (;;) {
      if (auto d = socket.receive()) return d;
      if (t_ns_ >= end) break;
      step(10 * kMs);
    }
    // Loopback delivery is immediate in practice; a generous guard for a loaded machine.
    if (socket.wait_readable(1000)) return socket.receive();
    return std::nullopt;
  }
  std::string reply(TimeNs within_ns = 500 * kMs, UdpSocket* from = nullptr) {
    auto d = next(from ? *from : client_, within_ns);
    return d ? d->bytes : std::string("<none>");
  }
  void enter_sdk_mode() {
    send("command");
    ASSERT_EQ(reply(), "ok");
  }

  UdpSocket client_{"127.0.0.1", 0};
  UdpSocket state_{"127.0.0.1", 0};
  UdpSocket video_{"127.0.0.1", 0, 8 << 20};
  std::unique_ptr<TelloEmulator> emu_;
  TimeNs t_ns_ = 0;
};

// The SDK's order of things and the state record's layout and rate; in the world of the truth, so
// that `h` at rest reads 0 (the documented senses' noise moves it by a centimetre or two).
TEST_F(TelloEmulatorTest, NothingBeforeCommandThenOkAndStateRecordsAt10Hz) {
  start({}, truth_scenario());
  send("battery?");
  send("takeoff");
  step(500 * kMs);
  EXPECT_FALSE(client_.receive().has_value());
  EXPECT_FALSE(state_.receive().has_value()) << "state before `command`";
  send("command");
  EXPECT_EQ(reply(), "ok");  // the first reply at all: battery? and takeoff got none
  EXPECT_EQ(emu_->world().tello().mode(), plant::FlightMode::landed);

  // Two seconds of state: 20 records, SDK 2.0 layout, from the emulator's state port.
  std::vector<std::pair<TimeNs, std::string>> records;
  const TimeNs t_end = t_ns_ + 2000 * kMs;
  while (t_ns_ < t_end) {
    step(10 * kMs);
    while (auto d = state_.receive()) {
      EXPECT_EQ(d->from.port, emu_->ports().state_source);
      records.emplace_back(t_ns_, d->bytes);
    }
  }
  ASSERT_GE(records.size(), 19u);
  ASSERT_LE(records.size(), 21u);
  for (const auto& [t, text] : records) {
    EXPECT_EQ(text.rfind("mid:", 0), 0u) << text;
    EXPECT_EQ(text.substr(text.size() - 2), "\r\n") << text;
    sdk::StateParseReport rep;
    const auto parsed = sdk::parse_state_record(text, t, &rep);
    ASSERT_TRUE(parsed.has_value()) << text;
    EXPECT_TRUE(rep.mission_pad);
    EXPECT_EQ(rep.missing_keys, 0);
    EXPECT_NEAR(parsed->height_m, 0.0, 0.01);
    EXPECT_NEAR(parsed->az_B_mps2, 9.81, 0.2);  // at rest the IMU reads +1 g up
    EXPECT_EQ(parsed->battery_pct, 100);
  }
  for (std::size_t i = 1; i < records.size(); ++i) {
    EXPECT_NEAR(static_cast<double>(records[i].first - records[i - 1].first), 100e6, 10e6);  // simulated 10 Hz
  }
}

TEST_F(TelloEmulatorTest, RcIsNeverAnsweredReadsAndRangesAreTheTellos) {
  start();
  enter_sdk_mode();
  send("rc 0 0 0 0");
  send("rc 0 120 0 0");  // even out of range: no reply
  send("battery?");
  const std::string battery = reply();
  EXPECT_TRUE(all_digits(battery)) << battery;  // the first reply after the rcs is the battery's
  send("forward 10");
  EXPECT_EQ(reply(), "out of range");
  send("height?");
  EXPECT_EQ(reply(), "0dm");
  send("sdk?");
  EXPECT_EQ(reply(), "20");
  send("jump");
  EXPECT_EQ(reply().rfind("unknown command", 0), 0u);
  send("forward 50");  // a move while landed
  EXPECT_EQ(reply(), "error");
  EXPECT_FALSE(client_.receive().has_value());
}

TEST_F(TelloEmulatorTest, TakeoffAnswersWhenItEndsAndTheWatchdogLands) {
  start();
  enter_sdk_mode();
  const TimeNs t_sent = t_ns_;
  send("takeoff");
  const auto d = next(client_, 20'000 * kMs);
  ASSERT_TRUE(d.has_value());
  EXPECT_EQ(d->bytes, "ok");
  EXPECT_GE(t_ns_ - t_sent, 3000 * kMs) << "the takeoff reply came before the takeoff ended";
  EXPECT_EQ(emu_->world().tello().mode(), plant::FlightMode::flying);
  EXPECT_GT(emu_->world().tello().state().p_WB_m.z(), 0.7);
  // No command for 15 s: the drone lands by itself, and says nothing.
  const auto quiet = next(client_, 17'000 * kMs);
  EXPECT_FALSE(quiet.has_value()) << quiet->bytes;
  step(4000 * kMs);
  EXPECT_EQ(emu_->world().tello().mode(), plant::FlightMode::landed);
  const EmulatorReport r = emu_->report();
  EXPECT_TRUE(r.flew);
  EXPECT_TRUE(r.landed);
  EXPECT_GT(r.flight_time_s, 10.0);
  EXPECT_FALSE(r.truth.contact.has_value());
  EXPECT_FALSE(r.truth.crossed.has_value());
  EXPECT_EQ(r.inventory_truth, true_inventory(default_scenario()));
}

TEST_F(TelloEmulatorTest, RepliesGoToTheSendersAddressAndPort) {
  start();
  enter_sdk_mode();
  UdpSocket other("127.0.0.1", 0);
  send("battery?", &other);
  EXPECT_TRUE(all_digits(reply(500 * kMs, &other)));
  EXPECT_FALSE(client_.receive().has_value());
  send("sdk?");
  EXPECT_EQ(reply(), "20");
  EXPECT_FALSE(other.receive().has_value());
}

TEST_F(TelloEmulatorTest, MalformedDatagramsAreDroppedAndCounted) {
  start();
  send(std::string("\xff\xfe\x01", 3));
  send(std::string(300, 'a'));
  send("");
  send("command");
  EXPECT_EQ(reply(), "ok");  // the first reply: the malformed ones got none
  const EmulatorCounters c = emu_->report().counters;
  EXPECT_EQ(c.commands_received, 4);
  EXPECT_EQ(c.commands_malformed, 3);
  EXPECT_EQ(c.commands_delivered, 1);
}

TEST_F(TelloEmulatorTest, StreamonSendsH264InTelloDatagrams) {
  start();
  enter_sdk_mode();
  EXPECT_FALSE(video_.receive().has_value());
  send("streamon");
  EXPECT_EQ(reply(), "ok");
  // Frames: the datagrams up to the first short one that carries more than parameter sets.
  std::vector<std::vector<std::string>> frames(1);
  tello::H264Decoder decoder;
  int pictures = 0;
  const TimeNs frame_ns = kNsPerSecond / 30 + 1;
  const auto handed = [&] {
    const EmulatorCounters c = emu_->report().counters;
    return c.frames_captured - c.frames_dropped_busy - c.frames_dropped_late - c.frames_stalled - c.frames_lost;
  };
  for (int steps = 0; frames.size() <= 4; ++steps) {
    ASSERT_FALSE(emu_->finished()) << emu_->report().end_reason << ": " << emu_->report().detail;
    ASSERT_LT(steps, 600) << "fewer than 4 frames in 20 s of simulated time";
    const std::int64_t before = handed();
    step(frame_ns);
    if (handed() == before) continue;  // no capture handed to the worker in this step
    // The capture went to the worker; wait for its datagrams (guard: 30 s on a loaded machine).
    while (video_.wait_readable(30000)) {
      auto d = video_.receive();
      ASSERT_TRUE(d.has_value());
      EXPECT_EQ(d->from.port, emu_->ports().video_source);
      ASSERT_LE(d->bytes.size(), 1460u);
      frames.back().push_back(d->bytes);
      const std::vector<int> types = sdk::nal_unit_types(d->bytes);
      const bool parameter_sets_only =
          !types.empty() && std::all_of(types.begin(), types.end(), [](int t) { return t == 7 || t == 8 || t == 9; });
      if (d->bytes.size() < 1460 && !parameter_sets_only) {
        std::string au;
        for (const auto& piece : frames.back()) au += piece;
        pictures += decoder.decode(au).pictures;
        frames.emplace_back();
        break;
      }
    }
  }
  frames.pop_back();
  ASSERT_GE(frames.size(), 4u);
  for (std::size_t f = 0; f < frames.size(); ++f) {
    const auto& datagrams = frames[f];
    std::string au;
    for (const auto& d : datagrams) au += d;
    const std::vector<int> types = sdk::nal_unit_types(au);
    const auto idr = std::find(types.begin(), types.end(), 5);
    if (f == 0) {
      ASSERT_NE(idr, types.end()) << "the first frame after streamon is a key frame";
    }
    if (idr != types.end()) {
      // SPS and PPS first, each in a short datagram of its own, then the key frame.
      ASSERT_GE(datagrams.size(), 3u);
      EXPECT_EQ(sdk::nal_unit_types(datagrams[0]), std::vector<int>{7});
      EXPECT_EQ(sdk::nal_unit_types(datagrams[1]), std::vector<int>{8});
      EXPECT_LT(std::find(types.begin(), types.end(), 7), idr);
      EXPECT_LT(std::find(types.begin(), types.end(), 8), idr);
    }
    // Every datagram of the picture is 1460 bytes but the last, which is shorter.
    std::size_t first_picture = 0;
    while (first_picture < datagrams.size() && datagrams[first_picture].size() < 1460 &&
           first_picture + 1 < datagrams.size()) {
      ++first_picture;  // the short parameter-set datagrams
    }
    for (std::size_t i = first_picture; i + 1 < datagrams.size(); ++i) EXPECT_EQ(datagrams[i].size(), 1460u);
    EXPECT_LT(datagrams.back().size(), 1460u);
  }
  EXPECT_EQ(pictures, static_cast<int>(frames.size()));
  cv::Mat bgr;
  ASSERT_TRUE(decoder.latest_bgr(bgr));
  EXPECT_EQ(bgr.cols, 960);
  EXPECT_EQ(bgr.rows, 720);
  const EmulatorCounters c = emu_->report().counters;
  EXPECT_GE(c.frames_sent, static_cast<std::int64_t>(frames.size()));
  EXPECT_GE(c.key_frames, 1);
  EXPECT_EQ(c.video_datagrams_dropped, 0);
  send("streamoff");
  EXPECT_EQ(reply(), "ok");
}

TEST_F(TelloEmulatorTest, InjectedStateLossDropsTheExpectedFractionReproducibly) {
  const auto run = [&](std::uint64_t seed) {
    EmulatorConfig c;
    c.seed = seed;
    c.faults.state.loss = 0.3;
    t_ns_ = 0;
    start(c);
    enter_sdk_mode();
    std::int64_t received = 0;
    for (int i = 0; i < 3000; ++i) {  // 30 s
      step(10 * kMs);
      while (state_.receive()) ++received;
    }
    if (state_.wait_readable(200)) {
      while (state_.receive()) ++received;
    }
    const EmulatorCounters counters = emu_->report().counters;
    EXPECT_EQ(received, counters.state_sent);
    emu_.reset();
    return counters;
  };
  const EmulatorCounters a = run(7);
  const std::int64_t total = a.state_sent + a.state_dropped;
  EXPECT_NEAR(static_cast<double>(total), 300.0, 2.0);
  // Binomial(300, 0.3): 90 +- 7.9; 5 sigma.
  EXPECT_NEAR(static_cast<double>(a.state_dropped), 0.3 * static_cast<double>(total), 40.0);
  EXPECT_GT(a.state_dropped, 0);
  const EmulatorCounters b = run(7);  // the same seed and timeline: the same draws
  EXPECT_EQ(a.state_dropped, b.state_dropped);
  EXPECT_EQ(a.state_sent, b.state_sent);
}

TEST_F(TelloEmulatorTest, InjectedCommandLossAndReplyFaults) {
  EmulatorConfig c;
  c.faults.commands.loss = 0.5;
  start(c);
  int answered = 0;
  const int sent = 200;
  for (int i = 0; i < sent; ++i) {
    send("sdk?");
    step(10 * kMs);
    while (auto d = client_.receive()) ++answered;
  }
  // Until a `command` got through nothing is answered; count what the emulator saw.
  const EmulatorCounters k = emu_->report().counters;
  EXPECT_EQ(k.commands_received, sent);
  EXPECT_NEAR(static_cast<double>(k.commands_dropped), 0.5 * sent, 5 * std::sqrt(0.25 * sent));
  EXPECT_EQ(answered, 0);  // no `command` yet
  emu_.reset();

  // Forced refusals and duplicated replies.
  EmulatorConfig f;
  f.faults.not_joystick = 1.0;
  f.faults.replies.duplicate = 1.0;
  t_ns_ = 0;
  start(f);
  send("command");
  EXPECT_EQ(reply(), "ok");
  EXPECT_EQ(reply(), "ok");  // its duplicate
  send("takeoff");
  EXPECT_EQ(reply(), "error Not joystick");
  EXPECT_EQ(reply(), "error Not joystick");
  step(1000 * kMs);
  EXPECT_EQ(emu_->world().tello().mode(), plant::FlightMode::landed);
  emu_.reset();

  EmulatorConfig g;
  g.faults.no_valid_imu = 1.0;
  g.faults.replies.delay_ms = 300;
  t_ns_ = 0;
  start(g);
  send("command");
  const TimeNs t_sent = t_ns_;
  EXPECT_EQ(reply(), "ok");
  EXPECT_GE(t_ns_ - t_sent, 300 * kMs);
  send("takeoff");
  EXPECT_EQ(reply(), "error No valid imu");
  EXPECT_EQ(emu_->report().counters.injected_errors, 1);
}

// A refused manoeuvre ("error Not joystick") is still a command the drone received: it
// counts for the 15 s no-command watchdog, as any command does (docs/tello_sdk.md). Refusals are
// drawn (seeded, p = 0.9): the first seed of 1..10 whose draws give a takeoff and then more
// than 15 s of nothing but refused commands is flown to the end.
TEST_F(TelloEmulatorTest, RefusedCommandsCountForTheWatchdog) {
  bool window = false;
  for (std::uint64_t seed = 1; seed <= 10 && !window; ++seed) {
    EmulatorConfig c;
    c.seed = seed;
    c.faults.not_joystick = 0.9;
    t_ns_ = 0;
    start(c);
    enter_sdk_mode();
    for (int attempt = 0; attempt < 200 && emu_->world().tello().mode() == plant::FlightMode::landed; ++attempt) {
      send("takeoff");
      if (reply(20'000 * kMs) == "ok") break;
      step(200 * kMs);
    }
    ASSERT_EQ(emu_->world().tello().mode(), plant::FlightMode::flying);
    TimeNs last_accepted_ns = t_ns_;
    for (int k = 0; k < 8; ++k) {
      step(2500 * kMs);
      send("cw 1");
      const std::string r = reply(5000 * kMs);
      if (r == "ok") {
        last_accepted_ns = t_ns_;
      } else {
        EXPECT_EQ(r, "error Not joystick");
      }
    }
    step(1000 * kMs);
    window = t_ns_ - last_accepted_ns >= 15'000 * kMs;
    if (window) {
      EXPECT_EQ(emu_->world().tello().mode(), plant::FlightMode::flying) << "the watchdog landed a drone that was commanded";
      // Then silence: the watchdog lands it.
      step(17'000 * kMs);
      EXPECT_EQ(emu_->world().tello().mode(), plant::FlightMode::landed);
    }
    emu_.reset();
  }
  EXPECT_TRUE(window) << "no seed of 1..10 gave 15 s of refusals only";
}

TEST(TelloEmulatorConfig, BadSettingsAreRefused) {
  EmulatorConfig c;
  c.faults.video.loss = 1.5;
  EXPECT_THROW(validate_emulator_config(c), std::invalid_argument);
  c = {};
  c.faults.replies.delay_ms = -1;
  EXPECT_THROW(validate_emulator_config(c), std::invalid_argument);
  c = {};
  c.faults.video_stall_start_s = 2.0;
  c.faults.video_stall_duration_s = 0.0;
  EXPECT_THROW(validate_emulator_config(c), std::invalid_argument);
  c = {};
  c.bind_ip = "localhost:1";
  EXPECT_THROW(validate_emulator_config(c), std::invalid_argument);
  c = {};
  c.slices_per_frame = 0;
  EXPECT_THROW(validate_emulator_config(c), std::invalid_argument);
  c.slices_per_frame = 46;
  EXPECT_THROW(validate_emulator_config(c), std::invalid_argument);
  EXPECT_NO_THROW(validate_emulator_config(EmulatorConfig{}));
}

// The range sensor reads the surface below, not the floor: over the floor in front of the shelf
// `tof?` and the state record read the height; inside the empty cell (level 2, column 2), above
// the box of cell (1, 2), both read the distance to the box's top. The record's `h`, the fused
// height a client reads (djitellopy's get_height()), does not step with the range: in the world
// of the truth the height hold ignores the range reading (the documented senses' blend follows it
// by half, and their noise would blur the centimetres checked here).
TEST_F(TelloEmulatorTest, TofReadsTheBoxTopFromInsideTheShelf) {
  start({}, truth_scenario());
  enter_sdk_mode();
  send("takeoff");
  ASSERT_EQ(reply(20'000 * kMs), "ok");
  for (const char* m : {"down 20", "left 24"}) {  // level 2 (0.64 to 0.98 m), the centre of column 2 (0.24 m)
    send(m);
    ASSERT_EQ(reply(20'000 * kMs), "ok") << m;
  }
  const auto tof_reply_m = [&] {
    send("tof?");
    const std::string r = reply();
    EXPECT_EQ(r.substr(r.size() - 2), "mm") << r;
    return std::stoi(r.substr(0, r.size() - 2)) / 1000.0;
  };
  const auto record = [&] {
    while (state_.receive()) {
    }
    const auto d = next(state_, 500 * kMs);
    EXPECT_TRUE(d.has_value());
    const auto r = d ? sdk::parse_state_record(d->bytes, t_ns_) : std::nullopt;
    EXPECT_TRUE(r && r->tof_m);
    return r && r->tof_m ? *r : StateRecord{};
  };
  const double rest_m = 0.5 * default_scenario().vehicle.size_m.z();
  const auto belly_m = [&] { return emu_->world().tello().state().p_WB_m.z() - rest_m; };
  EXPECT_NEAR(tof_reply_m(), 0.1 + belly_m(), 0.002);
  const StateRecord outside = record();
  EXPECT_NEAR(*outside.tof_m, 0.1 + belly_m(), 0.006);  // whole centimetres
  EXPECT_NEAR(outside.height_m, belly_m(), 0.011);     // h from the take-off height, whole cm
  send("forward 317");  // to the middle of the shelf's depth
  ASSERT_EQ(reply(20'000 * kMs), "ok");
  const double box_top_m = 0.30 + 0.01 + default_scenario().warehouse.box_size_m.z();
  EXPECT_NEAR(tof_reply_m(), 0.1 + belly_m() - box_top_m, 0.002);
  const StateRecord inside = record();
  EXPECT_NEAR(*inside.tof_m, 0.1 + belly_m() - box_top_m, 0.006);
  EXPECT_NEAR(inside.height_m, belly_m(), 0.011);
  EXPECT_FALSE(emu_->report().truth.contact.has_value());
}

}  // namespace
}  // namespace shelfcross::verification
