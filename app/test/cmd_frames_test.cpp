// `shelfcross frames`: renders the perception benchmark's frame set and, with --check, shows
// that the fast and the reference perception pipelines decide the same on it.

#include <gtest/gtest.h>

#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <string>

#include "run_shelfcross.hpp"

namespace {

namespace fs = std::filesystem;

class CmdFrames : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("shelfcross_cmd_frames_" + std::to_string(::getpid()) + "_" +
                                        ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  fs::path dir_;
};

TEST_F(CmdFrames, UnknownConditionIsBadInput) {
  const auto r = shelfcross::app::test::run_shelfcross("frames", "--condition foggy --out " + dir_.string());
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("unknown condition 'foggy'"), std::string::npos) << r.output;
}

// The nominal sequence and the far stills: every frame written with its manifest line; the
// fast tag detector finds exactly the reference's front tags on every whole frame; and the
// flight software, fed the sequence, takes the inventory and approaches the target with both
// pipelines, deciding the same at every frame.
TEST_F(CmdFrames, NominalSequenceRendersAndBothPipelinesDecideTheSame) {
  const auto r = shelfcross::app::test::run_shelfcross(
      "frames", "--scenario " SHELFCROSS_SOURCE_DIR "/scenarios/paper_test_shelf.yaml --condition nominal --check --out " +
                    dir_.string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("wrote 110 frames"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("nominal: "), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("take_inventory@"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("approach@"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("same decisions"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("whole-frame tags after eq. 1: 110 frames"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("front tags: identical"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("decisions: fast == reference"), std::string::npos) << r.output;
  std::ifstream manifest(dir_ / "manifest.csv");
  std::string line;
  int rows = 0;
  std::getline(manifest, line);
  EXPECT_EQ(line.rfind("# shelfcross bench frames version 4 scenario paper_test_shelf", 0), 0u) << line;
  std::getline(manifest, line);  // column names
  while (std::getline(manifest, line)) {
    ++rows;
    const std::string name = line.substr(0, line.find(','));
    EXPECT_TRUE(fs::exists(dir_ / (name + ".png"))) << name;
  }
  EXPECT_EQ(rows, 110);
}

}  // namespace
