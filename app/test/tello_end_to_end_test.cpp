// End to end on loopback: the real `tello_pilot` flies `shelfcross tello-sim` (the default
// scenario, nominal world), in real time, as it would fly a Tello. Each flight takes half a
// minute to a minute of wall time, so each case flies once: the calibration manoeuvre, a clean
// link, 5 % datagram loss on every channel (its second seed is flown by the co-simulation over
// the same pilot loop, SdkLink.FivePercentLossOnEveryChannelNeverTouchesAndListsNothingWrong). Ports are
// ephemeral ones found free, so these tests may run beside others. Wall-clock waits are
// failure guards only; every assertion is about what happened.

#include <gtest/gtest.h>

#include "run_shelfcross.hpp"

#include <arpa/inet.h>
#include <netinet/in.h>
#include <signal.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>
#include <string>
#include <thread>
#include <tuple>
#include <vector>

#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>
#include <opencv2/videoio.hpp>

namespace {

namespace fs = std::filesystem;
using nlohmann::json;

/// `count` distinct UDP ports free on 127.0.0.1 right now (bound together, then released).
std::vector<int> free_udp_ports(int count) {
  std::vector<int> fds, ports;
  for (int i = 0; i < count; ++i) {
    const int fd = ::socket(AF_INET, SOCK_DGRAM, 0);
    sockaddr_in a{};
    a.sin_family = AF_INET;
    a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    a.sin_port = 0;
    EXPECT_EQ(::bind(fd, reinterpret_cast<sockaddr*>(&a), sizeof a), 0);
    socklen_t len = sizeof a;
    ::getsockname(fd, reinterpret_cast<sockaddr*>(&a), &len);
    fds.push_back(fd);
    ports.push_back(ntohs(a.sin_port));
  }
  for (int fd : fds) ::close(fd);
  return ports;
}

/// A child process with stdout and stderr to a file.
struct Child {
  pid_t pid = -1;
  Child(const std::vector<std::string>& argv, const fs::path& output) {
    pid = ::fork();
    if (pid == 0) {
      std::FILE* f = std::freopen(output.c_str(), "w", stdout);
      if (f) ::dup2(::fileno(stdout), 2);
      std::vector<char*> args;
      for (const auto& a : argv) args.push_back(const_cast<char*>(a.c_str()));
      args.push_back(nullptr);
      ::execv(args[0], args.data());
      std::_Exit(127);
    }
  }
  /// Exit code, or -1 if it had to be killed after `guard`.
  int wait(std::chrono::seconds guard) {
    const auto end = std::chrono::steady_clock::now() + guard;
    int status = 0;
    while (::waitpid(pid, &status, WNOHANG) == 0) {
      if (std::chrono::steady_clock::now() > end) {
        ::kill(pid, SIGKILL);
        ::waitpid(pid, &status, 0);
        return -1;
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(100));
    }
    return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  }
};

std::string read_file(const fs::path& p) {
  std::ifstream in(p);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

using Entry = std::tuple<int, int, int, int>;  // id, shelf, level, column

std::set<Entry> boxes(const json& list) {
  std::set<Entry> out;
  for (const json& b : list) out.insert({b.at("id").get<int>(), b.at("shelf").get<int>(), b.at("level").get<int>(), b.at("column").get<int>()});
  return out;
}

#ifdef SHELFCROSS_TELLO_PILOT
class TelloEndToEnd : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("shelfcross_tello_e2e_" + std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()) +
            "_" + std::to_string(::getpid()));
    fs::create_directories(dir_);
  }
  void TearDown() override {
    if (!HasFailure()) fs::remove_all(dir_);
  }

  /// One mission: the emulator, then tello_pilot against it; returns the emulator's report.
  json fly(const std::vector<std::string>& fault_options, const std::string& seed = "11",
           const std::vector<std::string>& pilot_options = {}) {
    const std::vector<int> p = free_udp_ports(5);
    const std::string cmd = std::to_string(p[0]), state = std::to_string(p[1]), video = std::to_string(p[2]),
                      state_src = std::to_string(p[3]), video_src = std::to_string(p[4]);
    const std::string src = SHELFCROSS_SOURCE_DIR;
    std::vector<std::string> emu_args{SHELFCROSS_PROGRAM, "tello-sim", "--scenario", src + "/scenarios/paper_test_shelf.yaml",
                                      "--seed", seed, "--nominal", "--bind-ip", "127.0.0.1", "--command-port", cmd,
                                      "--client-state-port", state, "--client-video-port", video,
                                      "--state-source-port", state_src, "--video-source-port", video_src,
                                      "--max-seconds", "300", "--report", (dir_ / "report.json").string()};
    emu_args.insert(emu_args.end(), fault_options.begin(), fault_options.end());
    Child emulator(emu_args, dir_ / "emulator.txt");
    // The emulator is up when it has printed its ports (guard: 60 s for EGL and x264 set-up).
    for (int i = 0; i < 600 && read_file(dir_ / "emulator.txt").find("renderer:") == std::string::npos; ++i) {
      std::this_thread::sleep_for(std::chrono::milliseconds(100));
    }
    std::vector<std::string> pilot_args{
        SHELFCROSS_TELLO_PILOT, "--config", src + "/flight_sw/config/paper_test_shelf.yaml",
        "--drone-ip", "127.0.0.1", "--local-ip", "127.0.0.1", "--command-port", cmd, "--state-port", state,
        "--video-port", video, "--state-source-port", state_src, "--video-source-port", video_src,
        "--log", (dir_ / "flight_log.jsonl").string(), "--inventory", (dir_ / "inventory.json").string()};
    pilot_args.insert(pilot_args.end(), pilot_options.begin(), pilot_options.end());
    Child pilot(pilot_args, dir_ / "pilot.txt");
    pilot_exit_ = pilot.wait(std::chrono::seconds(280));
    ::kill(emulator.pid, SIGTERM);
    const int emulator_exit = emulator.wait(std::chrono::seconds(30));
    EXPECT_EQ(emulator_exit, 0) << read_file(dir_ / "emulator.txt");
    std::cout << "--- tello_pilot (exit " << pilot_exit_ << ")\n"
              << read_file(dir_ / "pilot.txt") << "--- emulator\n"
              << read_file(dir_ / "emulator.txt");
    return json::parse(read_file(dir_ / "report.json"));
  }

  /// The mission flew and crossed without contact (what both flights must show).
  void expect_crossed_without_contact(const json& report) {
    EXPECT_EQ(pilot_exit_, 0) << read_file(dir_ / "pilot.txt");
    EXPECT_TRUE(report.at("contact").is_null()) << report.dump(2);
    EXPECT_FALSE(report.at("crossed").is_null()) << report.dump(2);
    EXPECT_TRUE(report.at("flew").get<bool>());
    EXPECT_TRUE(report.at("landed").get<bool>());
    EXPECT_GT(report.at("path_length_m").get<double>(), 3.0);  // start 3 m before the face, through 0.34 m
    EXPECT_GT(report.at("counters").at("frames_sent").get<int>(), 0);
  }

  /// Every box the inventory lists is where the truth has it, and no cell it lists empty
  /// holds a box. A cell whose marker damaged pictures let through only now and then stays
  /// "uncertain" (never listed, never a target): the safe outcome the inventory is built for;
  /// the flight must still find all but two boxes.
  void expect_safe_inventory(const json& report) {
    ASSERT_TRUE(fs::exists(dir_ / "inventory.json"));
    const json inventory = json::parse(read_file(dir_ / "inventory.json"));
    const std::set<Entry> truth = boxes(report.at("inventory_truth")), found = boxes(inventory.at("boxes"));
    for (const Entry& b : found) EXPECT_TRUE(truth.count(b)) << "box listed but not there: id " << std::get<0>(b);
    for (const json& e : inventory.at("empty")) {
      for (const Entry& b : truth) {
        EXPECT_FALSE(std::get<2>(b) == e.at("level").get<int>() && std::get<3>(b) == e.at("column").get<int>())
            << "cell listed empty holds box " << std::get<0>(b);
      }
    }
    EXPECT_GE(found.size() + 2, truth.size()) << inventory.dump();
  }

  void expect_clean_mission(const json& report) {
    expect_crossed_without_contact(report);
    ASSERT_TRUE(fs::exists(dir_ / "inventory.json"));
    const json inventory = json::parse(read_file(dir_ / "inventory.json"));
    EXPECT_EQ(boxes(inventory.at("boxes")), boxes(report.at("inventory_truth")))
        << inventory.dump() << "\n" << report.at("inventory_truth").dump();
  }

  /// The flight log's last line of a type (null when none).
  json last_log_line(const std::string& type) const {
    std::ifstream in(dir_ / "flight_log.jsonl");
    std::string line;
    json found;
    while (std::getline(in, line)) {
      const json j = json::parse(line, nullptr, false);
      if (!j.is_discarded() && j.value("type", "") == type) found = j;
    }
    return found;
  }

  fs::path dir_;
  int pilot_exit_ = -1;
};

