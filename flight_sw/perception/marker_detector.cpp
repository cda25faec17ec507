#include "flight_sw/perception/marker_detector.hpp"

#include <algorithm>
#include <cmath>

#include <opencv2/aruco.hpp>
#include <opencv2/imgproc.hpp>

#include "shelfcross/aruco_dictionaries.hpp"

namespace shelfcross::flight_sw {

std::optional<int> aruco_dictionary_id(const std::string& name) {
  const ArucoDictionaryEntry* e = find_aruco_dictionary(name);
  if (!e) return std::nullopt;
  return e->id;
}


MarkerDetector::MarkerDetector(const std::string& dictionary_name) {
  const auto id = aruco_dictionary_id(dictionary_name);
  if (!id) throw std::invalid_argument("unknown ArUco dictionary '" + dictionary_name + "'");
  dictionary_ = cv::aruco::getPredefinedDictionary(*id);
  parameters_ = cv::aruco::DetectorParameters::create();
  parameters_->cornerRefinementMethod = cv::aruco::CORNER_REFINE_SUBPIX;
  fast_parameters_ = cv::aruco::DetectorParameters::create();
  fast_parameters_->cornerRefinementMethod = cv::aruco::CORNER_REFINE_NONE;
}

void MarkerDetector::collect(double scale, cv::Point2d offset, double grow_px, std::vector<MarkerSighting>& out) {
  // Pixel u of an image decimated by `scale` (block average) covers full-resolution pixels
  // scale u .. scale u + scale - 1: its centre is scale u + (scale - 1) / 2.
  const double shift = 0.5 * (scale - 1.0);
  for (size_t i = 0; i < ids_.size(); ++i) {
    MarkerSighting m;
    m.id = ids_[i];
    std::array<cv::Point2d, 4> q;
    cv::Point2d c(0, 0);
    for (size_t k = 0; k < 4; ++k) {
      q[k] = cv::Point2d(scale * corners_[i][k].x + shift + offset.x, scale * corners_[i][k].y + shift + offset.y);
      c += 0.25 * q[k];
    }
    // Unrefined corners lie on the centres of the border's outermost dark pixels, half a pixel
    // inside its edge: every side moved out by grow_px (miter: corner + d (n1 + n2) / (1 + n1.n2)
    // with n1, n2 the outward unit normals of its two sides).
    c = cv::Point2d(0, 0);
    for (size_t k = 0; k < 4; ++k) {
      cv::Point2d p = q[k];
      if (grow_px > 0.0) {
        const auto outward = [&](const cv::Point2d& a, const cv::Point2d& b) {
          const cv::Point2d e = b - a;
          cv::Point2d n(-e.y, e.x);
          n *= 1.0 / std::max(1e-9, cv::norm(n));
          const cv::Point2d centre = 0.25 * (q[0] + q[1] + q[2] + q[3]);
          return n.dot(0.5 * (a + b) - centre) >= 0.0 ? n : -n;
        };
        const cv::Point2d n1 = outward(q[(k + 3) % 4], q[k]), n2 = outward(q[k], q[(k + 1) % 4]);
        p += grow_px * (n1 + n2) * (1.0 / std::max(0.1, 1.0 + n1.dot(n2)));
      }
      m.corners_px[k] = cv::Point2f(p);
      c += cv::Point2d(m.corners_px[k]);
    }
    m.centre_px = c * 0.25;
    m.area_px = std::abs(cv::contourArea(m.corners_px));
    out.push_back(m);
  }
}

void MarkerDetector::detect(const cv::Mat& bgr, std::vector<MarkerSighting>& out) {
  cv::cvtColor(bgr, gray_, cv::COLOR_BGR2GRAY);
  corners_.clear();
  ids_.clear();
  cv::aruco::detectMarkers(gray_, dictionary_, corners_, ids_, parameters_, rejected_);
  collect(1.0, {0.0, 0.0}, 0.0, out);  // sub-pixel refined
}

void MarkerDetector::detect_in(const cv::Mat& bgr, cv::Rect region, double expected_side_px,
                               double min_area_ratio, std::vector<MarkerSighting>& out) {
  region &= cv::Rect(0, 0, bgr.cols, bgr.rows);
  if (region.width < 8 || region.height < 8 || !(expected_side_px > 0.0)) return;
  cv::cvtColor(bgr(region), gray_, cv::COLOR_BGR2GRAY);
  const double side = expected_side_px;
  const double longest = std::max(gray_.cols, gray_.rows);
  cv::aruco::DetectorParameters& p = *fast_parameters_;
  // A quadrilateral of perimeter P has at most the area (P/4)^2 (the square's), so one with
  // P < 4 sqrt(marker_area_ratio) side can never pass eq. 1 on marker area (area >= ratio
  // side^2): such candidates (the colour tags, markers of shelves behind) are not even decoded.
  p.minMarkerPerimeterRate = std::min(4.0, 0.98 * std::sqrt(min_area_ratio) * 4.0 * side / longest);
  p.maxMarkerPerimeterRate = std::min(4.0, 2.5 * 4.0 * side / longest);
  // One threshold window about half a marker wide (the defaults try 3, 13 and 23 px): a
  // marker's black border and white bits both fall inside it.
  const int window = std::clamp(2 * static_cast<int>(std::lround(0.25 * side)) + 1, 5, 31);
  p.adaptiveThreshWinSizeMin = window;
  p.adaptiveThreshWinSizeMax = window;
  p.adaptiveThreshWinSizeStep = 10;
  corners_.clear();
  ids_.clear();
  cv::aruco::detectMarkers(gray_, dictionary_, corners_, ids_, fast_parameters_, rejected_);
  collect(1.0, cv::Point2d(region.x, region.y), 0.5, out);
}

}  // namespace shelfcross::flight_sw
