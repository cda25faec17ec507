// tello_pilot --print-markers: the sheets it writes as PNG are read back and their markers
// found by the detector at their printed size. A program of its own (world_image_test), the one
// of this room that reads image files: OpenCV's image codecs, which it links, cost every start
// of a program that links them (cmake/shelfcross_module.cmake).
#include <gtest/gtest.h>

#include <filesystem>
#include <string>
#include <vector>

#include <opencv2/aruco.hpp>
#include <opencv2/imgcodecs.hpp>

#include "verification/world/test/tello_pilot_child.hpp"

namespace shelfcross::tello {
namespace {

namespace fs = std::filesystem;
using testing::kConfig;
using testing::run_to_exit;
using testing::temp_dir;

TEST(TelloPilot, PrintsMarkersTheDetectorReads) {
  const fs::path dir = temp_dir("print");
  std::string err;
  ASSERT_EQ(run_to_exit({"--config", kConfig, "--print-markers", dir.string(), "--marker-ids", "3-5"}, &err), 0) << err;
  const auto dict = cv::aruco::getPredefinedDictionary(cv::aruco::DICT_4X4_50);  // the config's
  for (int id = 3; id <= 5; ++id) {
    const cv::Mat sheet = cv::imread((dir / ("marker_" + std::to_string(id) + ".png")).string());
    ASSERT_FALSE(sheet.empty()) << id;
    std::vector<int> ids;
    std::vector<std::vector<cv::Point2f>> corners;
    cv::aruco::detectMarkers(sheet, dict, corners, ids);
    ASSERT_EQ(ids, std::vector<int>{id});
    // 0.10 m at 300 dpi: 1181 px a side.
    EXPECT_NEAR(cv::norm(corners[0][0] - corners[0][1]), 1181.0, 3.0);
  }
  EXPECT_FALSE(cv::imread((dir / "tag.png").string()).empty());
  EXPECT_EQ(run_to_exit({"--config", kConfig, "--print-markers", dir.string(), "--marker-ids", "5-2"}, &err), 2);
  if (!HasFailure()) fs::remove_all(dir);
}

}  // namespace
}  // namespace shelfcross::tello