// The calibration manoeuvre (tello_pilot --fly-calibration) wants open space: taken off 3 m in
// front of the shelf and facing it, it sees the shelf's tags, flies none of its steps and lands
// where it took off (exit 1). (The manoeuvre flown whole, and identified, is the validation of
// docs/calibration.md: about a minute a flight, too long for this suite.)
TEST_F(TelloEndToEnd, CalibrationFlightFacingTheShelfStopsAndLands) {
  const json report = fly({}, "11", {"--fly-calibration"});
  EXPECT_EQ(pilot_exit_, 1) << read_file(dir_ / "pilot.txt");
  EXPECT_TRUE(report.at("contact").is_null()) << report.dump(2);
  EXPECT_TRUE(report.at("flew").get<bool>());
  EXPECT_TRUE(report.at("landed").get<bool>());
  EXPECT_LT(report.at("path_length_m").get<double>(), 2.0);  // the climb and the descent
  EXPECT_EQ(last_log_line("start").value("mode", ""), "calibration_flight");
  EXPECT_EQ(last_log_line("stick_program").value("event", ""), "stopped: shelf tags in view");
  EXPECT_NE(last_log_line("failsafe").value("reason", "").find("shelf tags in view"), std::string::npos);
}

TEST_F(TelloEndToEnd, PilotFliesTheEmulatorTakesInventoryCrossesAndLands) {
  const json report = fly({});
  expect_clean_mission(report);
  EXPECT_EQ(report.at("counters").at("state_dropped").get<int>(), 0);
}

