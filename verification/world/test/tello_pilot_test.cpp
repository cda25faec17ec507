// tello_pilot as a child process against a scripted fake Tello on loopback: real UDP, real
// H.264, the real flight software. The fake drone is stepped by the test (no thread); waits
// are bounded by counts of short poll() waits, never by reading a clock.
#include <signal.h>

#include <gtest/gtest.h>

#include <filesystem>
#include <functional>
#include <fstream>

#include <nlohmann/json.hpp>
#include <opencv2/aruco.hpp>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>

#include "flight_sw/tello/test/loopback.hpp"
#include "sdk/command.hpp"
#include "sdk/video_framing.hpp"
// The drone's side, to make a Tello-like stream (tests may link verification/; the program not).
#include "verification/world/h264_encoder.hpp"
#include "verification/world/test/tello_pilot_child.hpp"

namespace shelfcross::tello {
namespace {

namespace fs = std::filesystem;
using testing::Child;
using testing::kConfig;
using testing::pause_ms;
using testing::read_file;
using testing::run_to_exit;
using testing::temp_dir;

constexpr const char* kState =
    "mid:-1;x:-100;y:-100;z:-100;mpry:-1,-1,-1;pitch:0;roll:0;yaw:0;vgx:0;vgy:0;vgz:0;templ:55;temph:57;"
    "tof:80;h:80;bat:83;baro:118.26;time:3;agx:-4.00;agy:1.00;agz:-997.00;\r\n";

// The flight log's lines of one type whose `key` equals `value` (empty key: all of the type).
int log_lines(const fs::path& log, const std::string& type, const std::string& key = "",
              const std::string& value = "") {
  std::ifstream in(log);
  std::string line;
  int n = 0;
  while (std::getline(in, line)) {
    const auto j = nlohmann::json::parse(line, nullptr, false);
    if (j.is_discarded() || !j.contains("t_s") || !j.contains("t_ns")) continue;
    if (j.value("type", "") != type) continue;
    if (key.empty() || (j.contains(key) && j[key].is_string() && j[key] == value)) ++n;
  }
  return n;
}

std::uint16_t free_port() {
  UdpSocket s("127.0.0.1", 0);
  return s.local_port();
}

// A fake Tello: answers "ok" to every non-rc command (unless told to stay silent), pushes
// state records and a 960 x 720 H.264 stream once `streamon` came, records all it receives.
struct FakeTello {
  UdpSocket command{"127.0.0.1", 0};
  UdpSocket state{"127.0.0.1", 0};
  UdpSocket video{"127.0.0.1", 0};
  std::uint16_t pilot_state_port = free_port();
  std::uint16_t pilot_video_port = free_port();
  verification::H264Encoder encoder{960, 720, 30, 10};
  std::vector<std::string> received;
  /// The reply to a non-rc command ("ok" unless a test scripts refusals).
  std::function<std::string(const std::string&)> answer = [](const std::string&) { return std::string("ok"); };
  bool streaming = false;
  bool send_state = true;
  std::string state_text = kState;
  int frame = 0;
  std::function<cv::Mat(int)> picture = [](int k) {
    cv::Mat img(720, 960, CV_8UC3, cv::Scalar(90, 90, 90));
    cv::circle(img, cv::Point(100 + 5 * (k % 100), 300), 50, cv::Scalar(255, 255, 255), cv::FILLED);
    return img;
  };

