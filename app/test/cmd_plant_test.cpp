// `shelfcross plant`: bad input exits 2 naming file and line; a good run writes the CSV.

#include <gtest/gtest.h>

#include "run_shelfcross.hpp"

#include <sys/wait.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

namespace {

namespace fs = std::filesystem;

using Result = shelfcross::app::test::ProgramResult;

std::vector<std::string> lines_of(const std::string& path) {
  std::ifstream in(path);
  std::vector<std::string> lines;
  for (std::string l; std::getline(in, l);) lines.push_back(l);
  return lines;
}

Result run(const std::string& args) { return shelfcross::app::test::run_shelfcross("plant", args); }

class CmdPlant : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("shelfcross_cmd_plant_" + std::to_string(::getpid()) + "_" +
            std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()));
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  std::string write(const std::string& name, const std::string& text) {
    const fs::path p = dir_ / name;
    std::ofstream(p) << text;
    return p.string();
  }
  std::string out() const { return (dir_ / "out.csv").string(); }
  void expect_bad(const std::string& option, const std::string& text, int line, const std::string& reason_part) {
    const std::string f = write("bad.txt", text);
    const Result r = run(option + " " + f + " --seconds 2 --out " + out());
    EXPECT_EQ(r.exit_code, 2) << r.output;
    EXPECT_NE(r.output.find(f + ":" + std::to_string(line) + ":"), std::string::npos) << r.output;
    EXPECT_NE(r.output.find(reason_part), std::string::npos) << r.output;
  }
  fs::path dir_;
};

TEST_F(CmdPlant, UnknownCommandIsBadInput) {
  expect_bad("--commands", "0 command\n# comment\n\n1 hover\n", 4, "unknown command");
}

TEST_F(CmdPlant, OutOfRangeValueIsBadInput) {
  expect_bad("--commands", "0 command\n1 takeoff\n6 rc 0 120 0 0\n", 3, "outside -100..100");
  expect_bad("--commands", "0 command\n1 forward 10\n", 2, "outside 20..500");
}

TEST_F(CmdPlant, TimesNotIncreasingAreBadInput) {
  expect_bad("--commands", "0 command\n2 takeoff\n1.5 land\n", 3, "not after");
  expect_bad("--commands", "0 command\n0 takeoff\n", 2, "not after");
}

TEST_F(CmdPlant, MalformedLinesAreBadInput) {
  expect_bad("--commands", "0 command\nsoon takeoff\n", 2, "not a number");
  expect_bad("--commands", "0 command\n3\n", 2, "missing command");
  expect_bad("--commands", "-1 command\n", 1, "negative");
  expect_bad("--rotor-speeds", "0 100 100 100\n", 1, "expected 4 rotor speeds");
  expect_bad("--rotor-speeds", "0 100 100 100 x\n", 1, "not a number");
  expect_bad("--rotor-speeds", "0 100 100 100 100\n0.5 1 2 3 99999\n", 2, "outside");
  expect_bad("--rotor-speeds", "0 1 2 3 4 5\n", 1, "unexpected");
}

TEST_F(CmdPlant, MissingFileIsBadInput) {
  const std::string missing = (dir_ / "nope.commands").string();
  const Result r = run("--commands " + missing + " --seconds 1 --out " + out());
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.output.find(missing), std::string::npos) << r.output;
}

TEST_F(CmdPlant, BadOptionsAreBadInput) {
  const std::string f = write("ok.txt", "0 command\n");
  EXPECT_EQ(run("--commands " + f + " --seconds -1 --out " + out()).exit_code, 2);
  EXPECT_EQ(run("--commands " + f + " --out " + out()).exit_code, 2);  // --seconds required
  EXPECT_EQ(run("--seconds 1 --out " + out()).exit_code, 2);           // no input
  EXPECT_EQ(run("--commands " + f + " --rotor-speeds " + f + " --seconds 1 --out " + out()).exit_code, 2);
}


TEST_F(CmdPlant, GoodRunWritesHeaderAndExpectedRows) {
  const std::string f = write("demo.commands",
                              "# take off and fly forward\n0 command\n0.5 takeoff\n6 rc 0 50 0 0\n8 rc 0 0 0 0\n");
  const std::string replies = (dir_ / "replies.txt").string();
  const Result r = run("--commands " + f + " --seconds 9 --rate 50 --out " + out() + " --replies " + replies);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto lines = lines_of(out());
  ASSERT_EQ(lines.size(), 1u + 9 * 50 + 1);  // header + samples at 0, 0.02, ..., 9.0
  EXPECT_EQ(lines[0],
            "t_s,x_m,y_m,z_m,vx_mps,vy_mps,vz_mps,roll_rad,pitch_rad,yaw_rad,p_radps,q_radps,r_radps,"
            "w1_radps,w2_radps,w3_radps,w4_radps");
  // The last row: flying forward about 1 m high, ahead of the start.
  std::stringstream last(lines.back());
  std::vector<double> v;
  for (std::string cell; std::getline(last, cell, ',');) v.push_back(std::stod(cell));
  ASSERT_EQ(v.size(), 17u);
  EXPECT_DOUBLE_EQ(v[0], 9.0);
  EXPECT_GT(v[1], 0.5);
  EXPECT_NEAR(v[3], 1.0, 0.1);
  // The firmware's replies were logged: "ok" to command and the deferred takeoff "ok".
  const auto reply_lines = lines_of(replies);
  ASSERT_GE(reply_lines.size(), 2u);
  EXPECT_NE(reply_lines[0].find("-> ok"), std::string::npos);
  EXPECT_NE(reply_lines[1].find("(deferred) -> ok"), std::string::npos);
}