// 5 % of the datagrams of every channel are lost: commands, replies, state records and video
// (a lost video datagram damages its slice and, through prediction, the pictures after it
// until the next key frame; the receiver hands over the error-concealed pictures, marked
// damaged, and the flight software decides only on nearly whole ones, steers on moderately
// damaged ones and checks every pose against the state's height, so that it never locks on
// another level's tags). The mission still succeeds, and the frames the flight software flew
// on were damaged ones for the most part.
//
// Under heavy damage the flight software may also give up safely ("target lost", "approach
// timed out": it lands without touching anything); a contact, a wrong inventory or a flight
// that did not land fails. One real-time flight, seed 11; seed 12 at the same losses is flown
// by the co-simulation over tello_pilot's own loop (verification/campaign/test/sdk_link_test.cpp),
// not paced by the wall clock.
// (Measured 2026-11-21 on this 2-core machine under load: of 12 flights of seed 11, 11
// crossed without contact and 1 gave up safely ("could not centre on the target cell"); before
// the level check 2 of 4 touched the box above the target. One CI flight then lost its `land`
// and flew on into the wall behind the shelf; with the driver's stop before a manoeuvre, 8 of 8
// further flights crossed and landed.)
// At 5 % loss on every channel nearly every picture reaches the flight software
// error-concealed (a lost datagram damages the rest of its 1 s group of pictures: 847 of 855
// in one flight), and since the identity check the flight software mostly gives up
// safely there rather than decide on such pictures: over the co-simulation's sdk link, 1 of 16
// runs at 5 % video datagram loss crossed, 15 aborted, 0 contacts
// (lossy_level_check_on.yaml). What must hold at 5 %, flight after
// flight: no contact, landed, nothing listed wrong in the inventory; a crossing when it comes.
TEST_F(TelloEndToEnd, SameWithFivePercentLossOnEveryChannel) {
  const std::vector<std::string> faults{"--loss-commands", "0.05", "--loss-replies", "0.05", "--loss-state", "0.05",
                                        "--loss-video", "0.05"};
  const std::string seed = "11";
  SCOPED_TRACE("seed " + seed);
  const json report = fly(faults, seed);
  EXPECT_TRUE(report.at("contact").is_null()) << report.dump(2);
  EXPECT_TRUE(report.at("flew").get<bool>());
  EXPECT_TRUE(report.at("landed").get<bool>());
  EXPECT_TRUE(pilot_exit_ == 0 || pilot_exit_ == 1) << read_file(dir_ / "pilot.txt");  // crossed, or gave up
  if (!report.at("crossed").is_null()) expect_crossed_without_contact(report);
  std::cout << "--- seed " << seed << (report.at("crossed").is_null() ? ": gave up safely" : ": crossed") << "\n";
  ASSERT_TRUE(fs::exists(dir_ / "inventory.json"));
  const json inventory = json::parse(read_file(dir_ / "inventory.json"));
  const std::set<Entry> truth = boxes(report.at("inventory_truth")), found = boxes(inventory.at("boxes"));
  for (const Entry& b : found) EXPECT_TRUE(truth.count(b)) << "box listed but not there: id " << std::get<0>(b);
  const json& c = report.at("counters");
  EXPECT_GT(c.at("state_dropped").get<int>(), 0);
  EXPECT_GT(c.at("video_datagrams_dropped").get<int>(), 0);
  const json end = last_log_line("end");
  ASSERT_TRUE(end.is_object());
  const std::string video = end.at("video").get<std::string>();
  EXPECT_EQ(video.find("handed_damaged=0 "), std::string::npos) << video;  // concealed frames were used
}