  std::vector<std::string> args(const fs::path& dir) const {
    return {"--config", kConfig, "--drone-ip", "127.0.0.1", "--local-ip", "127.0.0.1",
            "--command-port", std::to_string(command.local_port()),
            "--state-port", std::to_string(pilot_state_port), "--video-port", std::to_string(pilot_video_port),
            "--state-source-port", std::to_string(state.local_port()),
            "--video-source-port", std::to_string(video.local_port()),
            "--log", (dir / "log.jsonl").string(), "--inventory", (dir / "inventory.json").string()};
  }
  /// One step: answer commands (waiting up to 10 ms for one), push a state record and a frame.
  void step() {
    if (command.wait_readable(10)) {
      while (auto d = command.receive()) {
        received.push_back(d->bytes);
        if (d->bytes.rfind("rc ", 0) != 0) command.send_to(d->from, answer(d->bytes) + "\r\n");
        if (d->bytes == "streamon") streaming = true;
      }
    }
    if (send_state) state.send_to({"127.0.0.1", pilot_state_port}, state_text);
    if (streaming) {
      for (const auto& d : sdk::tello_datagrams(encoder.encode(picture(frame)))) video.send_to({"127.0.0.1", pilot_video_port}, d);
      ++frame;
    }
  }
  bool got(const std::string& c) const { return std::find(received.begin(), received.end(), c) != received.end(); }
  /// Steps until `c` was received; the guard is a count of steps.
  bool step_until(const std::string& c, int guard = 1500) {
    for (int i = 0; i < guard && !got(c); ++i) step();
    return got(c);
  }
  size_t index_of(const std::string& c) const {
    return static_cast<size_t>(std::find(received.begin(), received.end(), c) - received.begin());
  }
  int count(const std::string& c) const { return static_cast<int>(std::count(received.begin(), received.end(), c)); }
  /// Every datagram received is a valid SDK command within its ranges.
  void expect_all_valid() const {
    for (const auto& c : received) {
      std::string why;
      EXPECT_TRUE(sdk::classify_command(c, &why)) << "'" << c << "': " << why;
    }
  }
};

TEST(TelloPilot, BadCommandLineOrConfigExitsWith2) {
  const fs::path dir = temp_dir("bad");
  std::string err;
  EXPECT_EQ(run_to_exit({"--bogus"}, &err), 2);
  EXPECT_NE(err.find("tello_pilot:"), std::string::npos);
  EXPECT_EQ(run_to_exit({}, &err), 2);  // no flight configuration
  EXPECT_NE(err.find("--config"), std::string::npos);
  EXPECT_EQ(run_to_exit({"--config", (dir / "missing.yaml").string()}, &err), 2);
  std::ofstream(dir / "bad.yaml") << "shelf:\n  column_pitch_m: [0.3]\n  row_pitch_m: [0.3]\n  colour: red\n";
  EXPECT_EQ(run_to_exit({"--config", (dir / "bad.yaml").string()}, &err), 2);
  EXPECT_NE(err.find("bad.yaml:4"), std::string::npos) << err;
  EXPECT_EQ(run_to_exit({"--config", kConfig, "--drone-ip", "192.168.10"}, &err), 2);
  EXPECT_EQ(run_to_exit({"--config", kConfig, "--command-port", "70000"}, &err), 2);
  std::ofstream(dir / "calib.yml") << "%YAML:1.0\n---\nimage_width: 960\nimage_height: 720\n";
  EXPECT_EQ(run_to_exit({"--config", kConfig, "--calibration", (dir / "calib.yml").string()}, &err), 2);
  EXPECT_NE(err.find("camera_matrix"), std::string::npos) << err;
  std::ofstream(dir / "pilot.yaml") << "link:\n  drone_ip: 127.0.0.1\n  speed: 3\n";
  EXPECT_EQ(run_to_exit({"--config", kConfig, "--pilot", (dir / "pilot.yaml").string()}, &err), 2);
  EXPECT_NE(err.find("pilot.yaml:3"), std::string::npos) << err;
  EXPECT_EQ(run_to_exit({"--config", kConfig, "--log", (dir / "no" / "such" / "dir.jsonl").string()}, &err), 2);
  EXPECT_EQ(run_to_exit({"--config", kConfig, "--senses-board", "1.5"}, &err), 2);  // a part of --fly-calibration
  EXPECT_NE(err.find("--fly-calibration"), std::string::npos) << err;
  EXPECT_EQ(run_to_exit({"--config", kConfig, "--fly-calibration", "--senses-board", "3"}, &err), 2);  // 1.0..2.5 m
  EXPECT_NE(err.find("--senses-board"), std::string::npos) << err;
  EXPECT_EQ(run_to_exit({"--config", kConfig, "--damaged-video", "blurry"}, &err), 2);
  EXPECT_NE(err.find("--damaged-video"), std::string::npos) << err;
  std::ofstream(dir / "video.yaml") << "video:\n  damaged_frames: conceal\n  damage_limit: 3\n";
  EXPECT_EQ(run_to_exit({"--config", kConfig, "--pilot", (dir / "video.yaml").string()}, &err), 2);
  EXPECT_NE(err.find("video.yaml:3"), std::string::npos) << err;
  EXPECT_NE(err.find("damage_limit"), std::string::npos) << err;
  EXPECT_EQ(run_to_exit({"--config", kConfig, "--mission-budget", "0"}, &err), 2);
  EXPECT_NE(err.find("--mission-budget"), std::string::npos) << err;
  // The link's ride-through bound: at most the Tello's watchdog less the keep-alive (10 s), and
  // not shorter than the state timeout that starts it.
  EXPECT_EQ(run_to_exit({"--config", kConfig, "--link-outage", "12"}, &err), 2);
  EXPECT_NE(err.find("--link-outage"), std::string::npos) << err;
  EXPECT_EQ(run_to_exit({"--config", kConfig, "--state-timeout", "3", "--link-outage", "2"}, &err), 2);
  EXPECT_NE(err.find("--link-outage must not be shorter than --state-timeout"), std::string::npos) << err;
  std::ofstream(dir / "outage.yaml") << "failsafes:\n  state_timeout_s: 2.0\n  link_outage_s: 15.0\n";
  EXPECT_EQ(run_to_exit({"--config", kConfig, "--pilot", (dir / "outage.yaml").string()}, &err), 2);
  EXPECT_NE(err.find("outage.yaml:3"), std::string::npos) << err;
  EXPECT_NE(err.find("link_outage_s"), std::string::npos) << err;
  std::ofstream(dir / "short.yaml") << "failsafes:\n  state_timeout_s: 4.0\n  link_outage_s: 3.0\n";
  EXPECT_EQ(run_to_exit({"--config", kConfig, "--pilot", (dir / "short.yaml").string()}, &err), 2);
  EXPECT_NE(err.find("must not be shorter than state_timeout_s"), std::string::npos) << err;
  if (!HasFailure()) fs::remove_all(dir);
}

// The mission's budget (--mission-budget, replacing the configuration's timeouts.mission_s)
// spent while the flight software searches for a shelf that is not in view: it lands on its
// own and the program ends with the flight software's named outcome (aborted: exit 1), before
// any program failsafe.
TEST(TelloPilot, MissionBudgetSpentLandsWithItsOutcome) {
  const fs::path dir = temp_dir("budget");
  FakeTello drone;
  auto args = drone.args(dir);
  args.insert(args.end(), {"--mission-budget", "3"});
  Child pilot(args, dir);
  ASSERT_TRUE(drone.step_until("takeoff")) << read_file(pilot.err);
  ASSERT_TRUE(drone.step_until("land", 20000)) << read_file(pilot.err);
  for (int i = 0; i < 500 && !pilot.poll_exit(); ++i) drone.step();
  EXPECT_EQ(pilot.exit_code, 1) << read_file(pilot.err);
  const fs::path log = dir / "log.jsonl";
  EXPECT_EQ(log_lines(log, "end", "reason", "mission time limit reached"), 1) << read_file(log);
  EXPECT_EQ(log_lines(log, "end", "outcome", "aborted"), 1);
  EXPECT_EQ(log_lines(log, "failsafe"), 0) << "the flight software ended it, not a program failsafe";
  drone.expect_all_valid();
  if (!HasFailure()) fs::remove_all(dir);
}

TEST(TelloPilot, SignalLandsAndExits) {
  const fs::path dir = temp_dir("signal");
  FakeTello drone;
  Child pilot(drone.args(dir), dir);
  ASSERT_TRUE(drone.step_until("takeoff")) << read_file(pilot.err);
  for (int i = 0; i < 20; ++i) drone.step();  // flying: the flight software steers
  ASSERT_FALSE(pilot.poll_exit());
  ::kill(pilot.pid, SIGTERM);
  ASSERT_TRUE(drone.step_until("land"));
  for (int i = 0; i < 500 && !pilot.poll_exit(); ++i) drone.step();
  EXPECT_EQ(pilot.exit_code, 0) << read_file(pilot.err);
  // Nothing but land after land; no motion command after the signal's land.
  for (size_t i = drone.index_of("land") + 1; i < drone.received.size(); ++i) {
    EXPECT_EQ(drone.received[i].rfind("rc", 0), std::string::npos) << drone.received[i];
  }
  const fs::path log = dir / "log.jsonl";
  EXPECT_EQ(log_lines(log, "failsafe", "reason", "stopped by a signal"), 1);
  EXPECT_GT(log_lines(log, "frame"), 0);
  EXPECT_GT(log_lines(log, "state"), 0);
  EXPECT_EQ(log_lines(log, "sent", "command", "takeoff"), 1);
  EXPECT_EQ(log_lines(log, "reply", "command", "land"), 1);
  EXPECT_EQ(log_lines(log, "end"), 1);
  // Twenty steps of flight drive no axis for the 30 windows an estimate needs.
  EXPECT_EQ(log_lines(log, "end", "fsw_sticks", "horizontal not measured; vertical not measured; yaw not measured"), 1);
  EXPECT_TRUE(fs::exists(dir / "inventory.json"));
  if (!HasFailure()) fs::remove_all(dir);
}

// The state records stop in the air: after --state-timeout the link is out and the program
// hovers (its rc 0 0 0 0, the flight software's sticks withheld); after --link-outage it lands.
TEST(TelloPilot, NoStateWhileAirborneHoversThenLands) {
  const fs::path dir = temp_dir("nostate");
  FakeTello drone;
  auto args = drone.args(dir);
  args.insert(args.end(), {"--state-timeout", "0.5", "--link-outage", "1.5"});
  Child pilot(args, dir);
  ASSERT_TRUE(drone.step_until("takeoff")) << read_file(pilot.err);
  drone.send_state = false;
  ASSERT_TRUE(drone.step_until("land"));
  for (int i = 0; i < 500 && !pilot.poll_exit(); ++i) drone.step();
  EXPECT_EQ(pilot.exit_code, 1);
  const fs::path log = dir / "log.jsonl";
  EXPECT_EQ(log_lines(log, "failsafe", "event", "link lost: hovering"), 1) << read_file(log);
  EXPECT_GT(log_lines(log, "fsw_command_ignored", "why", "program failsafe hover: link out"), 0);
  EXPECT_EQ(log_lines(log, "failsafe", "reason", "no state record for 1.5 s: the link is lost"), 1);
  const size_t land = drone.index_of("land");
  ASSERT_GT(land, 0u);
  EXPECT_EQ(drone.received[land - 1], "rc 0 0 0 0") << "hovering when the land went";
  if (!HasFailure()) fs::remove_all(dir);
}

TEST(TelloPilot, DryRunNeverSendsAMotionCommand) {
  const fs::path dir = temp_dir("dry");
  FakeTello drone;
  auto args = drone.args(dir);
  args.push_back("--dry-run");
  Child pilot(args, dir);
  ASSERT_TRUE(drone.step_until("streamon")) << read_file(pilot.err);
  const fs::path log = dir / "log.jsonl";
  // Run until the flight software has asked for a takeoff (and been filtered).
  bool filtered = false;
  for (int i = 0; i < 1500 && !filtered; ++i) {
    drone.step();
    if (i % 20 == 0) filtered = log_lines(log, "filtered", "command", "takeoff") == 1;
  }
  EXPECT_TRUE(filtered);
  for (int i = 0; i < 50; ++i) drone.step();
  ::kill(pilot.pid, SIGINT);
  for (int i = 0; i < 500 && !pilot.poll_exit(); ++i) drone.step();
  EXPECT_EQ(pilot.exit_code, 130);
  for (const auto& c : drone.received) {
    EXPECT_TRUE(c == "command" || c == "streamon") << "sent in a dry run: " << c;
  }
  EXPECT_GT(log_lines(log, "filtered"), 1);  // the flight software's rc too, logged, not sent
  EXPECT_GT(log_lines(log, "frame"), 0);
  if (!HasFailure()) fs::remove_all(dir);
}

}  // namespace
}  // namespace shelfcross::tello

