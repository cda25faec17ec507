#include "verification/plot/plot.hpp"

#include <unistd.h>
#include <cmath>
#include <filesystem>

#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>

namespace shelfcross::verification {
namespace {

TEST(Plot, NiceTicksAreRoundAndCoverTheRange) {
  EXPECT_EQ(nice_ticks(0.0, 10.0, 5), (std::vector<double>{0, 2, 4, 6, 8, 10}));
  const auto t = nice_ticks(-0.13, 0.42, 6);
  ASSERT_GE(t.size(), 3u);
  EXPECT_NEAR(t[1] - t[0], 0.1, 1e-12);
  EXPECT_GE(t.front(), -0.13);
  EXPECT_LE(t.back(), 0.42 + 1e-12);
}

TEST(Plot, DrawsSeriesWhereTheDataIs) {
  Chart chart("t", "x", "y", 400, 300);
  chart.set_x_limits(0, 10);
  chart.set_y_limits(0, 10);
  chart.add_rect(4, 4, 6, 6, cv::Scalar(0, 0, 255), true);
  const cv::Mat img = chart.draw();
  ASSERT_EQ(img.size(), cv::Size(400, 300));
  // The plot area is 400-100-30 = 270 wide, 300-50-70 = 180 high: data (5, 5) sits at its centre.
  const cv::Vec3b centre = img.at<cv::Vec3b>(50 + 90, 100 + 135);
  EXPECT_EQ(centre, cv::Vec3b(0, 0, 255));
  const cv::Vec3b outside = img.at<cv::Vec3b>(50 + 20, 100 + 20);
  EXPECT_NE(outside, cv::Vec3b(0, 0, 255));
}

TEST(Plot, HistogramAndPngOutput) {
  std::vector<double> v;
  for (int i = 0; i < 100; ++i) v.push_back(std::sin(i));
  const Chart h = histogram_chart(v, 10, "h", "value");
  const auto path = std::filesystem::temp_directory_path() / ("shelfcross_plot_test_" + std::to_string(::getpid()) + ".png");
  h.save_png(path.string());
  const cv::Mat back = cv::imread(path.string());
  EXPECT_EQ(back.cols, 960);
  EXPECT_EQ(back.rows, 640);
  std::filesystem::remove(path);
}

}  // namespace
}  // namespace shelfcross::verification
