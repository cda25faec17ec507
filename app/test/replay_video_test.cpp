// The replay video: H.264 (`avc1`) in MP4, yuv420p, 30 fps, 960 x 720; pictures
// placed on the camera's timeline; and each annotation drawn on the picture it was computed
// from, never on a later picture.

#include <gtest/gtest.h>

#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include <opencv2/imgproc.hpp>
#include <opencv2/videoio.hpp>

#include "../run_output.hpp"
#include "run_shelfcross.hpp"
#include "verification/campaign/campaign.hpp"
#include "verification/scenario/dispersion.hpp"
#include "verification/scenario/scenario.hpp"
#include "verification/scenario/senses_dispersion.hpp"

namespace {

namespace fs = std::filesystem;
using shelfcross::CameraFrame;
using shelfcross::app::AnnotationSorter;
using shelfcross::app::FrameAnnotations;
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

// `shelfcross run --video` on the default scenario, cut to its first 4 simulated seconds:
// the file is H.264 in yuv420p (what browsers decode), at the camera's 30 fps and 960 x 720,
// and holds one picture per camera frame from the first one received to the end.
TEST_F(ReplayVideoTest, RunWritesBrowserPlayableH264) {
  std::ifstream in(SHELFCROSS_SOURCE_DIR "/scenarios/paper_test_shelf.yaml");
  std::stringstream yaml;
  yaml << in.rdbuf();
  std::string text = yaml.str();
  const auto at = text.find("timeout_s: 120");
  ASSERT_NE(at, std::string::npos) << "the default scenario's cosim.timeout_s moved";
  text.replace(at, 14, "timeout_s: 4");
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
  // The stream starts after `command` and `streamon` (well under 2 s) and the run stops at 4 s:
  // a picture for every 1/30 s in between, lost ones filled.
  EXPECT_GE(frames, 2 * 30);
  EXPECT_LE(frames, 4 * 30 + 1);
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

CameraFrame picture(std::int64_t index, int shade) {
  return CameraFrame{index * 33'333'333, index, cv::Mat(48, 64, CV_8UC3, cv::Scalar(shade, shade, shade))};
}

// The sorter: a value that changed after a picture is that picture's; kept unchanged, it is
// drawn again only on a picture identical to its own; otherwise it is named as stale.
TEST(AnnotationSorter, DrawsOnlyWhatWasComputedFromThePicture) {
  AnnotationSorter sorter;
  shelfcross::flight_sw::Telemetry tm;
  tm.view.tags = {{cv::Point2d(10, 12), 30.0, 0, 1}, {cv::Point2d(40, 12), 31.0, 0, 2}};
  tm.tracking.tracked_box_px = cv::Rect2d(5, 5, 20, 20);
  tm.control.e_z_m = 0.05;
  tm.control.e_psi_rad = -0.01;

  FrameAnnotations a = sorter.sort(picture(7, 100), tm);
  EXPECT_EQ(a.frame, 7);
  EXPECT_EQ(a.tags.size(), 2u);
  EXPECT_TRUE(a.tracked_box_px);
  ASSERT_TRUE(a.e_z_m);
  EXPECT_DOUBLE_EQ(*a.e_z_m, 0.05);
  EXPECT_FALSE(a.stale_tags || a.stale_box || a.stale_errors);

  // The same picture again (a frozen stream): the same results belong to it.
  a = sorter.sort(picture(8, 100), tm);
  EXPECT_EQ(a.tags.size(), 2u);
  EXPECT_TRUE(a.tracked_box_px);
  EXPECT_FALSE(a.stale_tags || a.stale_box || a.stale_errors);

  // Another picture, on which the flight software computed a new box and new errors but kept
  // the tag list (as while approaching): the tags are not drawn, and say where they are from.
  tm.tracking.tracked_box_px = cv::Rect2d(6, 5, 21, 21);
  tm.control.e_z_m = 0.04;
  a = sorter.sort(picture(9, 120), tm);
  EXPECT_TRUE(a.tags.empty());
  ASSERT_TRUE(a.stale_tags);
  EXPECT_EQ(a.stale_tags->frame, 7);
  EXPECT_EQ(a.stale_tags->t_ns, 7 * 33'333'333);
  EXPECT_EQ(a.tracked_box_px, tm.tracking.tracked_box_px);
  ASSERT_TRUE(a.e_z_m);
  EXPECT_DOUBLE_EQ(*a.e_z_m, 0.04);

  // A picture on which the target was not measured: box and errors are frame 9's.
  a = sorter.sort(picture(10, 140), tm);
  EXPECT_FALSE(a.tracked_box_px);
  ASSERT_TRUE(a.stale_box);
  EXPECT_EQ(a.stale_box->frame, 9);
  EXPECT_FALSE(a.e_z_m);
  ASSERT_TRUE(a.stale_errors);
  EXPECT_EQ(a.stale_errors->frame, 9);
  EXPECT_DOUBLE_EQ(a.stale_e_z_m, 0.04);

  // A cleared box or tag list is nothing to draw and nothing stale.
  tm.tracking.tracked_box_px.reset();
  tm.view.tags.clear();
  a = sorter.sort(picture(11, 160), tm);
  EXPECT_FALSE(a.tracked_box_px || a.stale_box || a.stale_tags);
  EXPECT_TRUE(a.tags.empty());

  // Drawing does not throw and marks the picture.
  cv::Mat img(720, 960, CV_8UC3, cv::Scalar(0, 0, 0));
  shelfcross::app::draw_annotations(img, a);
  EXPECT_GT(cv::countNonZero(img.reshape(1)), 0);
}

// Whether the picture shows the tag colour at a point: the default scenario's tags are green;
// bars are blue, boxes brown, walls and floor grey.
bool on_tag(const cv::Mat& bgr, const cv::Point2d& p) {
  const cv::Point q(static_cast<int>(std::lround(p.x)), static_cast<int>(std::lround(p.y)));
  if (q.x < 0 || q.y < 0 || q.x >= bgr.cols || q.y >= bgr.rows) return false;
  const cv::Vec3b v = bgr.at<cv::Vec3b>(q);
  return v[1] > v[0] + 30 && v[1] > v[2] + 30;
}

// A whole co-simulated run of the default scenario: every tag drawn on a picture sits on a tag
// of that picture. The tag list the flight software holds from earlier pictures, which the
// overlay used to draw, does not (while approaching it is the inventory's, seconds old). The
// overlay's check needs a whole mission, approach and crossing: the run is flown in the world of
// the truth (without_senses), where this draw's mission succeeds; with the Tello's own senses
// it ends "approach timed out" (a safe abort, no crossing). The overlay draws what the flight
// software computed on the pictures it was handed, whichever link handed them: the run is flown
// over the ideal link (whole pictures: no H.264 to encode and decode).
TEST(ReplayOverlay, TagsAreDrawnOnThePictureTheyCameFrom) {
  using namespace shelfcross;
  verification::Scenario nominal = verification::without_senses(
      verification::load_scenario(SHELFCROSS_SOURCE_DIR "/scenarios/paper_test_shelf.yaml"));
  nominal.cosim.link.model = "ideal";
  const verification::RunSetup setup = verification::disperse(nominal, 3);
  const verification::Scenario& sc = *setup.scenario;
  render::Renderer renderer(sc.warehouse, sc.camera, verification::render_options_for(sc));
  AnnotationSorter sorter;
  int drawn = 0, drawn_on_tag = 0, held = 0, held_on_tag = 0, frames_with_stale_tags = 0, approach_frames = 0;
  const verification::FrameObserver observer = [&](const CameraFrame& frame, const flight_sw::FlightSoftware& fsw) {
    const FrameAnnotations a = sorter.sort(frame, fsw.telemetry());
    for (const auto& tag : a.tags) {
      ++drawn;
      drawn_on_tag += on_tag(frame.bgr, tag.centre_px);
    }
    if (a.stale_tags) {
      ++frames_with_stale_tags;
      for (const auto& tag : fsw.telemetry().view.tags) {
        ++held;
        held_on_tag += on_tag(frame.bgr, tag.centre_px);
      }
    }
    approach_frames += a.phase == "approach";
  };
  const verification::RunResult r = verification::run_cosimulation(setup, renderer, observer);
  EXPECT_EQ(r.outcome, verification::RunOutcome::success) << r.detail;
  ASSERT_GT(approach_frames, 30);
  ASSERT_GT(drawn, 1000);
  // Tag centres are blob centroids: on the tag, except for the odd blob cut by the image border
  // or a damaged picture.
  EXPECT_GE(drawn_on_tag, 0.98 * drawn) << drawn_on_tag << " of " << drawn;
  // What the old overlay drew on the approach's pictures: mostly off the tags.
  ASSERT_GT(frames_with_stale_tags, 30);
  EXPECT_LT(held_on_tag, 0.5 * held) << held_on_tag << " of " << held;
  std::printf("tags drawn %d, on a tag %d; tags held from earlier pictures %d (%d frames), on a tag %d\n", drawn,
              drawn_on_tag, held, frames_with_stale_tags, held_on_tag);
}

}  // namespace