namespace shelfcross::tello {
namespace {

// A 9 x 6 inner-corner chessboard of 25 mm squares seen by a pinhole camera (fx = fy = 920,
// cx = 480, cy = 360, no distortion) from pose `p`: the image is the board warped by the
// plane homography H = K [r1 r2 t] A (A: board-image pixels to board-plane metres, origin at
// the first inner corner).
cv::Mat chessboard_view(int p) {
  static const cv::Mat board = [] {
    cv::Mat b(900, 1200, CV_8UC3, cv::Scalar(255, 255, 255));  // 4 px/mm, 25 mm white margin
    for (int j = 0; j < 7; ++j) {
      for (int i = 0; i < 10; ++i) {
        if ((i + j) % 2 == 0) b(cv::Rect(100 + 100 * i, 100 + 100 * j, 100, 100)).setTo(cv::Scalar(0, 0, 0));
      }
    }
    return b;
  }();
  const cv::Matx33d K(920, 0, 480, 0, 920, 360, 0, 0, 1);
  const cv::Matx33d A(1 / 4000.0, 0, -0.05, 0, 1 / 4000.0, -0.05, 0, 0, 1);
  const double rx[] = {0.0, 0.35, -0.3, 0.1, -0.2, 0.3, 0.0, -0.35};
  const double ry[] = {0.0, 0.1, 0.3, -0.35, -0.2, 0.25, 0.4, -0.1};
  const double rz[] = {0.0, 0.1, -0.1, 0.2, 0.0, -0.15, 0.05, 0.1};
  const int k = p % 8;
  cv::Matx33d R;
  cv::Rodrigues(cv::Vec3d(rx[k], ry[k], rz[k]), R);
  const cv::Vec3d centre(0.1, 0.0625, 0.0);  // the board's middle in its plane
  const cv::Vec3d t = cv::Vec3d(0.04 * (k % 3 - 1), 0.03 * (k % 2), 0.55 + 0.05 * (k % 3)) - R * centre;
  const cv::Matx33d M(R(0, 0), R(0, 1), t[0], R(1, 0), R(1, 1), t[1], R(2, 0), R(2, 1), t[2]);
  cv::Mat view;
  cv::warpPerspective(board, view, cv::Mat(K * M * A), cv::Size(960, 720), cv::INTER_LINEAR,
                      cv::BORDER_CONSTANT, cv::Scalar(200, 200, 200));
  return view;
}

TEST(TelloPilot, CalibrationModeRecoversTheIntrinsicsWithoutMotion) {
  const fs::path dir = temp_dir("calibrate");
  FakeTello drone;
  drone.picture = [](int k) { return chessboard_view(k / 15); };  // a new pose every 15 frames
  auto args = drone.args(dir);
  const fs::path out = dir / "camera.yml";
  args.insert(args.end(), {"--calibrate", out.string(), "--board", "9x6", "--square", "0.025", "--views", "8"});
  Child pilot(args, dir);
  for (int i = 0; i < 3000 && !pilot.poll_exit(); ++i) drone.step();
  ASSERT_EQ(pilot.exit_code, 0) << read_file(pilot.err) << read_file(pilot.out);
  for (const auto& c : drone.received) {
    EXPECT_TRUE(c == "command" || c == "streamon" || c == "streamoff") << "sent while calibrating: " << c;
  }
  // The written file is what --calibration reads.
  cv::FileStorage fs(out.string(), cv::FileStorage::READ);
  cv::Mat K;
  fs["camera_matrix"] >> K;
  ASSERT_EQ(K.rows, 3);
  EXPECT_NEAR(K.at<double>(0, 0), 920.0, 920.0 * 0.02);
  EXPECT_NEAR(K.at<double>(1, 1), 920.0, 920.0 * 0.02);
  EXPECT_NEAR(K.at<double>(0, 2), 480.0, 15.0);
  EXPECT_NEAR(K.at<double>(1, 2), 360.0, 15.0);
  std::string err;
  // tello_pilot accepts the file as --calibration (print mode: it exits after loading).
  EXPECT_EQ(run_to_exit({"--config", kConfig, "--calibration", out.string(), "--print-markers",
                         (dir / "sheets").string(), "--marker-ids", "0-0"}, &err), 0) << err;
  if (!HasFailure()) fs::remove_all(dir);
}

}  // namespace
}  // namespace shelfcross::tello