// A command file that flies nothing says why. Every command the firmware ignored or
// refused is printed with its time and the reason; the run still writes its CSV (exit 0).
TEST_F(CmdPlant, TakeoffBeforeCommandIsReportedAsIgnored) {
  const std::string f = write("early.commands", "0 takeoff\n0.5 rc 0 50 0 0\n1 command\n");
  const Result r = run("--commands " + f + " --seconds 3 --out " + out());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("0 \"takeoff\" ignored: not in SDK mode ('command' not received yet), no reply"),
            std::string::npos)
      << r.output;
  EXPECT_NE(r.output.find("0.5 \"rc 0 50 0 0\" ignored: not in SDK mode"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("1 \"command\" -> ok"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("2 of 3 commands ignored or refused by the simulated firmware"), std::string::npos)
      << r.output;
  EXPECT_NE(r.output.find("final mode: landed"), std::string::npos) << r.output;
}

TEST_F(CmdPlant, RefusedAndIgnoredCommandsGiveTheReason) {
  const std::string f = write("refused.commands",
                              "0 command\n0.2 land\n0.4 forward 50\n0.5 takeoff\n1 rc 0 50 0 0\n1.5 takeoff\n"
                              "2 flip l\n");
  const std::string replies = (dir_ / "replies.txt").string();
  const Result r = run("--commands " + f + " --seconds 3 --out " + out() + " --replies " + replies);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  // On stderr although the replies go to a file.
  EXPECT_NE(r.output.find("0.2 \"land\" -> error: refused: the drone is landed"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("0.4 \"forward 50\" -> error: refused: the drone is landed"), std::string::npos)
      << r.output;
  EXPECT_NE(r.output.find("1 \"rc 0 50 0 0\" ignored: the drone is taking_off (rc acts only while flying free)"),
            std::string::npos)
      << r.output;
  EXPECT_NE(r.output.find("1.5 \"takeoff\" -> error: refused: the drone is taking_off"), std::string::npos)
      << r.output;
  EXPECT_NE(r.output.find("2 \"flip l\" -> error: refused: flip and curve are not simulated"), std::string::npos)
      << r.output;
  EXPECT_NE(r.output.find("5 of 7 commands ignored or refused"), std::string::npos) << r.output;
  // And in the replies file, in time order with the replies.
  const auto reply_lines = lines_of(replies);
  ASSERT_GE(reply_lines.size(), 6u);
  EXPECT_EQ(reply_lines[0], "0 \"command\" -> ok");
  EXPECT_EQ(reply_lines[1], "0.2 \"land\" -> error: refused: the drone is landed");
}

TEST_F(CmdPlant, WatchdogLandingIsReported) {
  const std::string f = write("quiet.commands", "0 command\n0.5 takeoff\n");
  const Result r = run("--commands " + f + " --seconds 20 --rate 10 --out " + out());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("landing by itself: no command for 15 s (since 0.5 s)"), std::string::npos) << r.output;
  EXPECT_EQ(r.output.find("ignored or refused"), std::string::npos) << r.output;
}

TEST_F(CmdPlant, RotorSpeedFileBypassesTheAutopilot) {
  // Near-full speed on all four rotors for 1 s: it climbs straight up.
  const std::string f = write("rotors.txt", "0 5400 5400 5400 5400\n1 0 0 0 0\n");
  const Result r = run("--rotor-speeds " + f + " --seconds 1 --out " + out());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto lines = lines_of(out());
  ASSERT_EQ(lines.size(), 1u + 100 + 1);
  std::stringstream last(lines.back());
  std::vector<double> v;
  for (std::string cell; std::getline(last, cell, ',');) v.push_back(std::stod(cell));
  EXPECT_GT(v[3], 0.5);                // climbed
  EXPECT_NEAR(v[1], 0.0, 1e-9);        // straight up
  EXPECT_NEAR(v[13], 5400.0, 1.0);     // w1 at its command
}

TEST_F(CmdPlant, HelpDocumentsRotorNumbering) {
  const Result r = run("--help");
  EXPECT_EQ(r.exit_code, 0);
  EXPECT_NE(r.output.find("1 front-left (ccw)"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("a right, b forward, c up, d clockwise"), std::string::npos);
}

TEST(CmdPlantDemo, ShippedDemoRuns) {
  const std::string out = (fs::temp_directory_path() / ("shelfcross_plant_demo_" + std::to_string(::getpid()) + ".csv")).string();
  const Result r = run(std::string("--commands ") + SHELFCROSS_SOURCE_DIR + "/scenarios/plant_demo.commands --seconds 20 --out " + out);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_EQ(lines_of(out).size(), 1u + 2000 + 1);
  EXPECT_NE(r.output.find("final mode: landed"), std::string::npos) << r.output;
  fs::remove(out);
}

}  // namespace
