// The replay video (issue 19): H.264 (`avc1`) in MP4, yuv420p, 30 fps, 960 x 720; pictures
// placed on the camera's timeline.

#include <gtest/gtest.h>

#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include <opencv2/videoio.hpp>

#include "../run_output.hpp"
#include "run_shelfcross.hpp"

namespace {

namespace fs = std::filesystem;
using shelfcross::app::ReplayVideo;

std::string fourcc_text(double v) {
  const int f = static_cast<int>(v);
  return {static_cast<char>(f & 0xff), static_cast<char>((f >> 8) & 0xff), static_cast<char>((f >> 16) & 0xff),
          static_cast<char>((f >> 24) & 0xff)};
}

class ReplayVideoTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("shelfcross_replay_video_" + std::to_string(::getpid()) + "_" +
                                        ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  fs::path dir_;
};

// `shelfcross run --video` on the default scenario, cut to its first 8 simulated seconds:
// the file is H.264 in yuv420p (what browsers decode), at the camera's 30 fps and 960 x 720,
// and holds one picture per camera frame from the first one received to the end.
TEST_F(ReplayVideoTest, RunWritesBrowserPlayableH264) {
  std::ifstream in(SHELFCROSS_SOURCE_DIR "/scenarios/paper_test_shelf.yaml");
  std::stringstream yaml;
  yaml << in.rdbuf();
  std::string text = yaml.str();
  const auto at = text.find("timeout_s: 120");
  ASSERT_NE(at, std::string::npos) << "the default scenario's cosim.timeout_s moved";
  text.replace(at, 14, "timeout_s: 8");
  const fs::path scenario = dir_ / "short.yaml";
  std::ofstream(scenario) << text;
  const fs::path out = dir_ / "run";
  const auto r = shelfcross::app::test::run_shelfcross(
      "run", "--scenario " + scenario.string() + " --seed 3 --out " + out.string() + " --video");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("video.mp4"), std::string::npos) << r.output;

  std::ifstream mp4(out / "video.mp4", std::ios::binary);
  std::string head(64, '\0');
  mp4.read(head.data(), 64);
  EXPECT_EQ(head.substr(4, 4), "ftyp");

  cv::VideoCapture cap((out / "video.mp4").string(), cv::CAP_FFMPEG);
  ASSERT_TRUE(cap.isOpened());
  EXPECT_EQ(fourcc_text(cap.get(cv::CAP_PROP_FOURCC)), "avc1");
  EXPECT_EQ(fourcc_text(cap.get(cv::CAP_PROP_CODEC_PIXEL_FORMAT)), "I420");  // yuv420p
  EXPECT_DOUBLE_EQ(cap.get(cv::CAP_PROP_FPS), 30.0);
  EXPECT_EQ(cap.get(cv::CAP_PROP_FRAME_WIDTH), 960.0);
  EXPECT_EQ(cap.get(cv::CAP_PROP_FRAME_HEIGHT), 720.0);
  int frames = 0;
  cv::Mat img;
  while (cap.read(img)) {
    ASSERT_EQ(img.size(), cv::Size(960, 720));
    ++frames;
  }
  // The stream starts after `command` and `streamon` (well under 2 s) and the run stops at 8 s:
  // a picture for every 1/30 s in between, lost ones filled.
  EXPECT_GE(frames, 6 * 30);
  EXPECT_LE(frames, 8 * 30 + 1);
}

// Frames the link lost are filled with the last picture, so the video keeps the camera's time.
TEST_F(ReplayVideoTest, LostPicturesAreFilled) {
  const fs::path path = dir_ / "gaps.mp4";
  {
    ReplayVideo video(path, 30.0, cv::Size(320, 240));
    for (const int index : {10, 11, 14, 15}) {
      video.write(cv::Mat(240, 320, CV_8UC3, cv::Scalar(index * 10, 0, 0)), index);
    }
    EXPECT_EQ(video.frames_written(), 6);  // 10, 11, (12, 13 filled), 14, 15
  }
  cv::VideoCapture cap(path.string(), cv::CAP_FFMPEG);
  int frames = 0;
  for (cv::Mat img; cap.read(img);) ++frames;
  EXPECT_EQ(frames, 6);
}

TEST_F(ReplayVideoTest, WrongPictureSizeIsRefused) {
  ReplayVideo video(dir_ / "size.mp4", 30.0, cv::Size(320, 240));
  EXPECT_THROW(video.write(cv::Mat(100, 100, CV_8UC3), 0), std::invalid_argument);
}

}  // namespace