namespace shelfcross::tello {
namespace {

TEST(TelloPilot, VideoStallHoversThenLands) {
  const fs::path dir = temp_dir("stall");
  FakeTello drone;
  auto args = drone.args(dir);
  // Wide enough that a loaded machine's scheduling gaps in the live stream are no stall (at
  // 0.3 s the pilot hovered 3 times under a load average of 8 in a clean-clone CI run).
  args.insert(args.end(), {"--video-hover", "0.6", "--video-land", "1.5"});
  Child pilot(args, dir);
  ASSERT_TRUE(drone.step_until("takeoff")) << read_file(pilot.err);
  for (int i = 0; i < 10; ++i) drone.step();
  drone.streaming = false;  // the video stalls; state goes on
  ASSERT_TRUE(drone.step_until("land"));
  for (int i = 0; i < 500 && !pilot.poll_exit(); ++i) drone.step();
  EXPECT_EQ(pilot.exit_code, 1);
  const fs::path log = dir / "log.jsonl";
  EXPECT_EQ(log_lines(log, "failsafe", "event", "video stalled: hovering"), 1);
  EXPECT_EQ(log_lines(log, "failsafe", "reason", "no video frame for 1.500000 s"), 1);
  // Between the stall and the land the sticks were zero.
  const size_t land = drone.index_of("land");
  ASSERT_GT(land, 0u);
  EXPECT_EQ(drone.received[land - 1], "rc 0 0 0 0");
  if (!HasFailure()) fs::remove_all(dir);
}

}  // namespace
}  // namespace shelfcross::tello