#endif  // SHELFCROSS_TELLO_PILOT

// A third-party client, written as Tello hobby scripts are (djitellopy and the SDK's own
// examples): a plain UDP socket for the commands and one for the state, and OpenCV's FFmpeg
// capture on the video port decoding the raw H.264 stream. Nothing of shelfcross's driver,
// receiver or SDK grammar is used: the emulator must serve any client that speaks the SDK.
TEST(TelloSimThirdPartyClient, CommandStateAndAStreamOpenCvDecodes) {
  const fs::path dir = fs::temp_directory_path() / ("shelfcross_tello_third_party_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  const std::vector<int> p = free_udp_ports(5);
  Child emulator({SHELFCROSS_PROGRAM, "tello-sim", "--scenario", std::string(SHELFCROSS_SOURCE_DIR) + "/scenarios/paper_test_shelf.yaml",
                  "--nominal", "--bind-ip", "127.0.0.1", "--command-port", std::to_string(p[0]), "--client-state-port",
                  std::to_string(p[1]), "--client-video-port", std::to_string(p[2]), "--state-source-port",
                  std::to_string(p[3]), "--video-source-port", std::to_string(p[4]), "--max-seconds", "60"},
                 dir / "emulator.txt");
  for (int i = 0; i < 600 && read_file(dir / "emulator.txt").find("renderer:") == std::string::npos; ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
  }
  const auto udp_socket = [](int port) {
    const int fd = ::socket(AF_INET, SOCK_DGRAM, 0);
    sockaddr_in a{};
    a.sin_family = AF_INET;
    a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    a.sin_port = htons(static_cast<uint16_t>(port));
    EXPECT_EQ(::bind(fd, reinterpret_cast<sockaddr*>(&a), sizeof a), 0);
    timeval tv{2, 0};  // a failure guard: every expected datagram comes within milliseconds
    ::setsockopt(fd, SOL_SOCKET, SO_RCVTIMEO, &tv, sizeof tv);
    return fd;
  };
  const int command_fd = udp_socket(0), state_fd = udp_socket(p[1]);
  sockaddr_in drone{};
  drone.sin_family = AF_INET;
  drone.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  drone.sin_port = htons(static_cast<uint16_t>(p[0]));
  const auto send_command = [&](const std::string& text) {
    ::sendto(command_fd, text.data(), text.size(), 0, reinterpret_cast<const sockaddr*>(&drone), sizeof drone);
    char buf[256];
    const ssize_t n = ::recv(command_fd, buf, sizeof buf, 0);
    return n > 0 ? std::string(buf, static_cast<size_t>(n)) : std::string("<no reply>");
  };
  EXPECT_EQ(send_command("command"), "ok");
  const std::string battery = send_command("battery?");
  EXPECT_GT(std::atoi(battery.c_str()), 0) << battery;
  // The state record: "key:value;" pairs, SDK 2.0's keys among them.
  char buf[2048];
  const ssize_t n = ::recv(state_fd, buf, sizeof buf, 0);
  ASSERT_GT(n, 0) << "no state record";
  const std::string record(buf, static_cast<size_t>(n));
  for (const char* key : {"pitch:", "roll:", "yaw:", "vgx:", "h:", "bat:", "baro:", "time:", "agx:"}) {
    EXPECT_NE(record.find(key), std::string::npos) << key << " in " << record;
  }
  EXPECT_EQ(send_command("streamon"), "ok");
  // How hobby scripts open the stream; the udp protocol's timeout (microseconds) and a bounded
  // probe keep a broken stream from blocking the test.
  ::setenv("OPENCV_FFMPEG_CAPTURE_OPTIONS", "analyzeduration;2000000|probesize;2000000", 1);
  cv::VideoCapture capture("udp://127.0.0.1:" + std::to_string(p[2]) + "?timeout=5000000", cv::CAP_FFMPEG);
  ASSERT_TRUE(capture.isOpened()) << read_file(dir / "emulator.txt");
  cv::Mat frame;
  int decoded = 0;
  for (int k = 0; k < 60 && decoded < 10; ++k) {
    if (capture.read(frame) && !frame.empty()) ++decoded;
  }
  EXPECT_EQ(decoded, 10);
  EXPECT_EQ(frame.cols, 960);
  EXPECT_EQ(frame.rows, 720);
  // A picture of the warehouse, not a blank: the shelf's tags and boxes make it vary.
  cv::Scalar mean, stddev;
  cv::meanStdDev(frame, mean, stddev);
  EXPECT_GT(stddev[0], 10.0);
  EXPECT_EQ(send_command("streamoff"), "ok");
  ::close(command_fd);
  ::close(state_fd);
  ::kill(emulator.pid, SIGTERM);
  EXPECT_EQ(emulator.wait(std::chrono::seconds(30)), 0) << read_file(dir / "emulator.txt");
  if (!::testing::Test::HasFailure()) fs::remove_all(dir);
}

using Result = shelfcross::app::test::ProgramResult;

Result run_program(const std::string& args) { return shelfcross::app::test::run_shelfcross("tello-sim", args); }

TEST(TelloSimCommandLine, BadOptionsExit2WithAMessage) {
  const auto expect_bad = [](const std::string& args, const std::string& part) {
    const Result r = run_program(args);
    EXPECT_EQ(r.exit_code, 2) << args << "\n" << r.output;
    EXPECT_NE(r.output.find(part), std::string::npos) << args << "\n" << r.output;
  };
  expect_bad("--loss-video 1.5", "--loss-video");
  expect_bad("--delay-state -3", "--delay-state");
  expect_bad("--video-stall 5", "--video-stall");
  expect_bad("--video-stall 5,0", "video stall");
  expect_bad("--burst-mean 61", "--burst-mean");
  expect_bad("--burst-loss 2", "--burst-loss");
  expect_bad("--burst-interval 0", "--burst-interval");
  expect_bad("--outage-interval 0.5", "time between outages");
  expect_bad("--outage-lengths 3", "--outage-lengths");
  expect_bad("--outage-lengths 4,2", "outage lengths");
  expect_bad("--outage 5", "--outage");
  expect_bad("--outage 5,0", "an outage needs");
  expect_bad("--command-port 70000", "--command-port");
  expect_bad("--slices 0", "--slices");
  expect_bad("--bind-ip 300.1.1.1", "300.1.1.1");
  expect_bad("--scenario /nonexistent/scenario.yaml", "/nonexistent/scenario.yaml");
  expect_bad("--frobnicate", "frobnicate");
}

// tello-sim --seed N flies the scenario's dispersions of seed N (as `shelfcross run --seed N`
// draws them): reproducible per seed, different between seeds; --nominal flies the scenario
// as written. The report names the draws and which of them the emulator applies;
// --write-calibration writes the camera the flight software would believe (its drawn error).
TEST(TelloSimCommandLine, DrawsTheScenarioDispersionsOfTheSeed) {
  const fs::path dir = fs::temp_directory_path() / ("shelfcross_tello_sim_dispersion_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  const auto run = [&](const std::string& name, const std::string& options) {
    const Result r = run_program("--scenario " + std::string(SHELFCROSS_SOURCE_DIR) +
                                 "/scenarios/paper_test_shelf.yaml --command-port 0 --max-seconds 0.2 " + options +
                                 " --report " + (dir / (name + ".json")).string() + " --write-calibration " +
                                 (dir / (name + ".yml")).string());
    EXPECT_EQ(r.exit_code, 0) << r.output;
    return json::parse(read_file(dir / (name + ".json")));
  };
  const json a = run("a", "--seed 5"), b = run("b", "--seed 5"), c = run("c", "--seed 6"), n = run("n", "--seed 5 --nominal");
  EXPECT_TRUE(a.at("dispersed").get<bool>());
  EXPECT_FALSE(n.at("dispersed").get<bool>());
  EXPECT_TRUE(n.at("dispersions").empty());
  EXPECT_EQ(a.at("dispersions"), b.at("dispersions"));
  EXPECT_EQ(a.at("start"), b.at("start"));
  EXPECT_EQ(a.at("inventory_truth"), b.at("inventory_truth"));
  EXPECT_NE(a.at("start"), c.at("start"));
  EXPECT_NE(a.at("start"), n.at("start"));
  EXPECT_NE(a.at("inventory_truth"), c.at("inventory_truth"));  // box_fill_ratio re-places the boxes
  EXPECT_EQ(n.at("inventory_truth").size(), 10u);                // the scenario's own boxes
  const json& d = a.at("dispersions");
  EXPECT_TRUE(d.at("start_distance_m").at("applied").get<bool>());
  EXPECT_TRUE(d.at("box_fill_ratio").at("applied").get<bool>());
  EXPECT_FALSE(d.at("camera_focal_error_rel").at("applied").get<bool>());
  EXPECT_FALSE(d.at("frame_drop_probability").at("applied").get<bool>());
  // The believed camera: the truth's focal lengths times (1 + the drawn error).
  const auto fx = [&](const std::string& name) {
    const std::string text = read_file(dir / (name + ".yml"));
    const auto at = text.find("data: [");
    EXPECT_NE(at, std::string::npos) << text;
    return std::stod(text.substr(at + 7));
  };
  EXPECT_NEAR(fx("a") / fx("n"), 1.0 + d.at("camera_focal_error_rel").at("value").get<double>(), 1e-6);
  fs::remove_all(dir);
}

TEST(TelloSimCommandLine, MaxSecondsEndsAndReportsAsJson) {
  const fs::path report = fs::temp_directory_path() / ("shelfcross_tello_sim_report_" + std::to_string(::getpid()) + ".json");
  const Result r = run_program("--scenario " + std::string(SHELFCROSS_SOURCE_DIR) + "/scenarios/paper_test_shelf.yaml --command-port 0 --max-seconds 0.5 --seed 3 --nominal --report " + report.string());
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("max_seconds"), std::string::npos) << r.output;
  const json j = json::parse(read_file(report));
  EXPECT_EQ(j.at("end_reason"), "max_seconds");
  EXPECT_FALSE(j.at("flew").get<bool>());
  EXPECT_TRUE(j.at("contact").is_null());
  EXPECT_EQ(j.at("inventory_truth").size(), 10u);
  fs::remove(report);
}

}  // namespace
