// --print-markers mode of tello_pilot: PNG files to print at 300 dpi for the test shelf: the
// box markers (the configured ArUco dictionary, marker_size_m including the black border,
// with a white quiet zone) and one colour tag (tag_size_m, a colour in the middle of the
// configured HSV range), each with its size written under it.
#include <cmath>
#include <filesystem>
#include <iostream>

#include <opencv2/aruco.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "flight_sw/perception/shelf_view.hpp"
#include "flight_sw/tello/pilot/pilot.hpp"

namespace shelfcross::tello::pilot {
namespace {

constexpr double kDotsPerMetre = 300.0 / 0.0254;  // 300 dpi

int pixels(double metres) { return static_cast<int>(std::lround(metres * kDotsPerMetre)); }

// A white page around `content` with a caption below it.
cv::Mat page(const cv::Mat& content, const std::string& caption) {
  const int margin = pixels(0.01);
  cv::Mat out(content.rows + 3 * margin, content.cols + 2 * margin, CV_8UC3, cv::Scalar(255, 255, 255));
  content.copyTo(out(cv::Rect(margin, margin, content.cols, content.rows)));
  cv::putText(out, caption, cv::Point(margin, content.rows + 2 * margin + margin / 2), cv::FONT_HERSHEY_SIMPLEX,
              1.0, cv::Scalar(0, 0, 0), 2);
  return out;
}

}  // namespace

int run_print_sheets(const PilotOptions& o) {
  namespace fs = std::filesystem;
  const auto& shelf = o.flight.shelf;
  std::error_code ec;
  fs::create_directories(o.print_dir, ec);
  const auto dict_id = flight_sw::aruco_dictionary_id(shelf.aruco_dictionary);
  if (!dict_id) throw UsageError("unknown ArUco dictionary " + shelf.aruco_dictionary);
  const cv::Ptr<cv::aruco::Dictionary> dict = cv::aruco::getPredefinedDictionary(*dict_id);
  const int side = pixels(shelf.marker_size_m);
  for (int id = o.marker_first; id <= o.marker_last; ++id) {
    if (id >= dict->bytesList.rows) throw UsageError("marker id " + std::to_string(id) + " is not in " + shelf.aruco_dictionary);
    cv::Mat gray;
    cv::aruco::drawMarker(dict, id, side, gray, 1);
    cv::Mat bgr;
    cv::cvtColor(gray, bgr, cv::COLOR_GRAY2BGR);
    const std::string caption = shelf.aruco_dictionary + " id " + std::to_string(id) + ", " +
                                std::to_string(static_cast<int>(std::lround(shelf.marker_size_m * 1000))) + " mm";
    const fs::path file = fs::path(o.print_dir) / ("marker_" + std::to_string(id) + ".png");
    if (!cv::imwrite(file.string(), page(bgr, caption), {cv::IMWRITE_PNG_COMPRESSION, 9})) {
      throw UsageError("cannot write " + file.string());
    }
  }
  // The tag colour: the middle of the configured HSV range (hue may wrap through red).
  const auto& hsv = o.flight.perception.tag_hsv;
  int hue = (hsv.hue_min + hsv.hue_max) / 2;
  if (hsv.hue_min > hsv.hue_max) hue = ((hsv.hue_min + hsv.hue_max + 180) / 2) % 180;
  const int sat = std::min(255, std::max(hsv.sat_min + 60, (hsv.sat_min + hsv.sat_max) / 2));
  const int val = std::min(255, std::max(hsv.val_min + 120, 200));
  cv::Mat one(1, 1, CV_8UC3, cv::Scalar(hue, sat, val)), colour;
  cv::cvtColor(one, colour, cv::COLOR_HSV2BGR);
  const int tag_side = pixels(shelf.tag_size_m);
  cv::Mat tag(tag_side, tag_side, CV_8UC3, cv::Scalar(colour.at<cv::Vec3b>(0, 0)));
  const fs::path tag_file = fs::path(o.print_dir) / "tag.png";
  if (!cv::imwrite(tag_file.string(),
                   page(tag, "tag " + std::to_string(static_cast<int>(std::lround(shelf.tag_size_m * 1000))) + " mm"))) {
    throw UsageError("cannot write " + tag_file.string());
  }
  std::cout << "tello_pilot: wrote markers " << o.marker_first << ".." << o.marker_last << " and tag.png to "
            << o.print_dir << " (print at 300 dpi, 100% scale; measure the printed sizes)" << std::endl;
  return 0;
}

}  // namespace shelfcross::tello::pilot