namespace shelfcross::tello {
namespace {

// "error No valid imu" (a real Tello in dim light) to every takeoff: the flight software
// asks again (its command_retries, 3), then gives up on the ground. The drone never left the
// ground, so the program sends no land, and exits 1.
TEST(TelloPilot, RefusedTakeoffIsRetriedThenGivesUpOnTheGround) {
  const fs::path dir = temp_dir("refused_takeoff");
  FakeTello drone;
  drone.answer = [](const std::string& c) { return std::string(c == "takeoff" ? "error No valid imu" : "ok"); };
  drone.state_text = "mid:-1;x:-100;y:-100;z:-100;mpry:-1,-1,-1;pitch:0;roll:0;yaw:0;vgx:0;vgy:0;vgz:0;templ:55;"
                     "temph:57;tof:10;h:0;bat:83;baro:118.26;time:0;agx:-4.00;agy:1.00;agz:-997.00;\r\n";
  Child pilot(drone.args(dir), dir);
  ASSERT_TRUE(drone.step_until("takeoff")) << read_file(pilot.err);
  for (int i = 0; i < 1500 && !pilot.poll_exit(); ++i) drone.step();
  EXPECT_EQ(pilot.exit_code, 1) << read_file(pilot.out);
  EXPECT_EQ(drone.count("takeoff"), 4);
  EXPECT_EQ(drone.count("land"), 0);
  drone.expect_all_valid();
  const fs::path log = dir / "log.jsonl";
  EXPECT_EQ(log_lines(log, "reply", "reply", "error No valid imu"), 4);
  EXPECT_EQ(log_lines(log, "rejected"), 0);
  EXPECT_NE(read_file(pilot.out).find("takeoff failed: error No valid imu"), std::string::npos) << read_file(pilot.out);
  if (!HasFailure()) fs::remove_all(dir);
}

// "error Not joystick" to the program's own land (Ctrl-C): it asks again every 0.5 s until
// the drone accepts, and exits 0 once landed; nothing but land goes out meanwhile.
TEST(TelloPilot, RefusedLandIsAskedAgainUntilAccepted) {
  const fs::path dir = temp_dir("refused_land");
  FakeTello drone;
  int lands = 0;
  drone.answer = [&](const std::string& c) {
    if (c == "land" && ++lands <= 2) return std::string("error Not joystick");
    return std::string("ok");
  };
  Child pilot(drone.args(dir), dir);
  ASSERT_TRUE(drone.step_until("takeoff")) << read_file(pilot.err);
  for (int i = 0; i < 20; ++i) drone.step();
  ::kill(pilot.pid, SIGINT);
  for (int i = 0; i < 1500 && !pilot.poll_exit(); ++i) drone.step();
  EXPECT_EQ(pilot.exit_code, 0) << read_file(pilot.err);
  EXPECT_EQ(drone.count("land"), 3);
  for (size_t i = drone.index_of("land"); i < drone.received.size(); ++i) {
    EXPECT_TRUE(drone.received[i] == "land" || drone.received[i] == "rc 0 0 0 0") << drone.received[i];
  }
  drone.expect_all_valid();
  const fs::path log = dir / "log.jsonl";
  EXPECT_EQ(log_lines(log, "refused", "reply", "error Not joystick"), 2);
  EXPECT_EQ(log_lines(log, "reply", "command", "land"), 1);
  if (!HasFailure()) fs::remove_all(dir);
}

}  // namespace
}  // namespace shelfcross::tello
